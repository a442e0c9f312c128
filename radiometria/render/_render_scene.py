"""`RenderScene`: a scene laid out for the integrators (arrays and plugins, one pytree).

A `RenderScene` holds what the bounce loop reads per hit: the triangles as structure-of-arrays
(for hit points and normals), the material index of each triangle, the scene's material
plugins (`MaterialSet`), its light plugin (`AbstractLight`: area lights today) and its
accelerator (`AbstractAccelerator`: brute force or a BVH, with the native CPU kernel or the
JAX traversal inside). `compile_scene` builds one from a loaded scene description.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, Int

from .._checks import device_array
from ._accelerators import (
    AbstractAccelerator,
    SphereAccelerator,
    build_accelerator,
    check_triangle_arrays,
)
from ._geometry._mesh import _areas, _corners
from ._geometry._sphere import MAX_ANALYTIC_SPHERES, Spheres
from ._lights import AbstractLight, AreaLight, LightSet
from ._materials import AbstractMaterial, Diffuse, MaterialSet
from ._media import AbstractMediumPlugin, MediumSet
from ._spectral import SpectrumTable
from ._textures import AbstractTexture, ConstantTexture

__all__ = ["RenderScene"]


class RenderScene(eqx.Module):
    """Triangles, material and light plugins and an accelerator, ready for the integrators.

    Build one with `RenderScene.from_triangles` (or from a loaded scene with
    `radiometria.render.compile_scene`). All arrays are float32 unless noted; lengths are in
    the scene's unit [scene units], spectra on the 1 nm grid of `wavelength_grid_nm`.

    **Fields:**

    - `p0`, `e1`, `e2`, `normal`: `(f, 3)` first corner, edges `v1 - v0`, `v2 - v0` and unit
        geometric normal (the direction of `e1 x e2`) of each triangle. [scene units]
    - `face_material`: `(f,)` int32 material of each triangle.
    - `materials`: the `MaterialSet` (one plugin per kind of material).
    - `light`: the emitters, an `AbstractLight`: an `AreaLight` on emissive triangles, or a
        `LightSet` of it and further plugins (point, spot, projector, directional, environment).
    - `accelerator`: an `AbstractAccelerator` (brute force or a BVH).
    - `ray_epsilon`: relative offset of secondary ray origins (static). [1]
    - `media`: the scene's participating media (`MediumSet`), or `None` for none.
    - `face_interior`, `face_exterior`: `(f,)` int32 medium index on the back side (against
        the normal) and the front side of each triangle: -1 is a vacuum, -2 (`KEEP_MEDIUM`)
        marks a triangle that is no medium boundary (a ray crossing it keeps its medium), as
        in Mitsuba, where only shapes with an `interior` or `exterior` change the medium.
        `None` when the scene has no media.
    - `camera_medium`: index of the medium the camera sits in, -1 for a vacuum (static).
    - `face_uv`: `(f, 3, 2)` surface coordinates (u, v) at the three corners of each
        triangle, interpolated with the hit's barycentrics for textures; `None` (meshes
        without uvs) gives the hit's barycentrics $(b_1, b_2)$ as uv, as Mitsuba 3. [1]
    - `shading_normal`: `(f, 3, 3)` unit normals at the three corners of each triangle
        (vertex normals), interpolated into the shading normal; `None`: flat shading.
    - `face_attributes`: `(f, a)` mesh attributes baked per triangle for `mesh_attribute`
        textures (blocks of `radiometria.render._textures._mesh_attribute.ATTRIBUTE_BLOCK`
        columns), or `None`. With them a hit's surface coordinates (the `uv` the textures
        get) are `(u, v, b1, b2, *face_attributes[face])`; without, `(u, v)`.
    - `spheres`: the true spheres intersected analytically (`Spheres`; the accelerator is a
        `SphereAccelerator`), or `None`. Their tessellations' triangles stay in the
        per-triangle tables (material, media, emitter rows) but not in the accelerator.
    - `face_sphere`: `(f,)` int32 index into `spheres` of the sphere each triangle
        tessellates, -1 for the others; `None` without `spheres`. A hit on such a triangle
        takes the sphere's point, normal (also the shading normal) and uv
        (`surface_geometry`).

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
    materials: MaterialSet  # the material plugins, one row per material
    light: AbstractLight  # the emitters
    accelerator: AbstractAccelerator  # what the intersection queries traverse
    ray_epsilon: float = eqx.field(static=True, default=1e-4)
    media: MediumSet | None = None  # participating media, one row per medium
    face_interior: Int[Array, " f"] | None = None  # medium behind each face (-1 vacuum, -2 keep)
    face_exterior: Int[Array, " f"] | None = None  # medium in front of each face
    camera_medium: int = eqx.field(static=True, default=-1)
    face_uv: Float[Array, "f 3 2"] | None = None  # uv at each triangle's corners (textures)
    shading_normal: Float[Array, "f 3 3"] | None = None  # unit normals at the corners
    face_attributes: Float[Array, "f a"] | None = None  # mesh attributes (mesh_attribute)
    spheres: Spheres | None = None  # spheres intersected analytically
    face_sphere: Int[Array, " f"] | None = None  # sphere of each triangle, -1 none

    def geometric_normal(self, face: Int[Array, " n"], p: Float[Array, "n 3"]):
        """The unit geometric normal `(n, 3)` of the surface of `face` at the points `p`:
        the triangle's, or for a triangle of an analytic sphere the sphere's at `p`."""
        n = self.normal[face]
        if self.spheres is None:
            return n
        s = self.face_sphere[face]
        n_s = self.spheres.normal(jnp.maximum(s, 0), p).astype(n.dtype)
        return jnp.where((s >= 0)[:, None], n_s, n)

    @property
    def surface_width(self) -> int:
        """Columns of a hit's surface coordinates: 2 (u, v), or 4 + the baked attributes'
        columns (u, v, b1, b2, attributes) when the scene has `face_attributes`."""
        return 2 if self.face_attributes is None else 4 + int(self.face_attributes.shape[1])

    @classmethod
    def from_triangles(
        cls,
        vertices,
        faces,
        face_material,
        materials: "SpectrumTable | MaterialSet | list[AbstractMaterial]",
        face_emitter,
        radiance: "SpectrumTable | AbstractTexture",
        *,
        two_sided=None,
        emitter_two_sided=None,
        emitter_sphere=None,
        lights: "list[AbstractLight] | tuple" = (),
        accelerator: "str | AbstractAccelerator" = "auto",
        dtype=jnp.float32,
        media: "MediumSet | list[AbstractMediumPlugin] | None" = None,
        face_interior=None,
        face_exterior=None,
        camera_medium: int = -1,
        face_uv=None,
        shading_normal=None,
        face_attributes=None,
        spheres=None,
    ) -> "RenderScene":
        """Lay out a triangle scene (NumPy work, done once, outside `jit`).

        **Arguments:**

        - `vertices`: `(v, 3)` positions [scene units]; `faces`: `(f, 3)` vertex indices, whose
            winding sets the front side (normal `(v1 - v0) x (v2 - v0)`).
        - `face_material`: `(f,)` material (row of `materials`) of each triangle.
        - `materials`: material plugins in material order (a list of `AbstractMaterial`, or a
            `MaterialSet`), or a `SpectrumTable` of diffuse reflectances, one row per
            (Lambertian) material [1].
        - `face_emitter`: `(f,)` row of `radiance` for each triangle, or -1.
        - `radiance`: emitted radiance, one row per emitter (a `SpectrumTable` or a texture),
            emitted on the front side. [W m^-2 sr^-1 nm^-1]
        - `two_sided`: `(m,)` booleans, Lambertian materials that scatter on both sides
            (default: none; only with a `SpectrumTable` of reflectances).
        - `emitter_two_sided`: `(e,)` booleans, emitters that emit on both sides (default:
            none).
        - `emitter_sphere`: per emitter, `(center, radius)` of the sphere its triangles
            tessellate (sampled by the cone it subtends: `AreaLight`), or `None` (default:
            none). [scene units]
        - `lights`: further light plugins beside the area lights (`PointLight`,
            `SpotLight`, `DirectionalLight`, `ConstantLight`, `EnvironmentLight`); with any,
            the scene's `light` is a `LightSet` that picks one per sample by power.
        - `accelerator`: an `AbstractAccelerator` built on these triangles, or a name:
            `"bvh"`, `"brute_force"` (test every triangle: fastest for a few dozen triangles,
            such as the Cornell box) or `"auto"` (brute force up to 64 triangles).
        - `dtype`: float dtype of the arrays (float32 for rendering).
        - `media`: medium plugins in medium order (a list of `AbstractMediumPlugin`, or a
            `MediumSet`), or `None` for a scene without media.
        - `face_interior`, `face_exterior`: `(f,)` medium index behind / in front of each
            triangle, -1 for a vacuum, -2 for no boundary (default: all -2).
        - `camera_medium`: the medium the camera is in, -1 for a vacuum.
        - `face_uv`: `(f, 3, 2)` uv at the corners of each triangle (textures), or `None`:
            the hit's barycentrics serve as uv. [1]
        - `shading_normal`: `(f, 3, 3)` unit normals at the corners of each triangle,
            interpolated with the hit's barycentrics into the shading normal that orients
            the BSDF's frame (Mitsuba's vertex normals; `Pharr2023` §3.10.1), or `None`: the
            geometric normals shade. Rows equal to the face's normal shade flat.
        - `face_attributes`: `(f, a)` baked mesh attributes of `mesh_attribute` textures
            (`compile_scene` makes them), or `None`.
        - `spheres`: true spheres to intersect analytically, a sequence of `(center (3,),
            radius, rotation (3, 3), triangles (m,))`: the sphere, the rotation from its
            object frame (uv, `Spheres`) to the scene's axes, and the indices of the triangles
            that tessellate it (they keep its table rows and leave the accelerator; an
            emitter on them samples the true sphere). At most `MAX_ANALYTIC_SPHERES`;
            `accelerator` must then be a name. Default none.
        """
        vertices, faces = check_triangle_arrays(vertices, faces)
        if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
            raise ValueError("`faces` index vertices out of range.")
        n_faces = faces.shape[0]
        face_material = np.asarray(face_material, dtype=np.int64).reshape(n_faces)
        face_emitter = np.asarray(face_emitter, dtype=np.int64).reshape(n_faces)
        if isinstance(materials, SpectrumTable):
            n_mat = materials.values.shape[0]
            sides = np.zeros(n_mat, bool) if two_sided is None else np.asarray(two_sided, bool)
            materials = [Diffuse(ConstantTexture(materials), device_array(sides.reshape(n_mat)))]
        elif two_sided is not None:
            raise ValueError("`two_sided` goes with a SpectrumTable; material plugins carry it.")
        if not isinstance(materials, MaterialSet):
            materials = MaterialSet.from_materials(list(materials))
        if isinstance(radiance, SpectrumTable):
            radiance = ConstantTexture(SpectrumTable(device_array(radiance.values, dtype)))
        n_mat, n_em = materials.n_materials, radiance.n_rows
        if face_material.min(initial=0) < 0 or face_material.max(initial=0) >= n_mat:
            raise ValueError(f"`face_material` must index the {n_mat} materials.")
        if face_emitter.min(initial=-1) < -1 or face_emitter.max(initial=-1) >= n_em:
            raise ValueError(f"`face_emitter` must be -1 or index the {n_em} radiance rows.")

        v0, v1, v2 = _corners(np, vertices, faces)
        e1, e2 = v1 - v0, v2 - v0
        area = _areas(np, vertices, faces)
        normal = np.cross(e1, e2) / np.where(area > 0, 2.0 * area, 1.0)[:, None]
        p0, e1, e2, normal = (device_array(x, dtype=dtype) for x in (v0, e1, e2, normal))
        sphere_fields, true_spheres = {}, None
        if spheres:
            sphere_fields = _sphere_fields(spheres, n_faces, dtype)
            true_spheres = _emitter_true_spheres(spheres, face_emitter, n_em)
        light = AreaLight.from_triangles(
            p0, e1, e2, normal, area, face_emitter, radiance, emitter_two_sided,
            face_uv=face_uv, emitter_sphere=emitter_sphere, emitter_true_sphere=true_spheres,
            dtype=dtype,
        )  # fmt: skip
        if lights:
            # The bounding sphere of the geometry sets the power of lights at infinity.
            lo, hi = (vertices.min(axis=0), vertices.max(axis=0)) if len(vertices) else (0, 0)
            radius = max(float(np.linalg.norm(np.asarray(hi) - lo)) / 2.0, 1e-4)
            center = (np.asarray(lo, float) + np.asarray(hi, float)) / 2.0
            light = LightSet.from_lights(
                [light, *lights], scene_radius=radius, scene_center=center, dtype=dtype
            )
        if spheres:
            if isinstance(accelerator, AbstractAccelerator):
                raise ValueError(
                    "`accelerator` must be a name when `spheres` are given: the spheres' "
                    "triangles are left out of the accelerator built here."
                )
            accelerator = SphereAccelerator.from_triangles(
                vertices, faces, dtype=dtype, spheres=sphere_fields["spheres"],
                sphere_faces=np.asarray(sphere_fields["face_sphere"]) >= 0, kind=accelerator,
            )  # fmt: skip
        if not isinstance(accelerator, AbstractAccelerator):
            accelerator = build_accelerator(vertices, faces, kind=accelerator, dtype=dtype)
        media_fields = _media_fields(media, face_interior, face_exterior, camera_medium, n_faces)
        face_uv = _optional_face_array(face_uv, "face_uv", (n_faces, 3, 2), dtype)
        shading_normal = _optional_face_array(
            shading_normal, "shading_normal", (n_faces, 3, 3), dtype
        )
        if face_attributes is not None:
            a = np.asarray(face_attributes)
            face_attributes = _optional_face_array(
                a, "face_attributes", (n_faces, a.shape[-1] if a.ndim == 2 else -1), dtype
            )
        return cls(
            p0=p0,
            e1=e1,
            e2=e2,
            normal=normal,
            face_material=device_array(face_material, dtype=jnp.int32),
            materials=materials,
            light=light,
            accelerator=accelerator,
            face_uv=face_uv,
            shading_normal=shading_normal,
            face_attributes=face_attributes,
            **media_fields,
            **sphere_fields,
        )


def _emitter_true_spheres(spheres, face_emitter: np.ndarray, n_em: int) -> list | None:
    """Per emitter, the `(center, radius, rotation)` of the analytic sphere it covers, or
    `None` (`AreaLight.from_triangles`' `emitter_true_sphere`); an analytic sphere must
    emit from all its triangles as one emitter that emits nowhere else, or not at all."""
    out: list = [None] * n_em
    for j, (center, radius, rotation, tri) in enumerate(spheres):
        tri = np.asarray(tri, np.int64).reshape(-1)
        ids = np.unique(face_emitter[tri])
        if ids.tolist() == [-1]:
            continue
        e = int(ids[0])
        if len(ids) > 1 or np.count_nonzero(face_emitter == e) != len(tri):
            raise ValueError(
                f"`spheres[{j}]`: an analytic sphere's triangles must all belong to one "
                f"emitter that has no other triangles, or to none; they belong to {ids.tolist()}."
            )
        out[e] = (center, radius, rotation)
    return out if any(sp is not None for sp in out) else None


def _sphere_fields(spheres, n_faces: int, dtype) -> dict:
    """`spheres` and `face_sphere` of `RenderScene.from_triangles`, checked (NumPy)."""
    spheres = list(spheres)
    if len(spheres) > MAX_ANALYTIC_SPHERES:
        raise ValueError(
            f"`spheres` holds {len(spheres)} spheres; at most {MAX_ANALYTIC_SPHERES} are "
            "intersected analytically (leave the others tessellated)."
        )
    face_sphere = np.full(n_faces, -1, np.int32)
    first = []
    for j, sp in enumerate(spheres):
        if len(sp) != 4:
            raise ValueError(
                f"`spheres[{j}]` must be (center, radius, rotation, triangles), got {len(sp)} "
                "items."
            )
        tri = np.asarray(sp[3], np.int64).reshape(-1)
        if (
            not len(tri)
            or tri.min() < 0
            or tri.max() >= n_faces
            or len(np.unique(tri)) < len(tri)
            or np.any(face_sphere[tri] >= 0)
        ):
            raise ValueError(
                f"`spheres[{j}]`: its triangles must be distinct indices of the {n_faces} "
                "triangles, not shared with another sphere."
            )
        face_sphere[tri] = j
        first.append(tri[0])
    sph = Spheres.from_arrays(
        [s[0] for s in spheres], [s[1] for s in spheres], [s[2] for s in spheres], first,
        dtype=dtype,
    )  # fmt: skip
    return {"spheres": sph, "face_sphere": device_array(face_sphere)}


def _optional_face_array(value, name: str, shape: tuple[int, ...], dtype):
    """`None`, or a per-face array checked to be finite and of `shape`, as `dtype`."""
    if value is None:
        return None
    value = np.asarray(value, np.float64)
    if value.shape != shape or not np.all(np.isfinite(value)):
        raise ValueError(
            f"`{name}` must be finite, of shape ({', '.join(map(str, shape))}), got shape "
            f"{value.shape}."
        )
    return device_array(value, dtype)


def _media_fields(media, face_interior, face_exterior, camera_medium, n_faces) -> dict:
    """The media fields of `RenderScene.from_triangles`, checked (NumPy, outside `jit`)."""
    if media is None:
        if face_interior is not None or face_exterior is not None or camera_medium != -1:
            raise ValueError("medium indices were given for a scene without `media`.")
        return {}
    if not isinstance(media, MediumSet):
        media = MediumSet.from_media(list(media))
    n_media = media.n_media
    out = {"media": media}
    for name, value in (("face_interior", face_interior), ("face_exterior", face_exterior)):
        a = np.full(n_faces, -2, np.int64) if value is None else np.asarray(value, np.int64)
        a = a.reshape(n_faces) if a.size == n_faces else a
        if a.shape != (n_faces,) or a.min(initial=-1) < -2 or a.max(initial=-1) >= n_media:
            raise ValueError(
                f"`{name}` must be ({n_faces},) indices of the {n_media} media, -1 (vacuum) "
                f"or -2 (no boundary); got shape {a.shape}, range "
                f"[{a.min(initial=0)}, {a.max(initial=0)}]."
            )
        out[name] = device_array(a, jnp.int32)
    inside = (out["face_interior"] == -2) != (out["face_exterior"] == -2)
    if bool(jnp.any(inside)):
        raise ValueError(
            "`face_interior` and `face_exterior` must both be -2 (no boundary) or both name a "
            "medium or -1 (vacuum) on each triangle."
        )
    if (
        isinstance(camera_medium, bool)
        or not isinstance(camera_medium, int)
        or not (-1 <= camera_medium < n_media)
    ):
        raise ValueError(
            f"`camera_medium` must be -1 (vacuum) or index the {n_media} media, got "
            f"{camera_medium!r}."
        )
    out["camera_medium"] = camera_medium
    return out
