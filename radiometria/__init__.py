"""radiometria: radiometry, photometry, colorimetry and Monte Carlo integration in JAX.

Implements the thesis *Metodi di Monte Carlo Applicati Alla Computer Grafica*: chapter 1
(radiometry, `radiometria.radiometry`), chapter 2 (photometry, colorimetry, RGB-to-spectrum
upsampling, camera: `photometry`, `colorimetry`, `upsampling`, `camera`), chapter 3 (surfaces,
`scattering`), chapter 4 (participating media, `media`: interfaces), chapters 5-7
(`montecarlo`) and chapters 8-9 (`render`).

```python
import radiometria as rm
rm.radiometry.planck(550.0, 5000.0)  # W sr^-1 m^-2 nm^-1
```
"""

import importlib
from typing import TYPE_CHECKING

# The subpackages load on first use (PEP 562), so that `radiometria render --help` or a script
# that needs only `radiometry` does not pay for importing every floor (about a second).
_SUBPACKAGES = (
    "camera",
    "colorimetry",
    "constants",
    "media",
    "montecarlo",
    "photometry",
    "radiometry",
    "render",
    "scattering",
    "upsampling",
)

if TYPE_CHECKING:
    from . import (
        camera as camera,
        colorimetry as colorimetry,
        constants as constants,
        media as media,
        montecarlo as montecarlo,
        photometry as photometry,
        radiometry as radiometry,
        render as render,
        scattering as scattering,
        upsampling as upsampling,
    )

__all__ = [*_SUBPACKAGES, "__version__"]


def __getattr__(name: str):
    if name == "__version__":  # importlib.metadata costs ~50 ms: `radiometria --help` skips it
        version = importlib.import_module("importlib.metadata").version("radiometria")
        globals()[name] = version
        return version
    if name in _SUBPACKAGES:
        module = importlib.import_module(f"{__name__}.{name}")
        globals()[name] = module
        return module
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_SUBPACKAGES) | {"__version__"})
