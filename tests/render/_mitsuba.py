"""Mitsuba 3 references for the render tests and the benchmark (helper P).

`cornell_box_xml()` writes Mitsuba 3's `cornell_box()` scene as a Mitsuba XML file (shapes with
their `to_world` matrices), which both Mitsuba and `radiometria.render.load_scene` read.
`mitsuba_moments` renders a scene with Mitsuba's `moment` integrator (the mean and per-sample
variance of every pixel, in CIE XYZ) and `z_test_against_mitsuba` renders the same file with
`radiometria.render.render` and applies `radiometria.montecarlo.pixel_z_test`, the test of
Mitsuba's own render suite.
"""

import numpy as np

VARIANT = "scalar_spectral"


def mitsuba():
    import mitsuba as mi

    mi.set_variant(VARIANT)
    return mi


def cornell_dict(width: int, height: int, spp: int = 64, variant: str = VARIANT) -> dict:
    import mitsuba as mi

    mi.set_variant(variant)
    d = mi.cornell_box()
    d["sensor"]["film"]["width"] = width
    d["sensor"]["film"]["height"] = height
    d["sensor"]["sampler"]["sample_count"] = spp
    return d


def render_mitsuba(scene_or_dict, spp: int, seed: int = 0) -> np.ndarray:
    """A Mitsuba render as float64 linear sRGB `(H, W, 3)`."""
    import mitsuba as mi

    scene = mi.load_dict(scene_or_dict) if isinstance(scene_or_dict, dict) else scene_or_dict
    return np.asarray(mi.render(scene, spp=spp, seed=seed), np.float64)


def mitsuba_moments(path, spp: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Mitsuba's mean and per-sample variance of every pixel, CIE XYZ `(H, W, 3)` each.

    The scene file's integrator is wrapped in a `moment` integrator, whose outputs are the
    filter-weighted first and second moments of the samples of each pixel (in XYZ, the only
    space in which the moments exist per channel); variance = m2 - m1^2.
    """
    mi = mitsuba()
    scene = mi.load_file(str(path))
    moment = mi.load_dict({"type": "moment", "nested": scene.integrator()})
    out = np.asarray(mi.render(scene, integrator=moment, spp=spp, seed=seed), np.float64)
    assert out.shape[-1] == 9, out.shape  # RGB, nested m1 (XYZ), nested m2 (XYZ)
    m1, m2 = out[..., 3:6], out[..., 6:9]
    return m1, np.maximum(m2 - m1 * m1, 0.0)


def z_test_against_mitsuba(
    path,
    *,
    spp: int,
    ref_spp: int,
    seed: int = 0,
    ref_seed: int = 1,
    ours_path=None,
    renders: int = 1,
    **render_kwargs,
):
    """Render `path` with radiometria (XYZ, independent samples by default) and with Mitsuba
    (`mitsuba_moments`), and return `pixel_z_test(ours, mean, variance, spp, ref_spp)`.
    `ours_path`: render that scene instead against `path`'s reference (negative controls).
    `renders` > 1: that many renders of `spp` samples (seeds `seed`, `seed + 1`, ...) judged by
    the two-sample test with their own per-sample variance, for estimators whose noise is not
    the reference's (light tracing, bidirectional methods)."""
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import render

    mean, var = mitsuba_moments(path, ref_spp, seed=ref_seed)
    render_kwargs.setdefault("progress", False)
    ours_path = path if ours_path is None else ours_path
    ours = np.stack([
        np.asarray(render(ours_path, spp=spp, seed=seed + i, return_xyz=True, **render_kwargs),
                   np.float64)
        for i in range(renders)
    ])  # fmt: skip
    if renders == 1:
        return pixel_z_test(ours[0], mean, var, spp, ref_spp)
    own = ours.var(axis=0, ddof=1) * spp  # per-sample variance of one render's samples
    return pixel_z_test(ours.mean(axis=0), mean, var, spp * renders, ref_spp, image_variance=own)


def film_xml(size: int, spp: int = 16, rfilter: str = "gaussian") -> str:
    """The `<sampler>` (independent, `spp` samples) and `<film>` (`size` x `size` hdrfilm,
    `rfilter`) of a test scene's sensor, on three lines (the sampler on the first)."""
    return (
        f'<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>\n'
        f'    <film type="hdrfilm"><integer name="width" value="{size}"/>\n'
        f'      <integer name="height" value="{size}"/><rfilter type="{rfilter}"/></film>'
    )


def perspective_xml(origin: str, fov: float, size: int, spp: int = 16, rfilter="gaussian") -> str:
    """A `perspective` sensor of horizontal field of view `fov` [deg] at `origin` looking at
    the world origin with +y up, with `film_xml(size, spp, rfilter)`."""
    return f"""<sensor type="perspective">
    <float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="{origin}" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    {film_xml(size, spp, rfilter)}
  </sensor>"""


def floor_and_light_xml(floor_scale: float, radiance: float) -> str:
    """A grey (0.5) diffuse floor at y = -1, `2 floor_scale` wide, lit by a `1.5`-half-width
    rectangle light of `radiance` (RGB grey) facing down from (1, 3, 1.5)."""
    return f"""<shape type="rectangle">
    <transform name="to_world"><scale value="{floor_scale}"/><rotate x="1" angle="-90"/>
      <translate y="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="1.5"/><rotate x="1" angle="90"/>
      <translate x="1" y="3" z="1.5"/></transform>
    <emitter type="area"><rgb name="radiance" value="{radiance}, {radiance}, {radiance}"/></emitter>
  </shape>"""


def _matrix(m) -> str:
    a = np.asarray(m.matrix if hasattr(m, "matrix") else m, np.float64).reshape(4, 4)
    return " ".join(f"{x:.9g}" for x in a.ravel())


def cornell_box_xml(width: int, height: int, spp: int = 64) -> str:
    """Mitsuba 3's `cornell_box()` as Mitsuba XML (version 3.0.0)."""
    d = cornell_dict(width, height, spp)
    lines = ['<scene version="3.0.0">']
    depth = d["integrator"]["max_depth"]
    lines.append(
        f'  <integrator type="path"><integer name="max_depth" value="{depth}"/></integrator>'
    )
    s = d["sensor"]
    lines += [
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{s["fov"]}"/>',
        f'    <string name="fov_axis" value="{s["fov_axis"]}"/>',
        f'    <transform name="to_world"><matrix value="{_matrix(s["to_world"])}"/></transform>',
        f'    <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>',
        '    <film type="hdrfilm">',
        f'      <integer name="width" value="{width}"/><integer name="height" value="{height}"/>',
        '      <rfilter type="gaussian"/>',
        "    </film>",
        "  </sensor>",
    ]
    for name in ("white", "green", "red"):
        rgb = " ".join(map(str, d[name]["reflectance"]["value"]))
        lines.append(
            f'  <bsdf type="diffuse" id="{name}"><rgb name="reflectance" value="{rgb}"/></bsdf>'
        )
    for key, shape in d.items():
        if not isinstance(shape, dict) or shape.get("type") not in ("rectangle", "cube"):
            continue
        lines.append(f'  <shape type="{shape["type"]}" id="{key}">')
        matrix = _matrix(shape["to_world"])
        lines.append(f'    <transform name="to_world"><matrix value="{matrix}"/></transform>')
        lines.append(f'    <ref id="{shape["bsdf"]["id"]}"/>')
        if "emitter" in shape:
            rgb = " ".join(map(str, shape["emitter"]["radiance"]["value"]))
            lines.append(f'    <emitter type="area"><rgb name="radiance" value="{rgb}"/></emitter>')
        lines.append("  </shape>")
    lines.append("</scene>")
    return "\n".join(lines) + "\n"


def rel_mse(image: np.ndarray, reference: np.ndarray, eps: float = 1e-2) -> float:
    """Relative MSE, mean of (x - ref)^2 / (ref^2 + eps) over pixels and channels."""
    return float(np.mean((image - reference) ** 2 / (reference**2 + eps)))


def cornell_box_materials_xml(width: int, height: int, spp: int = 64) -> str:
    """The Cornell box with a mirror back wall (smooth `conductor`), a rough gold tall box
    (`roughconductor`, GGX, alpha 0.2) and a glass short box (`dielectric`, BK7 in air)."""
    extra = (
        '  <bsdf type="conductor" id="mirror"/>\n'
        '  <bsdf type="roughconductor" id="gold"><string name="material" value="Au"/>'
        '<string name="distribution" value="ggx"/><float name="alpha" value="0.2"/></bsdf>\n'
        '  <bsdf type="dielectric" id="glass"/>\n'
    )
    which = {"back": "mirror", "large-box": "gold", "small-box": "glass"}
    out, current = [], None
    for line in cornell_box_xml(width, height, spp).splitlines():
        if "<shape" in line:
            current = next((m for shape, m in which.items() if f'id="{shape}"' in line), None)
        if current and '<ref id="white"/>' in line:
            line = line.replace('"white"', f'"{current}"')
        if '<bsdf type="diffuse" id="white">' in line:
            out.append(extra.rstrip("\n"))
        out.append(line)
    return "\n".join(out) + "\n"


def projected_image_scene(path, emitter: str, integrator: str = "direct"):
    """Write to `path` a 16 x 16 scene (box filter) of a grey diffuse wall at z = 1 seen from
    the origin, lit by `emitter` (an `<emitter>` element: a spot or projector casting an
    image), and return `path`."""
    path.write_text(f"""<scene version="3.0.0">
  {integrator}
  <sensor type="perspective"><float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/>
    </transform>
    {film_xml(16, 16, "box")}
  </sensor>
  {emitter}
  <shape type="rectangle">
    <transform name="to_world"><scale value="3"/><rotate y="1" angle="180"/>
      <translate z="1"/></transform>
    <bsdf type="diffuse"><spectrum name="reflectance" value="0.8"/></bsdf>
  </shape>
</scene>""")
    return path


def delta_light_values(emitter, ours, n: int = 96, seed: int = 1):
    """Mitsuba's `emitter.sample_direction` (scalar_spectral; intensity / distance^2 of a delta
    light) and our light's `sample_li` `radiance` towards `n` random points on the plane
    z = 3 (x in [-1.5, 2.5], y in [-1, 2]), at 430, 510, 570 and 640 nm: `(mitsuba, ours)`,
    each `(n, 4)`."""
    import drjit as dr
    import jax.numpy as jnp
    import mitsuba as mi

    rng = np.random.default_rng(seed)
    pts = np.column_stack([rng.uniform(-1.5, 2.5, n), rng.uniform(-1.0, 2.0, n),
                           np.full(n, 3.0)])  # fmt: skip
    wl = np.array([430.0, 510.0, 570.0, 640.0])
    expected = []
    for p in pts:
        it = dr.zeros(mi.Interaction3f)
        it.p = mi.Point3f(*map(float, p))
        it.wavelengths = mi.Spectrum(wl)
        _, spec = emitter.sample_direction(it, mi.Point2f(0, 0))
        expected.append(np.array(spec, np.float64))
    ls = ours.sample_li(
        jnp.asarray(pts, jnp.float32), jnp.zeros(n, jnp.float32), jnp.zeros((n, 2), jnp.float32),
        jnp.asarray(np.tile(wl, (n, 1)), jnp.float32),
    )  # fmt: skip
    return np.asarray(expected), np.asarray(ls.radiance, np.float64)
