"""The materials of a scene: one plugin per kind present, and the BxDF of each path's material."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Int

from ..._checks import device_array
from ..._math import compact_indices
from ...scattering import AbstractBxDF, BSDFSample
from ._base import AbstractMaterial, concatenate

__all__ = ["MaterialSet"]


class MaterialSet(eqx.Module):
    """A scene's `m` materials, grouped by kind into one plugin each.

    Build it with `MaterialSet.from_materials([...])` from material plugins (each of one or
    more rows), in the order of the scene's material indices.

    **Fields:**

    - `plugins`: one `AbstractMaterial` per kind present, holding that kind's materials.
    - `plugin_of`, `row_of`: `(m,)` int32, the plugin and the row of each material.
    - `two_sided`: `(m,)` bool, materials that scatter on both sides.
    - `transmissive`: `(m,)` bool, materials that transmit (both sides bound a medium).
    - `identity_rows`: static, one plugin whose rows are the materials in order.
    - `tangent_frame`: static, some material is anisotropic (`AbstractMaterial.tangent_frame`):
        the shading frames then follow dp/du.

    At a hit, `bxdf(material, wavelength_nm, uv)` is the plugin's own BxDF when the scene has one
    kind; otherwise a mixture whose queries evaluate each kind on the paths that use it (in
    blocks, `_on_paths`) and give each path its own kind's result.

    !!! note "Thesis"
        Chapter 3 (BSDFs, eq. 3.4).
    """

    plugins: tuple[AbstractMaterial, ...]
    plugin_of: Int[Array, " m"]
    row_of: Int[Array, " m"]
    two_sided: Bool[Array, " m"]
    transmissive: Bool[Array, " m"]
    identity_rows: bool = eqx.field(static=True)
    tangent_frame: bool = eqx.field(static=True, default=False)

    @classmethod
    def from_materials(cls, materials: "list[AbstractMaterial]") -> "MaterialSet":
        """Group material plugins by kind (NumPy work, outside `jit`)."""
        if not materials:
            raise ValueError("a scene needs at least one material.")
        kinds: list[type] = []
        groups: dict[type, list[AbstractMaterial]] = {}
        plugin_of, row_of, transmissive = [], [], []
        for m in materials:
            if not isinstance(m, AbstractMaterial):
                raise TypeError(f"materials must be AbstractMaterial plugins, got {type(m)}.")
            kind = type(m)
            if kind not in groups:
                kinds.append(kind)
                groups[kind] = []
            first = sum(g.n_rows for g in groups[kind])
            groups[kind].append(m)
            plugin_of += [kinds.index(kind)] * m.n_rows
            row_of += list(range(first, first + m.n_rows))
            transmissive += np.asarray(m.transmissive_rows, bool).tolist()
        plugins = tuple(concatenate(groups[k]) for k in kinds)
        two_sided = device_array(np.concatenate([np.asarray(m.two_sided, bool) for m in materials]))
        return cls(
            plugins=plugins,
            plugin_of=device_array(plugin_of, jnp.int32),
            row_of=device_array(row_of, jnp.int32),
            two_sided=two_sided,
            transmissive=device_array(transmissive, bool),
            identity_rows=len(plugins) == 1 and bool(np.all(np.diff(row_of) == 1)),
            tangent_frame=any(p.tangent_frame for p in plugins),
        )

    @classmethod
    def join(cls, sets: "list[MaterialSet]") -> "tuple[MaterialSet, list[int]]":
        """The materials of several sets as one set, in order, and the index of each set's
        first material in it (NumPy work, outside `jit`): plugins of one kind are
        concatenated, and each material keeps its plugin's row, shifted past the rows of
        that kind in the sets before it."""
        kinds: list[type] = []
        groups: dict[type, list[AbstractMaterial]] = {}
        plugin_of, row_of, offsets, first = [], [], [], 0
        for s in sets:
            offsets.append(first)
            first += s.n_materials
            shift = {}
            for p in s.plugins:
                kind = type(p)
                if kind not in groups:
                    kinds.append(kind)
                    groups[kind] = []
                shift[kind] = sum(g.n_rows for g in groups[kind])
                groups[kind].append(p)
            for j, r in zip(np.asarray(s.plugin_of), np.asarray(s.row_of), strict=True):
                kind = type(s.plugins[int(j)])
                plugin_of.append(kinds.index(kind))
                row_of.append(int(r) + shift[kind])
        plugins = tuple(concatenate(groups[k]) for k in kinds)
        return cls(
            plugins=plugins,
            plugin_of=device_array(plugin_of, jnp.int32),
            row_of=device_array(row_of, jnp.int32),
            two_sided=jnp.concatenate([s.two_sided for s in sets]),
            transmissive=jnp.concatenate([s.transmissive for s in sets]),
            identity_rows=len(kinds) == 1
            and row_of[:1] == [0]
            and bool(np.all(np.diff(row_of) == 1)),
            tangent_frame=any(p.tangent_frame for p in plugins),
        ), offsets

    @property
    def n_materials(self) -> int:
        """Number of materials `m`."""
        return int(self.plugin_of.shape[0])

    @property
    def needs_geometry(self) -> bool:
        """Whether some material needs the hits' `HitGeometry` (a normal or bump map; static)."""
        return any(p.needs_geometry for p in self.plugins)

    def bxdf(
        self, material: Int[Array, " n"], wavelength_nm, uv=None, geometry=None
    ) -> AbstractBxDF:
        """The BxDF of each path's material at its wavelengths (`(n,)`, `(n, k)` [nm]) and
        surface coordinates `uv` (`(n, 2)` [1], or `None`: textures are looked up at (0, 0)),
        which plugins with textured parameters (`USES_UV`) receive, and the hits'
        `HitGeometry` (or `None`), which normal and bump maps need (`USES_GEOMETRY`).

        With one kind this is the plugin's own BxDF. With several it is a `_Mixture` that
        builds each kind's BxDF (texture lookups, spectral upsampling, table rows) only for
        the paths of that kind, inside each query."""
        rows = material if self.identity_rows else self.row_of[material]
        if len(self.plugins) == 1:
            return _build(self.plugins[0], rows, wavelength_nm, uv, geometry)
        return _Mixture(self.plugin_of[material], rows, wavelength_nm, uv, geometry, self.plugins)


def _build(plugin: AbstractMaterial, rows, wavelength_nm, uv, geometry) -> AbstractBxDF:
    """`plugin`'s BxDF of the rows `rows`, given what its kind uses (uv, geometry)."""
    if plugin.USES_GEOMETRY:
        return plugin.bxdf(rows, wavelength_nm, uv, geometry)
    if plugin.USES_UV:
        return plugin.bxdf(rows, wavelength_nm, uv)
    return plugin.bxdf(rows, wavelength_nm)


_BLOCKS = 4  # each kind is evaluated in blocks of n / _BLOCKS paths, only as many as it needs
_MIN_SPLIT = 64  # batches smaller than this evaluate every kind on every path


def _on_paths(fn, args, mask):
    """`fn(*args)` for the paths of `mask` `(n,)` (elsewhere the result is 0), where every
    array leaf of `args` has the leading path axis `n`: the paths of `mask` are gathered
    first and evaluated in blocks of `n / _BLOCKS`, only as many blocks as they fill
    (`lax.cond` skips the others; the loop's static trip count keeps it differentiable), so
    a kind few paths use (a metal ball on a diffuse floor) costs in proportion to those
    paths."""
    n = mask.shape[0]
    if n < _MIN_SPLIT:
        return fn(*args)
    m = -(-n // _BLOCKS)
    order = compact_indices(mask, m * _BLOCKS, n)
    count = jnp.sum(mask, dtype=jnp.int32)

    def block(j):
        idx = jax.lax.dynamic_slice_in_dim(order, j * m, m)

        def take(x):
            return jnp.take(x, idx, axis=0, mode="clip")

        return idx, fn(*jax.tree.map(take, args))

    _, shapes = jax.eval_shape(block, 0)
    init = jax.tree.map(lambda sd: jnp.zeros((n,) + sd.shape[1:], sd.dtype), shapes)

    def body(j, acc):
        def run(acc):
            idx, out = block(j)  # padding indices are n: dropped
            return jax.tree.map(lambda a, o: a.at[idx].set(o, mode="drop"), acc, out)

        return jax.lax.cond(j * m < count, run, lambda acc: acc, acc)

    return jax.lax.fori_loop(0, _BLOCKS, body, init)


def _pick(plugin, values):
    """Per path, the value of its kind `plugin` `(n,)` among `values` (one per kind)."""
    out = values[0]
    for i, v in enumerate(values[1:], start=1):
        mask = (plugin == i).reshape(plugin.shape + (1,) * (v.ndim - 1))
        out = jnp.where(mask, v, out)
    return out


class _Mixture(AbstractBxDF):
    """The BxDFs of several material kinds, one chosen per path by `plugin`.

    Each query builds and evaluates each kind's BxDF on the paths that use it (`_on_paths`):
    with a rough conductor ball on a diffuse floor under an environment map, every path once
    evaluated the microfacet model, which took 60 % of the render. Building a kind's BxDF
    (texture lookups, spectral upsampling, table rows) happens inside those blocks too, so a
    kind costs nothing on the paths of the others. `f_pdf_sample` answers a path vertex's
    three queries with one pass per kind.
    """

    plugin: Array  # (n,) index into `kinds`
    rows: Array  # (n,) each path's row in its kind's table
    wavelength_nm: Array  # (n, k)
    uv: Array | None
    geometry: object  # HitGeometry | None
    kinds: tuple  # the MaterialSet's plugins

    def _each(self, query, *args):
        """`query(bxdf, *args)` of each kind on its paths."""
        out = []
        for i, kind in enumerate(self.kinds):

            def fn(rows, wl, uv, geometry, *a, kind=kind):
                return query(_build(kind, rows, wl, uv, geometry), *a)

            per_path = (self.rows, self.wavelength_nm, self.uv, self.geometry, *args)
            out.append(_on_paths(fn, per_path, self.plugin == i))
        return out

    def _pick_sample(self, samples) -> BSDFSample:
        return BSDFSample(
            **{
                name: _pick(self.plugin, [getattr(s, name) for s in samples])
                for name in ("f", "wi", "pdf", "is_delta", "is_transmission", "eta",
                             "terminate_secondary")
            }
        )  # fmt: skip

    def f(self, wo, wi, *, mode: str = "radiance"):
        return _pick(self.plugin, self._each(lambda b, o, i: b.f(o, i, mode=mode), wo, wi))

    def pdf(self, wo, wi):
        return _pick(self.plugin, self._each(lambda b, o, i: b.pdf(o, i), wo, wi))

    def sample_f(self, wo, u_lobe, u2, *, mode: str = "radiance") -> BSDFSample:
        samples = self._each(lambda b, o, u, v: b.sample_f(o, u, v, mode=mode), wo, u_lobe, u2)
        return self._pick_sample(samples)

    def f_pdf_sample(self, wo, wi, u_lobe, u2, *, mode: str = "radiance"):
        parts = self._each(
            lambda b, o, i, u, v: b.f_pdf_sample(o, i, u, v, mode=mode), wo, wi, u_lobe, u2
        )
        return (
            _pick(self.plugin, [p[0] for p in parts]),
            _pick(self.plugin, [p[1] for p in parts]),
            self._pick_sample([p[2] for p in parts]),
        )
