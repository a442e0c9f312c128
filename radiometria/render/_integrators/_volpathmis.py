"""`VolPathMIS`: volumetric path tracing with path-level spectral MIS (Mitsuba 3's
`volpathmis`), the estimator of `volpath_radiance` with `spectral_mis="path"`."""

from typing import ClassVar

import equinox as eqx

from ._base import AbstractIntegrator, check_path_fields, scene_flag, scene_max_depth
from ._volpath import volpath_radiance, volpath_sample_dimensions


class VolPathMIS(AbstractIntegrator):
    r"""Volumetric path tracing with spectral MIS over whole paths (Mitsuba 3's `volpathmis`).

    The same light transport as `VolPath` (next-event estimation through media, MIS against
    BSDF and phase sampling, Russian roulette; the same variates): only the weights of free
    flights in homogeneous media differ. A path samples its free flights at one of its
    wavelengths, chosen once, and each contribution is weighted by the balance heuristic over
    the path's wavelengths as sampling techniques, $F_j / \frac1k\sum_i P_i$ with $P_i$ the
    product of the path's free-flight densities at wavelength $i$ (`volpath_radiance`'s
    module docstring, "Spectral MIS"). Its expectation is `VolPath`'s; its variance is lower in
    chromatic media with several scattering events, where `VolPath`'s per-flight weights
    multiply. Grid media use `VolPath`'s weighted delta tracking in both.

    **Arguments:**

    - `max_depth`: largest number of path segments (Mitsuba's meaning, as `VolPath`), a
        static int >= 1 (default 8).
    - `rr_depth`: segments after which Russian roulette starts (default 5).
    - `hide_emitters`: directly visible emitters are black (default False).
    - `use_spectral_mis`: False samples free flights at the path's wavelength and weights
        the others by the ratio $f_j / p_c$ (no MIS: Mitsuba's `use_spectral_mis=false`, and
        its spectral `volpath`) (default True).

    !!! note "Thesis"
        Chapter 9 (volume rendering; title only in the text).

    ??? cite "References"
        `Miller2019` (spectral MIS in the null-scattering path integral); `Wilkie2014` (hero
        wavelengths); `Jakob2022` (`volpathmis`); `Pharr2023` §14.1.
    """

    NAME: ClassVar[str] = "volpathmis"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"max_depth", "rr_depth", "hide_emitters", "use_spectral_mis"}
    )
    max_depth: int = eqx.field(static=True, default=8)
    rr_depth: int = eqx.field(static=True, default=5)
    hide_emitters: bool = eqx.field(static=True, default=False)
    use_spectral_mis: bool = eqx.field(static=True, default=True)

    def __check_init__(self):
        check_path_fields(self)
        if not isinstance(self.use_spectral_mis, bool):
            raise TypeError(f"`use_spectral_mis` must be a bool, got {self.use_spectral_mis!r}.")

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "VolPathMIS":
        """From a scene file's `max_depth` (default 8; -1 = unbounded, taken as
        `DEFAULT_UNBOUNDED_DEPTH`), `rr_depth` (default 5), `hide_emitters` and
        `use_spectral_mis` (default True)."""
        return cls(
            max_depth=scene_max_depth(params),
            rr_depth=params.get("rr_depth", 5),
            hide_emitters=scene_flag(params, "hide_emitters", False, where),
            use_spectral_mis=scene_flag(params, "use_spectral_mis", True, where),
        )

    def sample_dimensions(self) -> int:
        return volpath_sample_dimensions(self.max_depth)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        return volpath_radiance(
            scene,
            origins,
            directions,
            wavelength_nm,
            None,
            max_depth=self.max_depth,
            rr_depth=self.rr_depth,
            hide_emitters=self.hide_emitters,
            active=active,
            variates=variates,
            spectral_mis="path" if self.use_spectral_mis else "none",
        )
