"""Scenes of Mitsuba 3's own render test suite, rendered by radiometria and judged against
Mitsuba 3 `scalar_spectral` with the per-pixel z-test (issue 12's "Done means").

Usage:

    python benchmarks/check_mitsuba_test_scenes.py ROOT [--spp 64] [--ref-spp 1024]
        [--size 32] [--only SUBSTRING ...]

`ROOT` is a folder laid out as the `mitsuba-renderer/mitsuba-data` repository: the scenes under
`ROOT/tests/scenes/<dir>/...` (with their `include/`, `fragments/`, `meshes/`, `textures/`) and
the shared assets under `ROOT/common/` (what `<path value="../../../common"/>` names). Nothing
is fetched: put the files there first. The whole `ROOT` is copied to a scratch folder in which
every literal film `width`/`height` is scaled so that the larger side is `--size` pixels (the
aspect ratio kept), and `$res` defaults are set to `--size`; both renderers read that copy.

For each scene: load it with `radiometria.render.load_scene`, render it with radiometria
(`--spp`, XYZ, the scene's own integrator and sampler), render Mitsuba's per-pixel mean and
per-sample variance with the `moment` integrator (`--ref-spp`; a scene whose integrator already
is `moment` is rendered as is, otherwise its integrator is wrapped), and apply
`radiometria.montecarlo.pixel_z_test`. One line of a Markdown table per scene: loads, renders,
the fraction of pixel channels that pass, pass/fail, the times, and the error or the worst pixel.
"""

import argparse
import re
import shutil
import tempfile
import time
import traceback
from pathlib import Path

import numpy as np

SCENES = (
    "floating_sphere/test_directional.xml",
    "floating_sphere/test_directional_direct.xml",
    "spot_light/test_spot.xml",
    "spot_light/test_spot_direct.xml",
    "orthographic_sensor/test_orthographic.xml",
    "texture_interp/test_texture_interp_direct.xml",
    "instancing/test_instancing_path.xml",
    "bsdf_spheres/test_pointlight.xml",
    "bsdf_spheres/test_constant.xml",
    "bsdf_spheres/test_arealight.xml",
    "bsdf_spheres/test_envmap.xml",
    "various_shapes/test_various_shapes_path.xml",
    "participating_media/test_homo_null_envmap.xml",
    "participating_media/test_surf_area_light.xml",
    "participating_media/test_homo_area_light.xml",
)

_SIZE = re.compile(r'(<integer\s+name="(width|height)"\s+value=")(\d+)(")')


def shrink_copy(root: Path, size: int) -> Path:
    """Copy `root` to a scratch folder and scale every literal film size to at most `size`."""
    out = Path(tempfile.mkdtemp(prefix="mitsuba_tests_")) / "root"
    shutil.copytree(root, out)
    for xml in out.rglob("*.xml"):
        text = xml.read_text()
        dims = {m.group(2): int(m.group(3)) for m in _SIZE.finditer(text)}
        if not dims:
            continue
        scale = size / max(dims.values())

        def sub(m, scale=scale):
            return f"{m.group(1)}{max(1, round(int(m.group(3)) * scale))}{m.group(4)}"

        xml.write_text(_SIZE.sub(sub, text))
    return out


def mitsuba_moments(path: Path, spp: int, params: dict, seed: int = 1):
    """Mitsuba's per-pixel mean and per-sample variance in CIE XYZ, `(H, W, 3)` each."""
    import mitsuba as mi

    mi.set_variant("scalar_spectral")
    scene = mi.load_file(str(path), **params)
    integrator = scene.integrator()
    if not integrator.aov_names():  # path, direct, volpath: no AOVs; a `moment` has its own
        integrator = mi.load_dict({"type": "moment", "nested": integrator})
    out = np.asarray(mi.render(scene, integrator=integrator, spp=spp, seed=seed), np.float64)
    if out.shape[-1] != 9:
        raise RuntimeError(f"Mitsuba's moment output has {out.shape[-1]} channels, not 9")
    m1, m2 = out[..., 3:6], out[..., 6:9]
    return m1, np.maximum(m2 - m1 * m1, 0.0)


def check(path: Path, *, spp: int, ref_spp: int, size: int) -> dict:
    from radiometria.montecarlo import pixel_z_test
    from radiometria.render import load_scene, render

    # Mitsuba rejects a parameter no file of the scene uses: pass `res` only where one does.
    uses_res = any("$res" in x.read_text() for x in path.parent.rglob("*.xml"))
    params = {"res": str(size)} if uses_res else {}
    row = {"scene": path.relative_to(path.parents[1]).as_posix(), "loads": "no", "renders": "-"}
    try:
        desc = load_scene(path, params=params)
    except Exception as e:  # noqa: BLE001 - the table reports every failure
        row["note"] = f"{type(e).__name__}: {e}".replace("\n", " ")[:300]
        return row
    row["loads"] = "yes"
    try:
        t0 = time.perf_counter()
        ours = np.asarray(render(desc, spp=spp, seed=0, return_xyz=True, progress=False))
        row["t_ours"] = time.perf_counter() - t0
    except Exception as e:  # noqa: BLE001
        row["renders"] = "no"
        row["note"] = f"{type(e).__name__}: {e}".replace("\n", " ")[:300]
        traceback.print_exc()
        return row
    row["renders"] = "yes"
    try:
        t0 = time.perf_counter()
        mean, var = mitsuba_moments(path, ref_spp, params)
        row["t_ref"] = time.perf_counter() - t0
    except Exception as e:  # noqa: BLE001
        row["note"] = f"Mitsuba failed: {type(e).__name__}: {e}".replace("\n", " ")[:300]
        return row
    if mean.shape != ours.shape:
        row["note"] = f"shape mismatch: ours {ours.shape}, Mitsuba {mean.shape}"
        return row
    result = pixel_z_test(ours.astype(np.float64), mean, var, spp, ref_spp)
    row["fraction"] = result.fraction_passed
    row["passed"] = result.passed
    rel = np.abs(ours.mean((0, 1)) - mean.mean((0, 1))) / np.maximum(mean.mean((0, 1)), 1e-6)
    row["note"] = f"mean XYZ rel. diff {np.array2string(rel, precision=3)}"
    if not result.passed and result.worst:
        idx, a, b, v, p = result.worst[0]
        row["note"] += f"; worst {idx}: ours {a:.4g} ref {b:.4g} var {v:.3g} p {p:.2g}"
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("root", type=Path, help="folder laid out as mitsuba-data")
    parser.add_argument("--spp", type=int, default=64, help="our samples per pixel")
    parser.add_argument("--ref-spp", type=int, default=1024, help="Mitsuba's samples per pixel")
    parser.add_argument("--size", type=int, default=32, help="larger film side [px]")
    parser.add_argument("--only", nargs="*", default=None, help="substrings of scene paths")
    args = parser.parse_args()
    scenes = [s for s in SCENES if not args.only or any(o in s for o in args.only)]
    copy = shrink_copy(args.root, args.size)
    print(f"scratch copy: {copy}; ours {args.spp} spp, Mitsuba {args.ref_spp} spp")
    print("| scene | loads | renders | z-test fraction | passed | ours [s] | Mitsuba [s] | note |")
    print("|---|---|---|---|---|---|---|---|")
    for s in scenes:
        path = copy / "tests" / "scenes" / s
        if not path.exists():
            print(f"| {s} | missing | - | - | - | - | - | not under ROOT/tests/scenes |")
            continue
        r = check(path, spp=args.spp, ref_spp=args.ref_spp, size=args.size)
        frac = f"{r['fraction']:.4f}" if "fraction" in r else "-"
        passed = {True: "yes", False: "NO"}.get(r.get("passed"), "-")
        t1 = f"{r['t_ours']:.1f}" if "t_ours" in r else "-"
        t2 = f"{r['t_ref']:.1f}" if "t_ref" in r else "-"
        cells = (s, r["loads"], r["renders"], frac, passed, t1, t2, r.get("note", ""))
        print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
