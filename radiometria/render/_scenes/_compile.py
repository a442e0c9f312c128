"""From a scene description to the renderer's plugins (thesis ch. 8; section 2.3)."""

import collections
import dataclasses
import hashlib
import threading
from pathlib import PurePath

import equinox as eqx
import jax
import numpy as np

from ..._io import hash_array
from ...camera import AbstractCamera, AbstractFilter, OrthographicCamera, ThinLensCamera
from .._geometry._sphere import MAX_ANALYTIC_SPHERES
from .._integrators import AbstractIntegrator
from .._integrators._base import DEFAULT_UNBOUNDED_DEPTH
from .._lights import AreaLight
from .._registry import CAMERAS, FILTERS, INTEGRATORS, LIGHTS, MATERIALS, MEDIA, SAMPLERS
from .._render_scene import RenderScene
from .._samplers import AbstractSampler
from .._textures._mesh_attribute import ATTRIBUTE_BLOCK, MeshAttributeTexture, corner_spectra
from ._description import SceneDescription, SceneError

__all__ = [
    "compile_scene",
    "compile_scene_cached",
    "scene_camera",
    "scene_filter",
    "scene_integrator",
    "scene_lights",
    "scene_sampler",
]

# Each filter's parameters in Mitsuba's names, with Mitsuba's defaults (the Gaussian's radius
# defaults to 4 standard deviations in the filter itself); `catmullrom` is Mitchell B=0, C=1/2.
_FILTER_ARGS = {
    "box": (("radius", 0.5),),
    "tent": (("radius", 1.0),),
    "gaussian": (("stddev", 0.5), ("radius", None)),
    "mitchell": (("B", 1.0 / 3.0), ("C", 1.0 / 3.0), ("radius", 2.0)),
    "catmullrom": (("B", 0.0), ("C", 0.5), ("radius", 2.0)),
    "lanczos": (("lobes", 3.0), ("radius", None)),
}


def scene_filter(description: SceneDescription) -> AbstractFilter:
    """The reconstruction filter of the scene's film (`FILTERS` registry).

    **Arguments:**

    - `description`: a `SceneDescription` (its film's filter and parameters, [px]).

    !!! note "Thesis"
        Section 2.3.2 (filtering image samples).
    """
    film = description.film
    if film.filter not in FILTERS:
        raise SceneError(
            f"{description.source or 'scene'}: unsupported reconstruction filter "
            f"{film.filter!r}; supported: {sorted(FILTERS)}."
        )
    p = dict(film.filter_params)
    if film.filter == "lanczos" and "tau" in p:  # Mitsuba 0.6's name for the lobes
        p.setdefault("lobes", p.pop("tau"))
    args = [p.get(name, default) for name, default in _FILTER_ARGS[film.filter]]
    return FILTERS[film.filter](*args)


def scene_integrator(
    description: SceneDescription, *, name: str | None = None, max_depth: int | None = None
) -> AbstractIntegrator:
    """The integrator the scene file asks for (`INTEGRATORS` registry), with its settings.

    **Arguments:**

    - `description`: a `SceneDescription` (its `integrator` name, `max_depth` and `rr_depth`
        [path segments]; an unbounded depth becomes 64 segments; its other
        `integrator_params`, such as `hide_emitters`, where the integrator takes them).
    - `name`: another integrator of the registry instead of the file's (`--integrator`).
    - `max_depth`: a depth instead of the file's (`--max-depth`) [path segments]; a
        `ValueError` for an integrator without one.

    **Returns:**

    An `AbstractIntegrator`, e.g. `Path(max_depth=8, rr_depth=5)` for the Cornell box.

    !!! note "Thesis"
        Chapters 8-9 (light transport).
    """
    name = description.integrator if name is None else name
    if name not in INTEGRATORS:
        raise ValueError(f"integrator must be one of {sorted(INTEGRATORS)}, got {name!r}.")
    cls = INTEGRATORS[name]
    if max_depth is not None and "max_depth" not in cls.PARAMETERS:
        raise ValueError(f"max_depth does not apply to the {name!r} integrator.")
    depth = description.max_depth if max_depth is None else max_depth
    params = dict(description.integrator_params) | {
        "max_depth": DEFAULT_UNBOUNDED_DEPTH if depth is None else depth,
        "rr_depth": description.rr_depth,
    }
    params = {k: v for k, v in params.items() if k in cls.PARAMETERS}
    return cls.from_properties(params, where=description.source or "scene")


def scene_lights(description: SceneDescription) -> list:
    """The light plugins of the scene's lights that are not on a shape (`LIGHTS` registry),
    one plugin per kind holding every light of that kind, in the order kinds first appear.

    **Arguments:**

    - `description`: a `SceneDescription` (its `lights`).

    **Returns:**

    A list of `AbstractLight` plugins (empty without such lights). Bad parameters raise
    `SceneError` naming the file, line and parameter; a second environment emitter too.

    !!! note "Thesis"
        Chapter 8 (light sources).
    """
    kinds: dict[str, list] = {}
    for light in description.lights:
        if light.type not in LIGHTS or light.type == "area":
            raise SceneError(
                f"{light.where or description.source or 'scene'}: unsupported emitter type "
                f"{light.type!r} outside a shape; supported: "
                f"{sorted(k for k in LIGHTS if k != 'area')}."
            )
        kinds.setdefault(light.type, []).append(light)
    infinite = [lt for lt in description.lights if lt.type in ("constant", "envmap")]
    if len(infinite) > 1:
        raise SceneError(
            f"{infinite[1].where}: a scene takes one environment emitter (constant or envmap); "
            f"the first is at {infinite[0].where}."
        )
    plugins = []
    for kind, group in kinds.items():
        where = [lt.where or lt.name for lt in group]
        try:
            plugins.append(LIGHTS[kind].from_properties([lt.params for lt in group], where=where))
        except ValueError as e:
            raise SceneError(str(e)) from None
    return plugins


_COMPILED_SCENES = 2  # compiled scenes `compile_scene_cached` keeps (most recent first)
_compiled: "collections.OrderedDict[tuple, tuple]" = collections.OrderedDict()
_compiled_lock = threading.Lock()


def _digest(obj, h) -> None:
    """Feed `obj` into the hash `h` by content: arrays by dtype, shape and bytes, dataclasses
    and equinox modules field by field, containers item by item, anything else by repr."""
    if isinstance(obj, np.ndarray | jax.Array):
        h.update(b"a")
        hash_array(h, obj)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"d{type(obj).__qualname__}(".encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _digest(getattr(obj, f.name), h)
        h.update(b")")
    elif isinstance(obj, eqx.Module):
        leaves, treedef = jax.tree.flatten(obj)
        h.update(f"m{treedef}".encode())
        for leaf in leaves:
            _digest(leaf, h)
    elif isinstance(obj, list | tuple):
        h.update(f"{type(obj).__name__}{len(obj)}(".encode())
        for x in obj:
            _digest(x, h)
        h.update(b")")
    elif isinstance(obj, dict):
        h.update(f"dict{len(obj)}(".encode())
        for k in sorted(obj, key=repr):
            _digest(k, h)
            _digest(obj[k], h)
        h.update(b")")
    elif obj is None or isinstance(obj, bool | int | float | complex | str | bytes | PurePath):
        h.update(f"{type(obj).__name__}:{obj!r};".encode())
    else:
        h.update(f"{type(obj).__qualname__}:{obj!r};".encode())


def scene_digest(description: SceneDescription) -> str:
    """A SHA-256 of a scene description's content (its arrays' bytes, its parameters), so
    that an edited description never finds the compilation of the one it was."""
    h = hashlib.sha256()
    _digest(description, h)
    return h.hexdigest()


def compile_scene_cached(
    description: SceneDescription, *, width=None, height=None
) -> tuple[RenderScene, AbstractCamera, AbstractFilter]:
    """`compile_scene`, kept for the last `_COMPILED_SCENES` descriptions (by content,
    `scene_digest`) and image sizes: rendering one loaded scene again (a convergence study,
    a benchmark, a figure at several spp) does not rebuild its BVH and plugins. Building them
    for 36 000 triangles takes 0.11 s, half of a 64 x 64 render at 4 spp."""
    key = (scene_digest(description), width, height)
    with _compiled_lock:
        if key in _compiled:
            _compiled.move_to_end(key)
            return _compiled[key]
    out = compile_scene(description, width=width, height=height)
    with _compiled_lock:
        _compiled[key] = out
        while len(_compiled) > _COMPILED_SCENES:
            _compiled.popitem(last=False)
    return out


def clear_compiled_scenes() -> None:
    """Forget the scenes `compile_scene_cached` keeps (their device arrays are freed)."""
    with _compiled_lock:
        _compiled.clear()


def compile_scene(
    description: SceneDescription,
    *,
    width=None,
    height=None,
    accelerator="auto",
    analytic_spheres: bool = True,
) -> tuple[RenderScene, AbstractCamera, AbstractFilter]:
    """Turn a loaded scene (`load_scene`) into `(RenderScene, camera, filter)`.

    Each material's `type` names its plugin in the `MATERIALS` registry, which reads the
    material's parameters (`from_properties`); their spectra and the emitters' are tabulated
    on the renderer's 1 nm grid: RGB reflectances as bounded sigmoid-polynomial spectra, RGB
    radiances as illuminant spectra (x D65 with Y = 1), measured and blackbody spectra as
    given. The camera keeps its field of view along its `fov_axis` when `width`/`height`
    override the film's size. `scene_integrator` gives the integrator the file asks for.

    **Arguments:**

    - `description`: a `SceneDescription`.
    - `width`, `height`: image size [px]; default: the scene's film.
    - `accelerator`: as in `RenderScene.from_triangles`.
    - `analytic_spheres`: intersect the true spheres of the scene's `sphere` shapes
        (`SceneDescription.spheres`) rather than their tessellations, as Mitsuba 3 does
        (default); an emitting sphere's light samples then lie on the true sphere too
        (`AreaLight`). A scene with more than `MAX_ANALYTIC_SPHERES` (32) spheres keeps
        their tessellations.

    **Returns:**

    `(scene, camera, rfilter)`.

    !!! note "Thesis"
        Chapter 8 (scenes); section 2.3 (camera and filter); section 2.2.3 (RGB to spectra).

    ??? cite "References"
        `Jakob2022` (Mitsuba 3's scene conventions).
    """
    where = description.source or "scene"
    materials = []
    for m in description.materials:
        if m.type not in MATERIALS:
            raise ValueError(
                f"{where}: material {m.name!r} has type {m.type!r}; supported: "
                f"{', '.join(MATERIALS)}."
            )
        what = f"{where}: material {m.name!r}"
        materials.append(
            MATERIALS[m.type].from_properties(m.params, two_sided=m.two_sided, where=what)
        )
    materials, face_attributes = _mesh_attributes(description, materials)
    radiance = AreaLight.radiance_texture([e.radiance for e in description.emitters])
    scene = RenderScene.from_triangles(
        description.vertices,
        description.faces,
        description.face_material,
        materials,
        description.face_emitter,
        radiance,
        emitter_two_sided=[e.two_sided for e in description.emitters],
        emitter_sphere=[e.sphere for e in description.emitters],
        lights=scene_lights(description),
        accelerator=accelerator,
        **_scene_media(description, where),
        face_uv=face_uvs(description),
        face_attributes=face_attributes,
        **_surface_attributes(description),
        spheres=_analytic_spheres(description) if analytic_spheres else None,
    )
    return scene, scene_camera(description, width, height), scene_filter(description)


def _analytic_spheres(description: SceneDescription) -> list | None:
    """The `RenderScene.from_triangles` `spheres` of a scene: its true spheres, or `None`
    when it has none or more than `MAX_ANALYTIC_SPHERES`."""
    spheres = [(s.center, s.radius, s.rotation, s.triangles) for s in description.spheres]
    return spheres if 0 < len(spheres) <= MAX_ANALYTIC_SPHERES else None


def scene_sampler(
    description: SceneDescription, *, default: str = "independent"
) -> AbstractSampler:
    """The sampler the scene file asks for (`SAMPLERS` registry: `Independent` or, for
    Mitsuba's `stratified`, `multijitter`, `ldsampler` and `sobol`, `OwenSobol`), or the
    sampler named `default` where the file names none (Mitsuba's default, `independent`)."""
    name = default if description.sampler is None else description.sampler
    if name not in SAMPLERS:
        raise ValueError(
            f"{description.source or 'scene'}: sampler {name!r}; supported: {', '.join(SAMPLERS)}."
        )
    return SAMPLERS[name]()


def scene_camera(description: SceneDescription, width=None, height=None) -> AbstractCamera:
    """The camera of a loaded scene: the `CAMERAS` plugin its `camera.type` names
    (`PinholeCamera`, `ThinLensCamera`, `OrthographicCamera`), `width` x `height` [px]
    (default: the scene's film), with the film's crop window and the sensor's principal
    point. A film with a crop window keeps its size: another `width`/`height` is a
    `ValueError`."""
    cam = description.camera
    kind = getattr(cam, "type", "perspective")
    if kind not in CAMERAS:
        raise ValueError(
            f"{description.source or 'scene'}: camera type {kind!r}; supported: "
            f"{', '.join(CAMERAS)}."
        )
    cls = CAMERAS[kind]
    to_world = np.asarray(cam.to_world, np.float64)
    film = description.film
    w = film.width if width is None else width
    h = film.height if height is None else height
    crop = getattr(film, "crop", None)
    if crop is not None and (w, h) != (film.width, film.height):
        raise ValueError(
            f"{description.source or 'scene'}: the film renders the crop window {crop[2]} x "
            f"{crop[3]} at ({crop[0]}, {crop[1]}) of a {film.width} x {film.height} film; "
            f"width x height {w} x {h} would move it: change the film in the scene file."
        )
    clip = {"near_clip": cam.near_clip, "far_clip": cam.far_clip, "crop_window": crop}
    if cls is OrthographicCamera:
        return cls.from_to_world(to_world, w, h, **clip)
    if cls is ThinLensCamera:
        return cls.from_to_world(
            to_world, float(cam.fov_deg), w, h, cam.aperture_radius, cam.focus_distance,
            cam.fov_axis, **clip,
        )  # fmt: skip
    pp = getattr(cam, "principal_point", (0.0, 0.0))
    return cls.from_to_world(
        to_world, float(cam.fov_deg), w, h, cam.fov_axis, principal_point=pp, **clip
    )


def _surface_attributes(description: SceneDescription) -> dict:
    """The `shading_normal` keyword of `RenderScene.from_triangles`: each triangle's corner
    values of the description's per-vertex normals; a triangle of a shape without normals
    gets its face normal at every corner (flat shading)."""
    if description.vertex_normals is None or not len(description.faces):
        return {}
    faces = np.asarray(description.faces, np.int64)
    n = np.asarray(description.vertex_normals, np.float64)[faces]
    v = np.asarray(description.vertices, np.float64)[faces]
    g = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    g = g / np.maximum(np.linalg.norm(g, axis=1, keepdims=True), 1e-300)
    flat = np.isnan(n).any(axis=(1, 2))
    return {"shading_normal": np.where(flat[:, None, None], g[:, None, :], n)}


def _is_attribute_texture(x) -> bool:
    return isinstance(x, MeshAttributeTexture)


def _mesh_attributes(description: SceneDescription, materials: list) -> tuple[list, object]:
    """Place the materials' `mesh_attribute` textures among a hit's surface coordinates and
    bake their attributes: `(materials, face_attributes)`, the second `(f, 12 a)` (a block
    of 12 columns per attribute and spectrum kind: `MeshAttributeTexture`) or `None` when no
    material reads an attribute. A triangle whose material reads an attribute its shape does
    not have is an error naming the shape and the attributes it has; other triangles get
    zeros."""
    where = description.source or "scene"
    keys: list[tuple[str, str]] = []
    users: dict[tuple[str, str], set[int]] = {}
    for i, m in enumerate(materials):
        for t in jax.tree.leaves(m, is_leaf=_is_attribute_texture):
            if _is_attribute_texture(t):
                key = (t.attribute, t.spectrum)
                if key not in users:
                    keys.append(key)
                users.setdefault(key, set()).add(i)
    if not keys:
        return materials, None
    block = {key: k for k, key in enumerate(keys)}
    materials = [
        jax.tree.map(
            lambda t: (
                dataclasses.replace(t, block=block[(t.attribute, t.spectrum)])
                if _is_attribute_texture(t)
                else t
            ),
            m,
            is_leaf=_is_attribute_texture,
        )
        for m in materials
    ]
    faces = np.asarray(description.faces, np.int64)
    fm = np.asarray(description.face_material)
    attrs = description.mesh_attributes
    columns = []
    for key in keys:
        name, spectrum = key
        used = np.isin(fm, sorted(users[key]))
        values = _corner_values(attrs.get(name, np.zeros((0, 1))), name, faces)
        bad = used & np.isnan(values).any(axis=(1, 2))
        if bad.any():
            shape = int(np.asarray(description.face_shape)[np.argmax(bad)])
            mine = np.asarray(description.face_shape) == shape
            has = [n for n, a in sorted(attrs.items())
                   if not np.isnan(_corner_values(a, n, faces)[mine]).any()]  # fmt: skip
            raise SceneError(
                f"{where}: shape {description.shape_names[shape]!r} has a material with a "
                f"mesh_attribute texture of {name!r}, which the shape's mesh does not have "
                f"(its attributes: {', '.join(has) or 'none'})."
            )
        try:
            block_values = corner_spectra(np.where(used[:, None, None], values, 0.0), spectrum)
        except ValueError as e:
            raise SceneError(f"{where}: mesh attribute {name!r}: {e}") from None
        columns.append(block_values.reshape(len(faces), ATTRIBUTE_BLOCK))
    return materials, np.concatenate(columns, axis=1)


def _corner_values(values: np.ndarray, name: str, faces: np.ndarray) -> np.ndarray:
    """`(f, 3, d)` values of a mesh attribute at each triangle's corners (a face attribute's
    value at all three; NaN everywhere for an attribute the scene lacks, `(0, d)` rows)."""
    if not len(values):
        return np.full((len(faces), 3, values.shape[-1]), np.nan)
    corners = values[faces] if name.startswith("vertex_") else values[:, None, :]
    return np.broadcast_to(corners, (len(faces), 3, values.shape[-1]))


def face_uvs(description: SceneDescription) -> np.ndarray | None:
    """`(f, 3, 2)` uv at the corners of each triangle from the description's per-vertex uvs
    (`RenderScene.from_triangles(face_uv=...)`), or `None` when no shape has uvs. A triangle
    of a shape without uvs gets (0, 0), (1, 0), (0, 1), whose interpolation is the
    barycentric uv Mitsuba gives such meshes."""
    if description.vertex_uvs is None or not len(description.faces):
        return None
    uv = np.asarray(description.vertex_uvs, np.float64)[np.asarray(description.faces, np.int64)]
    bary = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return np.where(np.isnan(uv).any(axis=(1, 2))[:, None, None], bary, uv)


def _scene_media(description: SceneDescription, where: str) -> dict:
    """The media keywords of `RenderScene.from_triangles`: each medium's `type` names its
    plugin in the `MEDIA` registry, which reads its parameters (`from_properties`)."""
    if not description.media:
        return {}
    media = []
    for m in description.media:
        if m.type not in MEDIA:
            raise SceneError(
                f"{where}: medium {m.name!r} has type {m.type!r}; supported: {sorted(MEDIA)}."
            )
        try:
            media.append(
                MEDIA[m.type].from_properties(m.params, where=f"{where}: medium {m.name!r}")
            )
        except ValueError as e:
            raise SceneError(str(e)) from None
    return {
        "media": media,
        "face_interior": description.face_interior,
        "face_exterior": description.face_exterior,
        "camera_medium": description.camera_medium,
    }
