"""Direct illumination: the `Direct` integrator (thesis ch. 8)."""

from typing import ClassVar

import equinox as eqx

from ._base import AbstractIntegrator, scene_flag
from ._path import DIMENSIONS_PER_BOUNCE, path_radiance, sample_dimensions

_SEGMENTS = 2  # the camera segment and one scattering vertex's light and BSDF samples


class Direct(AbstractIntegrator):
    """Direct illumination: emission seen from the camera plus, at the first hit, one light
    sample and one BSDF sample combined by multiple importance sampling (power heuristic).

    It is the path estimator with two segments and no Russian roulette (`path_radiance` with
    `max_depth=2`), which is Mitsuba's `direct` integrator with one emitter and one BSDF
    sample per vertex.

    **Arguments:**

    - `hide_emitters`: emitters seen directly from the camera are black (Mitsuba's
        `hide_emitters`; default False).

    !!! note "Thesis"
        Chapter 8 (direct lighting; title only in the text).

    ??? cite "References"
        `Veach1997` §9.2 (MIS); `Pharr2023` §13.3; `Jakob2022` (`direct`).
    """

    NAME: ClassVar[str] = "direct"
    PARAMETERS: ClassVar[frozenset[str]] = frozenset(
        {"emitter_samples", "bsdf_samples", "shading_samples", "hide_emitters"}
    )

    hide_emitters: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        if not isinstance(self.hide_emitters, bool):
            raise TypeError(f"`hide_emitters` must be a bool, got {self.hide_emitters!r}.")

    @classmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "Direct":
        """Mitsuba's `direct` with its defaults (one emitter and one BSDF sample) and
        `hide_emitters`."""
        for name, default in (("emitter_samples", 1), ("bsdf_samples", 1)):
            if params.get(name, default) != default:
                raise ValueError(
                    f"{where}: the direct integrator takes {name} = {default}, got "
                    f"{params[name]!r}."
                )
        return cls(hide_emitters=scene_flag(params, "hide_emitters", False, where))

    def sample_dimensions(self) -> int:
        return sample_dimensions(_SEGMENTS)

    def radiance(self, scene, origins, directions, wavelength_nm, variates, active):
        def u(b, paths):
            return variates(DIMENSIONS_PER_BOUNCE * b, DIMENSIONS_PER_BOUNCE, paths)

        return path_radiance(
            scene,
            origins,
            directions,
            wavelength_nm,
            u,
            max_depth=_SEGMENTS,
            rr_depth=_SEGMENTS,
            active=active,
            hide_emitters=self.hide_emitters,
        )
