"""The segment loop shared by unidirectional integrators: a `lax.scan` over path segments,
each tracing only the live paths, compacted into chunks of static size.

`run_segments(state, segment, ...)` runs `segment(state_chunk, wavelength_chunk, paths, b)`
for `b = 0 .. n_segments - 1`, where `state` is a pytree of arrays with a leading path axis
and a boolean field `alive`. With `compact=True` each segment gathers the indices of the live paths
(`_math.compact_indices`: `jnp.nonzero` with a static size) and traces them in chunks of `chunk`
paths by a `lax.fori_loop` whose trip count is the number of live chunks, so terminated paths cost
nothing and every shape stays static. With `compact=False` every path is traced in every
segment and the results of terminated ones are discarded: a loop of static length, which
reverse-mode differentiation (`jax.grad`) can pass through. This is the loop of `path_radiance`
(`_path.py`, which keeps its own copy), as a function of the segment.
"""

import jax
import jax.numpy as jnp

from ..._math import compact_indices

__all__ = ["run_segments"]


def run_segments(state, segment, wavelength_nm, *, n_segments: int, chunk: int, compact: bool):
    """Run `segment` for `n_segments` segments over the paths of `state` (module docstring).

    **Arguments:**

    - `state`: a pytree (an `equinox.Module`) of arrays with a leading axis of `n` paths and a
        boolean `(n,)` field `alive`.
    - `segment`: `segment(state, wavelength_nm, paths, b) -> state` for a subset of the paths
        (`paths`: their int32 indices into the batch, `>= n` for padding), `b` the segment.
    - `wavelength_nm`: `(n, k)` wavelengths of the paths. [nm]
    - `n_segments`, `chunk`: static ints; `compact`: static bool.

    **Returns:**

    The state after the last segment.
    """
    n = wavelength_nm.shape[0]

    def all_paths(state, b):
        alive = state.alive
        paths = jnp.arange(n, dtype=jnp.int32)
        new = segment(state, wavelength_nm, paths, b)

        def keep(x, old):
            return jnp.where(alive.reshape(alive.shape + (1,) * (x.ndim - 1)), x, old)

        return jax.tree.map(keep, new, state), None

    n_pad = -(-n // chunk) * chunk

    def live_paths(state, b):
        live = compact_indices(state.alive, n_pad, n)
        n_chunks = (jnp.sum(state.alive, dtype=jnp.int32) + chunk - 1) // chunk

        def one_chunk(i, state):
            sel = jax.lax.dynamic_slice_in_dim(live, i * chunk, chunk)

            def take(x):
                return jnp.take(x, sel, axis=0, mode="clip")

            new = segment(jax.tree.map(take, state), take(wavelength_nm), sel, b)
            return jax.tree.map(lambda a, x: a.at[sel].set(x, mode="drop"), state, new)

        return jax.lax.fori_loop(0, n_chunks, one_chunk, state), None

    segments = jnp.arange(n_segments, dtype=jnp.int32)
    state, _ = jax.lax.scan(live_paths if compact else all_paths, state, segments)
    return state
