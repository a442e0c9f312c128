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

from ._accelerators import AbstractAccelerator, build_accelerator, check_triangle_arrays
from ._geometry._mesh import _areas, _corners
from ._lights import AbstractLight, AreaLight
from ._materials import AbstractMaterial, Diffuse, MaterialSet
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
    - `light`: the emitters, an `AbstractLight` (an `AreaLight` on emissive triangles).
    - `accelerator`: an `AbstractAccelerator` (brute force or a BVH).
    - `ray_epsilon`: relative offset of secondary ray origins (static). [1]

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
        accelerator: "str | AbstractAccelerator" = "auto",
        dtype=jnp.float32,
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
        - `accelerator`: an `AbstractAccelerator` built on these triangles, or a name:
            `"bvh"`, `"brute_force"` (test every triangle: fastest for a few dozen triangles,
            such as the Cornell box) or `"auto"` (brute force up to 64 triangles).
        - `dtype`: float dtype of the arrays (float32 for rendering).
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
            materials = [Diffuse(ConstantTexture(materials), jnp.asarray(sides.reshape(n_mat)))]
        elif two_sided is not None:
            raise ValueError("`two_sided` goes with a SpectrumTable; material plugins carry it.")
        if not isinstance(materials, MaterialSet):
            materials = MaterialSet.from_materials(list(materials))
        if isinstance(radiance, SpectrumTable):
            radiance = ConstantTexture(SpectrumTable(jnp.asarray(radiance.values, dtype)))
        n_mat, n_em = materials.n_materials, radiance.n_rows
        if face_material.min(initial=0) < 0 or face_material.max(initial=0) >= n_mat:
            raise ValueError(f"`face_material` must index the {n_mat} materials.")
        if face_emitter.min(initial=-1) < -1 or face_emitter.max(initial=-1) >= n_em:
            raise ValueError(f"`face_emitter` must be -1 or index the {n_em} radiance rows.")

        v0, v1, v2 = _corners(np, vertices, faces)
        e1, e2 = v1 - v0, v2 - v0
        area = _areas(np, vertices, faces)
        normal = np.cross(e1, e2) / np.where(area > 0, 2.0 * area, 1.0)[:, None]
        p0, e1, e2, normal = (jnp.asarray(x, dtype=dtype) for x in (v0, e1, e2, normal))
        light = AreaLight.from_triangles(
            p0, e1, e2, normal, area, face_emitter, radiance, emitter_two_sided, dtype=dtype
        )
        if not isinstance(accelerator, AbstractAccelerator):
            accelerator = build_accelerator(vertices, faces, kind=accelerator, dtype=dtype)
        return cls(
            p0=p0,
            e1=e1,
            e2=e2,
            normal=normal,
            face_material=jnp.asarray(face_material, dtype=jnp.int32),
            materials=materials,
            light=light,
            accelerator=accelerator,
        )
