"""The measured Cornell box (built-in `cornell-box-measured`) against Mitsuba 3.

The built-in scene's geometry, measured reflectance spectra and light spectrum are written as a
Mitsuba XML file (one OBJ mesh per material, flat facets, spectra as `l:v` pairs) and rendered
by Mitsuba 3 `scalar_spectral`; our render of the built-in scene must pass the per-pixel z-test.
"""

import dataclasses

import numpy as np
import pytest

from radiometria.render import load_scene, render
from radiometria.render._scenes._description import SceneDescription

from ._mitsuba import mitsuba_moments

SIZE = 16


def _spectrum(name: str, s) -> str:
    pairs = ", ".join(
        f"{lam:.6g}:{v:.9g}"
        for lam, v in zip(np.asarray(s.wavelengths_nm), np.asarray(s.values), strict=True)
    )
    return f'<spectrum name="{name}" value="{pairs}"/>'


def _write_obj(path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Each triangle with its own three vertices (Mitsuba's OBJ loader then has nothing to
    smooth across facets)."""
    corners = vertices[faces].reshape(-1, 3)
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in corners]
    lines += [f"f {3 * i + 1} {3 * i + 2} {3 * i + 3}" for i in range(len(faces))]
    path.write_text("\n".join(lines) + "\n")


def measured_cornell_xml(desc: SceneDescription, folder, size: int) -> str:
    """The description as Mitsuba XML (version 3), its meshes written into `folder`."""
    cam = desc.camera
    matrix = " ".join(f"{x:.12g}" for x in np.asarray(cam.to_world).ravel())
    out = [
        '<scene version="3.0.0">',
        f'<integrator type="path"><integer name="max_depth" value="{desc.max_depth}"/>'
        f'<integer name="rr_depth" value="{desc.rr_depth}"/></integrator>',
        f'<sensor type="perspective"><float name="fov" value="{cam.fov_deg}"/>'
        f'<string name="fov_axis" value="{cam.fov_axis}"/>'
        f'<transform name="to_world"><matrix value="{matrix}"/></transform>'
        '<sampler type="independent"/>'
        f'<film type="hdrfilm"><integer name="width" value="{size}"/>'
        f'<integer name="height" value="{size}"/><rfilter type="gaussian"/></film></sensor>',
    ]
    for i, m in enumerate(desc.materials):
        assert m.type == "diffuse" and not m.two_sided
        rho = _spectrum("reflectance", m.params["reflectance"])
        out.append(f'<bsdf type="diffuse" id="m{i}">{rho}</bsdf>')
    groups = [(i, -1) for i in range(len(desc.materials))]
    groups += [(None, e) for e in range(len(desc.emitters))]
    for k, (mat, em) in enumerate(groups):
        if em >= 0:
            sel = desc.face_emitter == em
            mat = int(desc.face_material[sel][0])
        else:
            sel = (desc.face_material == mat) & (desc.face_emitter == -1)
        if not np.any(sel):
            continue
        _write_obj(folder / f"part{k}.obj", desc.vertices, desc.faces[sel])
        emitter = ""
        if em >= 0:
            assert not desc.emitters[em].two_sided
            radiance = _spectrum("radiance", desc.emitters[em].radiance)
            emitter = f'<emitter type="area">{radiance}</emitter>'
        out.append(
            f'<shape type="obj"><string name="filename" value="part{k}.obj"/>'
            f'<boolean name="face_normals" value="true"/><ref id="m{mat}"/>{emitter}</shape>'
        )
    out.append("</scene>")
    return "\n".join(out) + "\n"


@pytest.mark.slow
def test_measured_cornell_box_matches_mitsuba(tmp_path):
    """Our 16 x 16 render of the built-in measured Cornell box (64 spp) against Mitsuba 3's
    of the same geometry and spectra (512 spp, moments): the z-test of Mitsuba's render
    suite passes, and the images' mean luminance agrees within 3 %. With the red and green
    walls' spectra swapped in Mitsuba's file, the z-test fails (it can fail)."""
    from radiometria.montecarlo import pixel_z_test

    desc = load_scene("cornell-box-measured")
    path = tmp_path / "measured.xml"
    path.write_text(measured_cornell_xml(desc, tmp_path, SIZE))
    mean, var = mitsuba_moments(path, 512, seed=1)
    ours = np.asarray(
        render("cornell-box-measured", spp=64, width=SIZE, height=SIZE, return_xyz=True,
               progress=False), np.float64,
    )  # fmt: skip
    res = pixel_z_test(ours, mean, var, 64, 512)
    assert res.passed, res.message
    np.testing.assert_allclose(ours[..., 1].mean(), mean[..., 1].mean(), rtol=0.03)

    names = [m.name for m in desc.materials]
    red, green = names.index("red"), names.index("green")
    swapped = list(desc.materials)
    swapped[red], swapped[green] = swapped[green], swapped[red]
    bad = tmp_path / "swapped.xml"
    bad.write_text(measured_cornell_xml(dataclasses.replace(desc, materials=tuple(swapped)),
                                        tmp_path, SIZE))  # fmt: skip
    mean_bad, var_bad = mitsuba_moments(bad, 512, seed=1)
    assert not pixel_z_test(ours, mean_bad, var_bad, 64, 512).passed
