"""Time to equal error: bidirectional path tracing (`bdpt`) against path tracing (issue 14).

Same machine, same run. Two scenes at `--size` px (default 64), `max_depth` 5:

- `hard`: Mitsuba's Cornell box whose ceiling light sits behind a thin glass panel
  (`thindielectric`) just below it: next-event estimation's shadow rays stop at the glass, so
  the path tracer finds the light only by BSDF samples that pass the panel, while bdpt's light
  subpaths cross it and connect to camera vertices (and to the camera).
- `cornell`: the built-in Cornell box; Mitsuba 3's `path` and `ptracer` (`scalar_spectral`)
  render its XML twin in the same run when `--mitsuba` is given.
- `door` (with `--mlt`): Veach's "door ajar" idea: the built-in Cornell box with a white
  plate (both sides) 10 cm below the ceiling, covering it but for a 10 cm slit along z near the
  right wall: the light lights the room only through that slit, mostly after bounces between
  the ceiling and the plate. `pssmlt` against `bdpt` (and `path`), all with the box filter
  (MLT's film); the reference is `bdpt` at `--ref-spp` (path tracing converges far slower
  there), so a renderer's error includes the reference's own; relMSE's eps is scaled by the
  image's mean squared (the scene is about 1000x darker than the others).

The reference of each scene is our `path` at `--ref-spp` (independent of bdpt). Each renderer
then renders spp = 2, 4, ... with fresh seeds; the wall time (after a warm-up render of the
same spp that compiles) and the relative MSE `mean((x - ref)^2 / (ref^2 + 0.01))` are recorded, and
each renderer's time to reach a common error (bdpt's at the largest spp rendered) is
extrapolated from its largest-spp render with relMSE x time constant (the Monte Carlo rate).
The ratios are printed and written as JSON.

    .venv/bin/python benchmarks/bench_bidirectional.py [--size 64] [--ref-spp 4096]
        [--quick] [--mitsuba] [--mlt] [--only door] [--out bench_bidirectional.json]
"""

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np

from tests.render._mitsuba import cornell_box_xml, rel_mse, render_mitsuba

DEPTH = 5


def _hard_xml(folder: Path, size: int) -> Path:
    """The Cornell box with a thin glass panel 2 cm below its light (the light is the
    rectangle at y = 0.99, |x| <= 0.23, -0.18 <= z <= 0.2 in Mitsuba's `cornell_box()`)."""
    xml = cornell_box_xml(size, size)
    panel = (
        '  <bsdf type="thindielectric" id="panel"/>\n'
        '  <shape type="rectangle" id="glass-panel"><transform name="to_world">'
        '<scale x="0.3" y="0.3" z="1"/><rotate x="1" angle="90"/>'
        '<translate x="0" y="0.97" z="0.01"/></transform><ref id="panel"/></shape>\n'
    )
    path = folder / "cornell_glass_panel.xml"
    path.write_text(xml.replace("</scene>", panel + "</scene>"))
    return path


def _door_json(folder: Path) -> Path:
    """The Cornell box with a white plate at y = 0.9 covering the ceiling but for a slit
    0.5 <= x <= 0.6 (all z), and a front wall closing the compartment: light reaches the
    room only through the slit. Plate and wall are two one-sided diffuse layers 1 mm apart,
    facing both ways (the JSON loader reads a material's `two_sided` as a spectrum)."""
    from importlib import resources

    text = resources.files("radiometria.render").joinpath("data", "cornell_box.json")
    scene = json.loads(text.read_text("utf-8"))
    for x0, x1 in ((-1.0, 0.5), (0.6, 1.0)):
        for y, faces in ((0.9, [[0, 1, 2], [0, 2, 3]]), (0.901, [[0, 2, 1], [0, 3, 2]])):
            scene["shapes"].append({
                "name": f"plate {x0} {y}", "material": "white",
                "vertices": [[x0, y, -1.0], [x1, y, -1.0], [x1, y, 1.0], [x0, y, 1.0]],
                "faces": faces,
            })  # fmt: skip
    # The compartment's front (the box is open towards the camera), facing in and out.
    for z, faces in ((1.0, [[0, 2, 1], [0, 3, 2]]), (1.001, [[0, 1, 2], [0, 2, 3]])):
        scene["shapes"].append({
            "name": f"front {z}", "material": "white",
            "vertices": [[-1.0, 0.9, z], [1.0, 0.9, z], [1.0, 1.0, z], [-1.0, 1.0, z]],
            "faces": faces,
        })  # fmt: skip
    path = folder / "cornell_door.json"
    path.write_text(json.dumps(scene))
    return path


def _ours(scene_name, size, integrator, rfilter=None):
    from radiometria.render import compile_scene, load_scene, render

    scene, camera, scene_filter = compile_scene(load_scene(scene_name), width=size, height=size)
    rfilter = scene_filter if rfilter is None else rfilter

    def run(spp, seed):
        # One step holding exactly the render's paths: bdpt traces every slot of a step (no
        # compaction of inactive padding slots), so a default (larger) batch would time padding;
        # at most 2^18 paths per step (a 4096-spp reference would not fit in memory at once).
        img = render(
            scene, camera=camera, rfilter=rfilter, spp=spp, seed=seed,
            integrator=integrator, progress=False, batch=min(size * size * spp, 2**18),
        )  # fmt: skip
        return np.asarray(img, np.float64)

    return run


def _mitsuba_cornell(size, integrator: str):
    import mitsuba as mi

    mi.set_variant("scalar_spectral")
    xml = cornell_box_xml(size, size).replace('type="path"', f'type="{integrator}"')
    scene = mi.load_string(xml)

    def run(spp, seed):
        return render_mitsuba(scene, spp, seed=seed)

    return run


def _curve(run, spps, reference, seed0, eps=1e-2):
    times, errors = [], []
    for i, spp in enumerate(spps):
        run(spp, seed0 + 1000 + i)  # warm-up: compiles (one program per batch size)
        t0 = time.perf_counter()
        img = run(spp, seed0 + i)
        times.append(time.perf_counter() - t0)
        errors.append(rel_mse(img, reference, eps))
    return times, errors


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--ref-spp", type=int, default=4096)
    parser.add_argument("--quick", action="store_true", help="size 32, reference 1024 spp")
    parser.add_argument("--mitsuba", action="store_true", help="Mitsuba path/ptracer too")
    parser.add_argument("--mlt", action="store_true", help="the door scene: pssmlt vs bdpt")
    parser.add_argument("--only", choices=["hard", "cornell", "door"], help="one scene only")
    parser.add_argument("--out", default="bench_bidirectional.json")
    args = parser.parse_args(argv)
    size, ref_spp = (32, 1024) if args.quick else (args.size, args.ref_spp)
    spps = [2, 4, 8, 16] if args.quick else [4, 8, 16, 32, 64]

    from radiometria.camera import BoxFilter
    from radiometria.render import PSSMLT, Path as PathTracer
    from radiometria.render._integrators import BDPT

    folder = Path(tempfile.mkdtemp(prefix="bench_bidirectional_"))
    scenes = {"hard": str(_hard_xml(folder, size)), "cornell": "cornell-box"}
    if args.mlt or args.only == "door":
        scenes["door"] = str(_door_json(folder))
    if args.only:
        scenes = {args.only: scenes[args.only]}
    results = {}
    for name, scene in scenes.items():
        box = BoxFilter() if name == "door" else None
        path = _ours(scene, size, PathTracer(max_depth=DEPTH), box)
        bdpt = _ours(scene, size, BDPT(max_depth=DEPTH), box)
        t0 = time.perf_counter()
        reference = (bdpt if name == "door" else path)(ref_spp, 10_000)
        which = "bdpt" if name == "door" else "path"
        print(f"[{name}] reference: {which} {ref_spp} spp in {time.perf_counter() - t0:.1f} s")
        runners = {"path": path, "bdpt": bdpt}
        if name == "door":  # chains fixed (one program for every spp): 4 spp mutations each
            mlt = PSSMLT(max_depth=DEPTH, chains=max(1, size * size // 4))
            runners["pssmlt"] = _ours(scene, size, mlt, box)
        if args.mitsuba and name == "cornell":
            for integ in ("path", "ptracer"):
                runners[f"mitsuba {integ}"] = _mitsuba_cornell(size, integ)
        # relMSE's eps is 0.01 for images of order 1; the door scene is about 1000x darker,
        # so its eps is scaled by its mean squared (else eps alone would set the weights).
        eps = 1e-2 * float(np.mean(reference)) ** 2 if name == "door" else 1e-2
        curves = {k: _curve(run, spps, reference, 100, eps) for k, run in runners.items()}
        # The common error: bdpt's at the largest spp. Each renderer's time to reach it is
        # extrapolated from its own largest-spp render by the Monte Carlo rate (relMSE x time
        # constant), which holds where the curves do not overlap (the hard scene).
        target = curves["bdpt"][1][-1]
        row = {"size": size, "spp": spps, "target_rel_mse": target, "renderers": {}}
        for k, (times, errors) in curves.items():
            t = times[-1] * errors[-1] / target
            row["renderers"][k] = {"times_s": times, "rel_mse": errors, "time_at_target_s": t}
            print(f"[{name}] {k:16s} relMSE {[f'{e:.3g}' for e in errors]} "
                  f"time {[f'{x:.2f}' for x in times]} s -> {t:.2f} s at {target:.3g}")  # fmt: skip
        ratio = (
            row["renderers"]["path"]["time_at_target_s"]
            / row["renderers"]["bdpt"]["time_at_target_s"]
        )
        row["path_over_bdpt_time"] = ratio
        print(f"[{name}] time to equal relMSE, path / bdpt = {ratio:.2f}")
        if "pssmlt" in row["renderers"]:
            mlt_ratio = (
                row["renderers"]["bdpt"]["time_at_target_s"]
                / row["renderers"]["pssmlt"]["time_at_target_s"]
            )
            row["bdpt_over_pssmlt_time"] = mlt_ratio
            print(f"[{name}] time to equal relMSE, bdpt / pssmlt = {mlt_ratio:.2f}")
        results[name] = row
    Path(args.out).write_text(json.dumps(results, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
