"""Small synthetic scenes for the integrator and driver tests (helper P)."""

import jax.numpy as jnp
import numpy as np

from radiometria.camera import PinholeCamera
from radiometria.render import RenderScene, SpectrumTable, wavelength_grid_nm

N_GRID = wavelength_grid_nm().shape[0]


def constant_table(*values):
    return SpectrumTable(jnp.asarray(np.outer(values, np.ones(N_GRID)), jnp.float32))


def quad(corners):
    """Two triangles (v0, v1, v2), (v0, v2, v3) of a quad; normal by the right-hand rule."""
    return np.asarray(corners, float), np.array([[0, 1, 2], [0, 2, 3]])


def merge(*quads):
    verts, faces, off = [], [], 0
    for v, f in quads:
        verts.append(v)
        faces.append(f + off)
        off += len(v)
    return np.concatenate(verts), np.concatenate(faces)


def inward_cube(h=1.0):
    """The six faces of [-h, h]^3, their normals pointing into the cube."""
    c = h
    v, f = merge(
        quad([[-c, -c, -c], [c, -c, -c], [c, -c, c], [-c, -c, c]]),  # y = -c
        quad([[-c, c, -c], [-c, c, c], [c, c, c], [c, c, -c]]),  # y = +c
        quad([[-c, -c, -c], [-c, -c, c], [-c, c, c], [-c, c, -c]]),  # x = -c
        quad([[c, -c, -c], [c, c, -c], [c, c, c], [c, -c, c]]),  # x = +c
        quad([[-c, -c, -c], [-c, c, -c], [c, c, -c], [c, -c, -c]]),  # z = -c
        quad([[-c, -c, c], [c, -c, c], [c, c, c], [-c, c, c]]),  # z = +c
    )
    return v, f[:, ::-1]  # the corners above wind outwards: reverse them


def furnace_scene(albedo: float, le: float) -> RenderScene:
    """The inside of a closed cube whose faces all have albedo `albedo` and emit `le`."""
    v, f = inward_cube()
    zero = np.zeros(len(f), int)
    return RenderScene.from_triangles(v, f, zero, constant_table(albedo), zero, constant_table(le))


def furnace_camera(width: int = 16, height: int = 16) -> PinholeCamera:
    return PinholeCamera.from_look_at(
        np.array([0.1, 0.2, -0.3]),
        np.array([0.5, 0.3, 1.0]),
        np.array([0.0, 1, 0]),
        70.0,
        width,
        height,
    )


def lit_box_scene() -> RenderScene:
    """A closed box with walls of four different grey/spectral albedos and a ceiling light."""
    v, f = inward_cube()
    light = quad([[-0.3, 0.99, -0.3], [0.3, 0.99, -0.3], [0.3, 0.99, 0.3], [-0.3, 0.99, 0.3]])
    v, f = merge((v, f), light)
    grid = wavelength_grid_nm()
    ramp = 0.1 + 0.8 * (grid - grid[0]) / (grid[-1] - grid[0])  # reddish: rises with wavelength
    albedo = np.stack([np.full_like(grid, 0.7), np.full_like(grid, 0.3), ramp, 1.0 - ramp])
    material = np.array([0, 0, 0, 0, 1, 1, 2, 2, 3, 3, 0, 0, 0, 0])
    emitter = np.where(np.arange(len(f)) >= 12, 0, -1)
    return RenderScene.from_triangles(
        v,
        f,
        material,
        SpectrumTable(jnp.asarray(albedo, jnp.float32)),
        emitter,
        constant_table(5.0),
    )


def lit_box_camera(width: int = 16, height: int = 12) -> PinholeCamera:
    return PinholeCamera.from_look_at(
        np.array([0.0, 0.0, -0.95]),
        np.array([0.0, 0.0, 1.0]),
        np.array([0.0, 1, 0]),
        80.0,
        width,
        height,
    )
