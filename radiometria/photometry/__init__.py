"""Photometry (thesis section 2.1): luminous efficiency functions and luminous quantities.

- The CIE spectral luminous efficiency functions, packaged with provenance: photopic
  V(lambda) (CIE 1924) and scotopic V'(lambda) (CIE 1951), `luminous_efficiency_function`
  and `luminous_efficiency_table`.
- Photometric quantities from sampled spectral radiometric ones (eq. 2.1-2.5):
  `luminous_quantity` and its named forms `luminous_energy`, `luminous_flux`, `illuminance`,
  `luminous_exitance`, `luminous_intensity`, `luminance`; and `luminous_efficacy` /
  `luminous_efficiency` of a spectrum.

Maximum luminous efficacies: `constants.K_M` (photopic) and `constants.K_M_SCOTOPIC`.
"""

from ._efficiency import (
    luminous_efficiency_function as luminous_efficiency_function,
    luminous_efficiency_table as luminous_efficiency_table,
)
from ._quantities import (
    illuminance as illuminance,
    luminance as luminance,
    luminous_efficacy as luminous_efficacy,
    luminous_efficiency as luminous_efficiency,
    luminous_energy as luminous_energy,
    luminous_exitance as luminous_exitance,
    luminous_flux as luminous_flux,
    luminous_intensity as luminous_intensity,
    luminous_quantity as luminous_quantity,
)
