"""The medium-plugin interface: media of one kind as rows, and the medium of each path."""

import abc
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, Float, Int

from ...media import AbstractMedium

__all__ = ["AbstractMediumPlugin"]


class AbstractMediumPlugin(eqx.Module):
    """A kind of participating medium (Mitsuba's `<medium type=...>`) with `m` media as rows.

    **Subclasses provide:**

    - `NAME`: the plugin's name in scene files (`"homogeneous"`, `"heterogeneous"`).
    - `n_rows`: the number of media held.
    - `medium(row, wavelength_nm)`: a `radiometria.media.AbstractMedium` whose parameters are
        those of row `row[i]` at the wavelengths `wavelength_nm[i]` [nm] of path `i`, so that
        its `sample_free_flight`, `transmittance` and `phase` serve a batch of paths in
        different media of this kind at once.
    - `CONCATENABLE`: whether plugins of this kind can be merged into one (rows of equal
        shape; a grid medium's grids generally differ, so each keeps its own plugin).

    !!! note "Thesis"
        Chapter 4 (energy transport in a medium) and chapter 9 (volume rendering); titles only
        in the text.

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's medium plugins); `Pharr2023` §11.4.
    """

    NAME: ClassVar[str]
    CONCATENABLE: ClassVar[bool] = True

    @property
    @abc.abstractmethod
    def n_rows(self) -> int:
        """Number of media held."""

    @abc.abstractmethod
    def medium(self, row: Int[Array, " n"], wavelength_nm: Float[Array, "n k"]) -> AbstractMedium:
        """The medium of row `row[i]` for path `i`, at its wavelengths [nm]."""
