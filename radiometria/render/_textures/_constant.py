"""A texture that is constant over the surface: one spectrum per row."""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from ..._checks import device_array
from .._spectral import SpectralValue, SpectrumTable, tabulate_spectrum, wavelength_grid_nm
from ._base import AbstractTexture


class ConstantTexture(AbstractTexture):
    """One spectrum per row, the same everywhere on the surface (Mitsuba's spectral values).

    **Arguments:**

    - `table`: a `SpectrumTable` with one row per material, on the renderer's 1 nm grid
        [the parameter's unit].

    Build one from scene values with `ConstantTexture.from_values(values, rgb_spectrum)`.

    ??? cite "References"
        `Pharr2023` §10.4.1 (`SpectrumConstantTexture`).
    """

    table: SpectrumTable

    @classmethod
    def from_values(
        cls, values: "list[SpectralValue]", rgb_spectrum: type, dtype=jnp.float32
    ) -> "ConstantTexture":
        """Tabulate scene values (`tabulate_spectrum`), one row each.

        **Arguments:**

        - `values`: `LinearRGB` triples, `AbstractSpectrum`s or numbers.
        - `rgb_spectrum`: how an RGB triple becomes a spectrum (`tabulate_spectrum`).
        - `dtype`: the table's dtype (float32 for rendering).
        """
        rows = [tabulate_spectrum(v, rgb_spectrum) for v in values]
        if not rows:
            return cls(SpectrumTable(jnp.zeros((0, wavelength_grid_nm().shape[0]), dtype)))
        return cls(SpectrumTable(device_array(np.stack(rows), dtype)))

    @property
    def n_rows(self) -> int:
        return int(self.table.values.shape[0])

    def __call__(
        self,
        row: Int[Array, " n"],
        wavelength_nm: Float[Array, "n k"],
        uv: Float[Array, "n _"] | None = None,
    ) -> Float[Array, "n k"]:
        return self.table(row, wavelength_nm)
