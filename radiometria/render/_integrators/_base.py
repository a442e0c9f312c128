"""The integrator interface: spectral radiance along a batch of camera rays."""

import abc
from collections.abc import Callable
from typing import ClassVar

import equinox as eqx
from jaxtyping import Array, Bool, Float, Int

__all__ = [
    "DEFAULT_UNBOUNDED_DEPTH",
    "AbstractIntegrator",
    "VariateFn",
    "check_path_fields",
    "scene_flag",
    "scene_max_depth",
]

DEFAULT_UNBOUNDED_DEPTH = 64  # max_depth for scenes that leave it unbounded (Mitsuba's -1)


def scene_max_depth(params: dict) -> int:
    """A scene file's `max_depth` (default 8); -1 or `None` (unbounded) is taken as
    `DEFAULT_UNBOUNDED_DEPTH`. Not checked here: the integrator's `__check_init__` does."""
    depth = params.get("max_depth", 8)
    return DEFAULT_UNBOUNDED_DEPTH if depth is None or depth == -1 else depth


def scene_flag(params: dict, name: str, default: bool, where: str) -> bool:
    """A scene file's boolean parameter `name` (default `default`): anything but a bool is a
    `ValueError` naming `where` (no `bool("false")` coercion)."""
    value = params.get(name, default)
    if not isinstance(value, bool):
        raise ValueError(f"{where}: `{name}` must be a boolean, got {value!r}.")
    return value


def check_path_fields(integrator) -> None:
    """The `__check_init__` of the path-type integrators: `max_depth` and `rr_depth` are ints
    >= 1 (`ValueError`), `hide_emitters` is a bool (`TypeError`)."""
    for name in ("max_depth", "rr_depth"):
        value = getattr(integrator, name)
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"`{name}` must be an int >= 1, got {value!r}.")
    if not isinstance(integrator.hide_emitters, bool):
        raise TypeError(f"`hide_emitters` must be a bool, got {integrator.hide_emitters!r}.")


VariateFn = Callable[[Array, int, Int[Array, " m"]], Float[Array, "m d"]]
"""`variates(first, n_dims, paths)`: uniform variates of dimensions `first .. first + n_dims -
1` of the paths `paths` (int32 indices into the batch; indices past the batch are padding),
`(m, n_dims)` in [0, 1). `first` may be traced, `n_dims` is a static multiple of 4. The
dimensions are counted after the camera's, so an integrator numbers its own from 0."""


class AbstractIntegrator(eqx.Module):
    """A light-transport estimator: spectral radiance along camera rays (thesis ch. 8-9).

    The render driver generates the camera rays and hero wavelengths of a batch of paths and
    calls `radiance`; the integrator draws every further variate from `variates`, so any
    sampler (independent, Owen-scrambled Sobol, ...) serves any integrator. Implementations are
    final `equinox` Modules whose shape-setting settings (`max_depth`) are static fields.

    **Subclasses provide:**

    - `NAME`: the integrator's name in scene files and on the command line (Mitsuba's).
    - `PARAMETERS`: the parameter names a scene file may give it.
    - `from_properties(params, where=...)`: the integrator from a scene file's parameters.
    - `sample_dimensions()`: how many variates one path consumes after the camera's.
    - `radiance(scene, origins, directions, wavelength_nm, variates, active)`.

    !!! note "Thesis"
        Chapters 8-9 (light transport; titles only in the text), chapters 5-7 (the samplers
        and estimators).

    ??? cite "References"
        `Veach1997`; `Pharr2023` ch. 13; `Jakob2022` (Mitsuba 3's integrator plugins).
    """

    NAME: ClassVar[str]
    PARAMETERS: ClassVar[frozenset[str]]

    @classmethod
    @abc.abstractmethod
    def from_properties(cls, params: dict, *, where: str = "scene") -> "AbstractIntegrator":
        """The integrator from a scene file's parameters (errors name `where`)."""

    @abc.abstractmethod
    def sample_dimensions(self) -> int:
        """Number of uniform variates one path consumes, camera excluded."""

    @abc.abstractmethod
    def radiance(
        self,
        scene,
        origins: Float[Array, "n 3"],
        directions: Float[Array, "n 3"],
        wavelength_nm: Float[Array, "n k"],
        variates: VariateFn,
        active: Bool[Array, " n"],
    ) -> Float[Array, "n k"]:
        """Radiance estimates `(n, k)` [W m^-2 sr^-1 nm^-1] along the rays of a `RenderScene`
        (unit `directions`, [scene units]) at their wavelengths [nm]; paths where `active` is
        False are not traced and return 0."""
