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
from ..scattering import DiffuseBxDF
from ._bvh import BVH, build_bvh
from ._intersect import (
    Hit,
    intersect_any,
    intersect_brute_force_any,
    intersect_brute_force_closest,
    intersect_closest,
)
from ._mesh import TriangleMesh
from ._spectral import SpectrumTable

__all__ = ["BRUTE_FORCE_MAX_TRIANGLES", "DEFAULT_UNBOUNDED_DEPTH", "RenderScene", "compile_scene"]

BRUTE_FORCE_MAX_TRIANGLES = 64


class RenderScene(eqx.Module):
    """Triangles, materials and emitters as arrays, ready for `path_radiance`.

    Build one with `RenderScene.from_triangles` (or from a loaded scene with
    `radiometria.render.compile_scene`). All arrays are float32 unless noted.
    """

    p0: Float[Array, "f 3"]  # first vertex of each triangle [scene units]
    e1: Float[Array, "f 3"]  # edge v1 - v0
    e2: Float[Array, "f 3"]  # edge v2 - v0
    normal: Float[Array, "f 3"]  # unit geometric normal, (v1 - v0) x (v2 - v0) direction
    face_material: Int[Array, " f"]  # material index of each triangle
    face_emitter: Int[Array, " f"]  # emitter index of each triangle, -1 when not emissive
    reflectance: SpectrumTable  # one row per material [1]
    two_sided: Bool[Array, " m"]  # per material: scatter on both sides
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
        reflectance: SpectrumTable,
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
        - `face_material`: `(f,)` row of `reflectance` for each triangle.
        - `reflectance`: diffuse reflectance spectra, one row per material [1].
        - `face_emitter`: `(f,)` row of `radiance` for each triangle, or -1.
        - `radiance`: emitted radiance spectra, one row per emitter, emitted on the front side.
        - `two_sided`: `(m,)` booleans, materials that scatter on both sides (default: none).
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
        n_mat = reflectance.values.shape[0]
        n_em = radiance.values.shape[0]
        if face_material.min(initial=0) < 0 or face_material.max(initial=0) >= n_mat:
            raise ValueError(f"`face_material` must index the {n_mat} reflectance rows.")
        if face_emitter.min(initial=-1) < -1 or face_emitter.max(initial=-1) >= n_em:
            raise ValueError(f"`face_emitter` must be -1 or index the {n_em} radiance rows.")
        two_sided = (
            np.zeros(n_mat, bool) if two_sided is None else np.asarray(two_sided, bool)
        ).reshape(n_mat)
        emitter_two_sided = (
            np.zeros(n_em, bool)
            if emitter_two_sided is None
            else np.asarray(emitter_two_sided, bool)
        ).reshape(n_em)

        v0, v1, v2 = (vertices[faces[:, i]] for i in range(3))
        e1, e2 = v1 - v0, v2 - v0
        cross = np.cross(e1, e2)
        double_area = np.linalg.norm(cross, axis=1)
        normal = cross / np.where(double_area > 0, double_area, 1.0)[:, None]
        area = 0.5 * double_area

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
            reflectance=SpectrumTable(f(reflectance.values)),
            two_sided=jnp.asarray(two_sided),
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
    def bsdf(self, material, wavelength_nm) -> DiffuseBxDF:
        """The BSDF of each hit at its wavelengths (Lambertian with the material's reflectance)."""
        return DiffuseBxDF(self.reflectance(material, wavelength_nm))


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

    Materials and emitters become spectra on the renderer's 1 nm grid (`spectrum_values`):
    RGB reflectances as bounded sigmoid-polynomial spectra, RGB radiances as illuminant
    spectra (x D65 with Y = 1), measured and blackbody spectra as given. The camera keeps its
    field of view along its `fov_axis` when `width`/`height` override the film's size.

    **Arguments:**

    - `description`: a `SceneDescription`.
    - `width`, `height`: image size [px]; default: the scene's film.
    - `accelerator`: as in `RenderScene.from_triangles`.

    **Returns:**

    `(scene, camera, rfilter)`.
    """
    from ..camera import PinholeCamera
    from ._spectral import spectrum_values

    for m in description.materials:
        if m.type != "diffuse":
            raise ValueError(
                f"{description.source or 'scene'}: material {m.name!r} has type {m.type!r}; "
                "the integrators support 'diffuse' materials."
            )
    reflectance = np.stack(
        [
            spectrum_values(m.params.get("reflectance", {"value": 0.5}), "albedo")
            for m in description.materials
        ]
    )
    if description.emitters:
        radiance = np.stack(
            [spectrum_values(e.radiance, "illuminant") for e in description.emitters]
        )
    else:
        radiance = np.zeros((0, reflectance.shape[1]))
    scene = RenderScene.from_triangles(
        description.vertices,
        description.faces,
        description.face_material,
        SpectrumTable(jnp.asarray(reflectance, jnp.float32)),
        description.face_emitter,
        SpectrumTable(jnp.asarray(radiance.reshape(-1, reflectance.shape[1]), jnp.float32)),
        two_sided=[m.two_sided for m in description.materials],
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
