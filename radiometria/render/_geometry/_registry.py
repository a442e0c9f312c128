"""The registry of traversal back ends, and the choice of one for a query (thesis ch. 8).

`TRAVERSAL_BACKENDS` lists the back ends by name, in order of preference; the `backend`
argument of the ray queries is a name from it, `"auto"`, or a back-end object. A new back end
is one file with a subclass of `AbstractTraversalBackend` and one line here.
"""

from collections.abc import Mapping
from types import MappingProxyType

import jax

from ..._checks import check_choice
from ._backends import AbstractTraversalBackend
from ._native import NativeCPUTraversal
from ._traversal import JaxTraversal

__all__ = ["TRAVERSAL_BACKENDS", "resolve_backend"]

TRAVERSAL_BACKENDS: Mapping[str, AbstractTraversalBackend] = MappingProxyType(
    {
        "native": NativeCPUTraversal(),
        "jax": JaxTraversal(),
    }
)
"""The traversal back ends by name, in order of preference for `backend="auto"`."""


def check_backend(backend: str | AbstractTraversalBackend) -> None:
    """Static check: `backend` is `"auto"`, a name in `TRAVERSAL_BACKENDS`, or a back end."""
    if not isinstance(backend, AbstractTraversalBackend):
        check_choice(backend, "backend", ("auto", *TRAVERSAL_BACKENDS))


def resolve_backend(backend: str | AbstractTraversalBackend) -> AbstractTraversalBackend:
    """The back end that runs a query (called at trace time, outside the compiled program).

    **Arguments:**

    - `backend`: `"auto"`, a name in `TRAVERSAL_BACKENDS` (`"native"`, `"jax"`), or an
        `AbstractTraversalBackend` object.

    **Returns:**

    For `"auto"`: the first registered back end whose `platforms` include the default JAX
    platform (`jax.default_backend()`, or `"*"` for every platform) and that is available.
    For a name or an object: that back end.

    **Raises:**

    `ValueError` for an unknown name, listing the valid ones; `RuntimeError` when the back
    end asked for by name or object is not available, with the reason.

    !!! note "Thesis"
        Ch. 8 (ray casting).
    """
    check_backend(backend)
    if backend == "auto":
        platform = jax.default_backend()
        for candidate in TRAVERSAL_BACKENDS.values():
            if ("*" in candidate.platforms or platform in candidate.platforms) and (
                candidate.available()[0]
            ):
                return candidate
        raise RuntimeError(f"no traversal back end is available on platform {platform!r}.")
    if isinstance(backend, str):
        name, backend = backend, TRAVERSAL_BACKENDS[backend]
    else:
        name = type(backend).__name__
    ok, reason = backend.available()
    if not ok:
        raise RuntimeError(f"the {name} BVH traversal is unavailable: {reason}.")
    return backend
