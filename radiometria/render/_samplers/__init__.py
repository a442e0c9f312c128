"""Pixel samplers of the render driver (thesis ch. 5-7), one per file.

Each subclasses `AbstractSampler` (`_base.py`); the names the command line uses are in
`radiometria.render._registry.SAMPLERS`.
"""

from ._base import AbstractSampler as AbstractSampler, sampler_seed as sampler_seed
from ._independent import Independent as Independent
from ._owen_sobol import OwenSobol as OwenSobol
