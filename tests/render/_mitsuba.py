"""Mitsuba 3 references for the render tests and the benchmark (helper P).

`cornell_box_xml()` writes Mitsuba 3's `cornell_box()` scene as a Mitsuba XML file (shapes with
their `to_world` matrices), which both Mitsuba and `radiometria.render.load_scene` read.
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
