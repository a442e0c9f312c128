"""`RenderScene`: a scene laid out for the integrators (arrays only, one pytree).

A `RenderScene` holds what the bounce loop reads per hit, as structure-of-arrays indexed by
triangle: the triangles themselves (for intersection and light sampling), their unit geometric
normals, material and emitter indices, the spectra of materials and emitters as
`SpectrumTable` rows, and the discrete distribution that next-event estimation uses to pick an
emissive triangle (proportional to area x mean emitted radiance, then uniform in area).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from .._checks import check_choice
from ._bvh import BVH, build_bvh
from ._intersect import (
    Hit,
    intersect_any,
    intersect_brute_force_any,
    intersect_brute_force_closest,
    intersect_closest,
)
from ._materials import MaterialTables, material_bxdf
from ._mesh import TriangleMesh, _areas, _corners
from ._spectral import SpectrumTable

__all__ = ["BRUTE_FORCE_MAX_TRIANGLES", "DEFAULT_UNBOUNDED_DEPTH", "RenderScene", "compile_scene"]

BRUTE_FORCE_MAX_TRIANGLES = 64


class RenderScene(eqx.Module):
    """Triangles, materials and emitters as arrays, ready for `path_radiance`.

    Build one with `RenderScene.from_triangles` (or from a loaded scene with
    `radiometria.render.compile_scene`). All arrays are float32 unless noted; lengths are in
    the scene's unit [scene units], spectra on the 1 nm grid of `wavelength_grid_nm`.

    !!! note "Thesis"
        Chapter 8 (the scene of the light transport equation).

    ??? cite "References"
        `Pharr2023` §12.2 (sampling area lights by power and area).
    """

    p0: Float[Array, "f 3"]  # first vertex of each triangle [scene units]
    e1: Float[Array, "f 3"]  # edge v1 - v0
    e2: Float[Array, "f 3"]  # edge v2 - v0
    normal: Float[Array, "f 3"]  # unit geometric normal, (v1 - v0) x (v2 - v0) direction
    face_material: Int[Array, " f"]  # material index of each triangle
    face_emitter: Int[Array, " f"]  # emitter index of each triangle, -1 when not emissive
    materials: MaterialTables  # one row per material
    radiance: SpectrumTable  # one row per emitter [W m^-2 sr^-1 nm^-1]
    emitter_two_sided: Bool[Array, " e"]  # per emitter: emits on both sides
    light_face: Int[Array, " l"]  # emissive triangles
    light_cdf: Float[Array, " l"]  # cumulative selection probabilities (last = 1)
    light_pdf_area: Float[Array, " f"]  # NEE density per unit area on each triangle [1/area]
    geometry: TriangleMesh | BVH  # what the intersection queries traverse
    ray_epsilon: float = eqx.field(static=True, default=1e-4)

    @classmethod
    def from_triangles(
        cls,
        vertices,
        faces,
        face_material,
        materials: "SpectrumTable | MaterialTables",
        face_emitter,
        radiance: SpectrumTable,
        *,
        two_sided=None,
        emitter_two_sided=None,
        accelerator: str = "auto",
        dtype=jnp.float32,
    ) -> "RenderScene":
        """Lay out a triangle scene (NumPy work, done once, outside `jit`).

        **Arguments:**

        - `vertices`: `(v, 3)` positions [scene units]; `faces`: `(f, 3)` vertex indices, whose
            winding sets the front side (normal `(v1 - v0) x (v2 - v0)`).
        - `face_material`: `(f,)` material (row of `materials`) of each triangle.
        - `materials`: a `MaterialTables` (`MaterialTables.from_materials`), or a
            `SpectrumTable` of diffuse reflectances, one row per (Lambertian) material [1].
        - `face_emitter`: `(f,)` row of `radiance` for each triangle, or -1.
        - `radiance`: emitted radiance spectra, one row per emitter, emitted on the front side.
        - `two_sided`: `(m,)` booleans, Lambertian materials that scatter on both sides
            (default: none; only with a `SpectrumTable` of reflectances).
        - `emitter_two_sided`: `(e,)` booleans, emitters that emit on both sides (default:
            none).
        - `accelerator`: `"bvh"`, `"brute_force"` (test every triangle: fastest for a few
            dozen triangles, such as the Cornell box) or `"auto"` (brute force up to
            `BRUTE_FORCE_MAX_TRIANGLES` triangles).
        """
        check_choice(accelerator, "accelerator", ("auto", "bvh", "brute_force"))
        vertices = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces)
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise ValueError(f"`vertices` must have shape (v, 3), got {vertices.shape}.")
        if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu":
            raise ValueError(f"`faces` must be integer (f, 3), got {faces.dtype} {faces.shape}.")
        if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise ValueError("`faces` index vertices out of range.")
        n_faces = faces.shape[0]
        face_material = np.asarray(face_material, dtype=np.int64).reshape(n_faces)
        face_emitter = np.asarray(face_emitter, dtype=np.int64).reshape(n_faces)
        if isinstance(materials, SpectrumTable):
            n_mat = materials.values.shape[0]
            materials = MaterialTables.lambertian(
                materials,
                np.zeros(n_mat, bool) if two_sided is None else np.asarray(two_sided, bool),
            )
        elif two_sided is not None:
            raise ValueError("`two_sided` goes with a SpectrumTable; MaterialTables carry it.")
        n_mat = materials.kind.shape[0]
        n_em = radiance.values.shape[0]
        if face_material.min(initial=0) < 0 or face_material.max(initial=0) >= n_mat:
            raise ValueError(f"`face_material` must index the {n_mat} materials.")
        if face_emitter.min(initial=-1) < -1 or face_emitter.max(initial=-1) >= n_em:
            raise ValueError(f"`face_emitter` must be -1 or index the {n_em} radiance rows.")
        emitter_two_sided = (
            np.zeros(n_em, bool)
            if emitter_two_sided is None
            else np.asarray(emitter_two_sided, bool)
        ).reshape(n_em)
        if n_em == 0:  # no light: one black row keeps the (clamped) emitter lookups in range
            radiance = SpectrumTable(jnp.zeros((1,) + radiance.values.shape[1:], dtype))
            emitter_two_sided = np.zeros(1, bool)

        v0, v1, v2 = _corners(np, vertices, faces)
        e1, e2 = v1 - v0, v2 - v0
        area = _areas(np, vertices, faces)
        normal = np.cross(e1, e2) / np.where(area > 0, 2.0 * area, 1.0)[:, None]

        # Next-event estimation picks an emissive triangle with probability proportional to
        # area x (mean emitted radiance over the grid), then a point uniformly on it.
        emissive = np.flatnonzero((face_emitter >= 0) & (area > 0))
        if emissive.size:
            mean_le = np.asarray(radiance.values, np.float64).mean(axis=1)
            power = area[emissive] * mean_le[face_emitter[emissive]]
            keep = power > 0
            emissive, power = emissive[keep], power[keep]
        if emissive.size == 0:
            # No light to sample: a dummy entry whose density is 0, so NEE contributes nothing.
            light_face = np.zeros(1, np.int64)
            light_cdf = np.ones(1)
            pdf_area = np.zeros(n_faces)
        else:
            prob = power / power.sum()
            light_face = emissive
            light_cdf = np.cumsum(prob)
            light_cdf[-1] = 1.0
            pdf_area = np.zeros(n_faces)
            pdf_area[emissive] = prob / area[emissive]

        def f(x):
            return jnp.asarray(x, dtype=dtype)

        def i(x):
            return jnp.asarray(x, dtype=jnp.int32)

        if accelerator == "auto":
            accelerator = "brute_force" if n_faces <= BRUTE_FORCE_MAX_TRIANGLES else "bvh"
        if accelerator == "bvh":
            geometry = build_bvh(vertices.astype(np.dtype(dtype)), faces)
        else:
            geometry = TriangleMesh(f(vertices), faces)
        return cls(
            geometry=geometry,
            p0=f(v0),
            e1=f(e1),
            e2=f(e2),
            normal=f(normal),
            face_material=i(face_material),
            face_emitter=i(face_emitter),
            materials=materials,
            radiance=SpectrumTable(f(radiance.values)),
            emitter_two_sided=jnp.asarray(emitter_two_sided),
            light_face=i(light_face),
            light_cdf=f(light_cdf),
            light_pdf_area=f(pdf_area),
        )

    # -- geometry queries ------------------------------------------------------------------
    def intersect_closest(self, origins, directions, tmax) -> Hit:
        """Closest hit of each ray (`prim = -1` for a miss)."""
        if isinstance(self.geometry, BVH):
            return intersect_closest(self.geometry, origins, directions, tmax)
        return intersect_brute_force_closest(self.geometry, origins, directions, tmax)

    def intersect_any(self, origins, directions, tmax):
        """Whether anything lies on each ray within (0, tmax)."""
        if isinstance(self.geometry, BVH):
            return intersect_any(self.geometry, origins, directions, tmax)
        return intersect_brute_force_any(self.geometry, origins, directions, tmax)

    # -- materials -------------------------------------------------------------------------
    def bsdf(self, material, wavelength_nm):
        """The BxDF of each hit's material at its wavelengths (`material_bxdf`)."""
        return material_bxdf(self.materials, material, wavelength_nm)


DEFAULT_UNBOUNDED_DEPTH = 64  # max_depth for scenes that leave it unbounded (Mitsuba's -1)


def _make_filter(film):
    from ..camera import BoxFilter, GaussianFilter, LanczosFilter, MitchellFilter, TentFilter

    p = dict(film.filter_params)
    kind = film.filter
    if kind == "gaussian":
        return GaussianFilter(p.get("stddev", 0.5), p.get("radius"))
    if kind == "box":
        return BoxFilter(p.get("radius", 0.5))
    if kind == "tent":
        return TentFilter(p.get("radius", 1.0))
    if kind in ("mitchell", "catmullrom"):
        b, c = (1.0 / 3.0, 1.0 / 3.0) if kind == "mitchell" else (0.0, 0.5)
        return MitchellFilter(p.get("B", b), p.get("C", c), p.get("radius", 2.0))
    if kind == "lanczos":
        lobes = p.get("lobes", p.get("tau", 3.0))
        return LanczosFilter(lobes, p.get("radius"))
    raise ValueError(f"Unsupported reconstruction filter {kind!r}.")


def compile_scene(description, *, width=None, height=None, accelerator: str = "auto"):
    """Turn a loaded scene (`load_scene`) into `(RenderScene, PinholeCamera, filter)`.

    Materials become `MaterialTables` (see `radiometria.render._materials` for the supported
    Mitsuba BSDFs); their spectra and the emitters' are tabulated on the renderer's 1 nm grid
    (`spectrum_values`): RGB reflectances as bounded sigmoid-polynomial spectra, RGB radiances
    as illuminant spectra (x D65 with Y = 1), measured and blackbody spectra as given. The
    camera keeps its field of view along its `fov_axis` when `width`/`height` override the
    film's size.

    **Arguments:**

    - `description`: a `SceneDescription`.
    - `width`, `height`: image size [px]; default: the scene's film.
    - `accelerator`: as in `RenderScene.from_triangles`.

    **Returns:**

    `(scene, camera, rfilter)`.

    !!! note "Thesis"
        Chapter 8 (scenes); section 2.3 (camera and filter); section 2.2.3 (RGB to spectra).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's scene conventions).
    """
    from ..camera import PinholeCamera
    from ._spectral import spectrum_values

    where = description.source or "scene"
    materials = MaterialTables.from_materials(description.materials, where)
    n_grid = materials.reflectance.values.shape[1]
    if description.emitters:
        radiance = np.stack(
            [spectrum_values(e.radiance, "illuminant") for e in description.emitters]
        )
    else:
        radiance = np.zeros((0, n_grid))
    scene = RenderScene.from_triangles(
        description.vertices,
        description.faces,
        description.face_material,
        materials,
        description.face_emitter,
        SpectrumTable(jnp.asarray(radiance.reshape(-1, n_grid), jnp.float32)),
        emitter_two_sided=[e.two_sided for e in description.emitters],
        accelerator=accelerator,
    )
    cam = description.camera
    camera = PinholeCamera.from_to_world(
        np.asarray(cam.to_world, np.float64),
        float(cam.fov_deg),
        description.film.width if width is None else width,
        description.film.height if height is None else height,
        cam.fov_axis,
        near_clip=cam.near_clip,
        far_clip=cam.far_clip,
    )
    return scene, camera, _make_filter(description.film)
