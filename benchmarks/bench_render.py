"""Time to equal error: radiometria's spectral path tracer against Mitsuba 3 on the same scene.

Same machine, same run. `--scene cornell` (default): the Cornell box (Mitsuba 3's
`cornell_box()`, radiometria's `cornell-box`) at 256 x 256 px, spectral, `max_depth` 8,
Gaussian film. One high-spp Mitsuba `scalar_spectral` image is the reference (cached in
`--cache`). Each renderer then renders spp = 4, 8, ..., 64 with fresh seeds; for each image the
wall time (after a warm-up render that compiles) and the relative MSE against the reference,
`mean((x - ref)^2 / (ref^2 + 0.01))`, are recorded. Log-log interpolation gives each renderer's
time to reach a common error (by default Mitsuba `scalar_spectral`'s error at 16 spp); the
ratios are printed and written as JSON.

Renderers: radiometria with the independent and the (padded Owen-scrambled) Sobol sampler,
Mitsuba 3 `scalar_spectral`, and Mitsuba 3 `llvm_ad_spectral` when libLLVM is found
(`apt-get install -y libllvm19`; set `DRJIT_LIBLLVM_PATH`). Every renderer uses all cores:
XLA is given one CPU device per core (`--xla_force_host_platform_device_count`, set before JAX
is imported, with the command line's other XLA flags: `radiometria.cli.cpu_xla_flags`) and
radiometria shards the pixels over them; Mitsuba uses its thread pool.

    .venv/bin/python benchmarks/bench_render.py [--scene cornell|textured|envmap]
        [--size 256] [--ref-spp 1024] [--quick] [--repeats 3]

`--scene textured`: a Mitsuba XML scene (written into `--cache` with its assets) of a floor
with an sRGB PNG `bitmap` texture (bilinear, repeated), a `checkerboard` sphere, a rough
plastic box and a rectangle light. `--scene envmap`: a diffuse sphere, a rough conductor
sphere and a floor under an equirectangular OpenEXR environment map (importance sampled by
both), no other light. Both renderers load the same file (`load_scene`, `mi.load_file`); the
integrator is the file's (`path`, `max_depth` 8).

For the Cornell box the script also renders the scene from a Mitsuba XML file with both
renderers and prints the per-channel means.
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radiometria.cli import cpu_xla_flags  # noqa: E402 (imports no JAX)

if "jax" not in sys.modules:  # the command line's XLA_FLAGS: one CPU device per core, so the
    # render is sharded over them, and XLA:CPU's small-loop threshold (`cpu_xla_flags`)
    os.environ["XLA_FLAGS"] = cpu_xla_flags(os.environ.get("XLA_FLAGS", ""), os.cpu_count() or 1)

import numpy as np

from tests.render._mitsuba import cornell_box_xml, cornell_dict, rel_mse, render_mitsuba

LLVM_CANDIDATES = ("/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/llvm-19/lib/libLLVM.so")


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _time_at_error(times, errors, target):
    """Log-log interpolation (or extrapolation from the two nearest points) of time vs error."""
    le, lt = np.log(np.asarray(errors)), np.log(np.asarray(times))
    order = np.argsort(le)
    le, lt = le[order], lt[order]
    x = np.log(target)
    i = int(np.clip(np.searchsorted(le, x), 1, len(le) - 1))
    slope = (lt[i] - lt[i - 1]) / (le[i] - le[i - 1])
    return float(np.exp(lt[i - 1] + slope * (x - le[i - 1])))


_SENSOR = """<sensor type="perspective"><float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="{origin}" target="0, 0.3, 0" up="0, 1, 0"/>
    </transform><sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{size}"/>
      <integer name="height" value="{size}"/></film></sensor>"""

_FLOOR = """<shape type="rectangle"><transform name="to_world"><scale value="4"/>
    <rotate x="1" angle="-90"/></transform>{bsdf}</shape>"""


def _textured_xml(folder: Path, size: int) -> Path:
    """The textured benchmark scene and its PNG texture (a smooth colour field with edges)."""
    from PIL import Image

    y, x = np.mgrid[0:256, 0:256] / 256.0
    rgb = np.stack([0.5 + 0.4 * np.sin(12 * x), 0.5 + 0.4 * np.cos(9 * y), (x + y) / 2], -1)
    rgb[(np.floor(8 * x) + np.floor(8 * y)) % 2 == 0] *= 0.6
    Image.fromarray(np.uint8(255 * np.clip(rgb, 0, 1))).save(folder / "bench_texture.png")
    floor = _FLOOR.format(
        bsdf="""<bsdf type="diffuse"><texture type="bitmap" name="reflectance">
      <string name="filename" value="bench_texture.png"/>
      <transform name="to_uv"><scale value="3"/></transform></texture></bsdf>"""
    )
    xml = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  {_SENSOR.format(fov=45, origin="0, 2.2, 4.5", size=size)}
  {floor}
  <shape type="sphere"><point name="center" value="-0.8, 0.6, 0"/><float name="radius" value="0.6"/>
    <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
      <rgb name="color0" value="0.8, 0.2, 0.1"/><rgb name="color1" value="0.9, 0.9, 0.8"/>
      <transform name="to_uv"><scale x="8" y="4"/></transform></texture></bsdf></shape>
  <shape type="cube"><transform name="to_world"><scale value="0.45"/><rotate y="1" angle="30"/>
      <translate x="0.8" y="0.45" z="0.2"/></transform>
    <bsdf type="roughplastic"><rgb name="diffuse_reflectance" value="0.1, 0.3, 0.7"/>
      <float name="alpha" value="0.2"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="0.8"/>
      <rotate x="1" angle="90"/><translate y="3.5" z="1"/></transform>
    <emitter type="area"><rgb name="radiance" value="12, 11, 10"/></emitter></shape>
</scene>
"""
    path = folder / f"bench_textured_{size}.xml"
    path.write_text(xml)
    return path


def _envmap_xml(folder: Path, size: int) -> Path:
    """The environment-map benchmark scene and its EXR sky (a sun-like blob on a gradient)."""
    from radiometria.camera import write_exr

    h, w = 128, 256
    v, u = (np.mgrid[0:h, 0:w] + 0.5) / np.array([h, w])[:, None, None]
    sky = np.stack([0.3 + 0.5 * (1 - v), 0.4 + 0.5 * (1 - v), 0.6 + 0.6 * (1 - v)], -1)
    sky[v > 0.5] = [0.25, 0.2, 0.15]  # the ground below the horizon
    sun = np.exp(-(((u - 0.3) / 0.02) ** 2 + ((v - 0.25) / 0.02) ** 2))
    sky += 200.0 * sun[..., None] * np.array([1.0, 0.9, 0.7])
    write_exr(folder / "bench_sky.exr", sky)
    floor = _FLOOR.format(
        bsdf='<bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>'
    )
    xml = f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="8"/></integrator>
  {_SENSOR.format(fov=45, origin="0, 1.5, 4.5", size=size)}
  <emitter type="envmap"><string name="filename" value="bench_sky.exr"/></emitter>
  {floor}
  <shape type="sphere"><point name="center" value="-0.7, 0.6, 0"/><float name="radius" value="0.6"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.3, 0.2"/></bsdf></shape>
  <shape type="sphere"><point name="center" value="0.7, 0.6, 0"/><float name="radius" value="0.6"/>
    <bsdf type="roughconductor"><string name="material" value="Cu"/>
      <float name="alpha" value="0.15"/></bsdf></shape>
</scene>
"""
    path = folder / f"bench_envmap_{size}.xml"
    path.write_text(xml)
    return path


def _ours(size, sampler, xml=None):
    from radiometria.render import (
        Path as PathTracer,
        compile_scene,
        load_scene,
        render,
        scene_integrator,
    )

    description = load_scene("cornell-box" if xml is None else xml)
    scene, camera, rfilter = compile_scene(description, width=size, height=size)
    integrator = PathTracer(max_depth=8) if xml is None else scene_integrator(description)

    def run(spp, seed):
        img = render(
            scene, camera=camera, rfilter=rfilter, spp=spp, seed=seed,
            integrator=integrator, sampler=sampler, progress=False,
        )  # fmt: skip
        return np.asarray(img, np.float64)

    return run


def _mitsuba(size, variant, xml=None):
    import mitsuba as mi

    mi.set_variant(variant)
    if xml is None:
        scene = mi.load_dict(cornell_dict(size, size, variant=variant))
    else:
        scene = mi.load_file(str(xml))

    def run(spp, seed):
        mi.set_variant(variant)
        return render_mitsuba(scene, spp, seed=seed)

    return run


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", choices=["cornell", "textured", "envmap"], default="cornell")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--ref-spp", type=int, default=1024)
    parser.add_argument("--spps", type=int, nargs="+", default=[4, 8, 16, 32, 64])
    parser.add_argument("--target-spp", type=int, default=16, help="Mitsuba spp of the target")
    parser.add_argument("--cache", type=Path, default=ROOT / "out" / "bench_render")
    parser.add_argument("--quick", action="store_true", help="64 x 64, reference 256 spp")
    parser.add_argument(
        "--repeats", type=int, default=3,
        help="rounds of timings (each renderer in turn per round); the median is reported",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.ref_spp, args.spps = 64, 256, [4, 8, 16, 32]
    args.cache.mkdir(parents=True, exist_ok=True)

    import jax

    from radiometria.render import Independent, OwenSobol

    print(f"devices: {jax.devices()}; cores: {os.cpu_count()}; scene: {args.scene}")
    xml = {"cornell": lambda *a: None, "textured": _textured_xml, "envmap": _envmap_xml}[
        args.scene
    ](args.cache, args.size)
    tag = "" if xml is None else f"{args.scene}_"
    ref_path = args.cache / f"mitsuba_ref_{tag}{args.size}_{args.ref_spp}.npy"
    if ref_path.exists():
        reference = np.load(ref_path)
    else:
        print(f"reference: Mitsuba scalar_spectral, {args.size}^2 px, {args.ref_spp} spp ...")
        reference, t = _timed(
            lambda: _mitsuba(args.size, "scalar_spectral", xml)(args.ref_spp, 12345)
        )
        np.save(ref_path, reference)
        print(f"  {t:.1f} s")

    renderers = {
        "radiometria (independent)": _ours(args.size, Independent(), xml),
        "radiometria (sobol)": _ours(args.size, OwenSobol(), xml),
        "mitsuba scalar_spectral": _mitsuba(args.size, "scalar_spectral", xml),
    }
    llvm = os.environ.get("DRJIT_LIBLLVM_PATH") or next(
        (p for p in LLVM_CANDIDATES if Path(p).exists()), None
    )
    if llvm:
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm
        try:
            renderers["mitsuba llvm_ad_spectral"] = _mitsuba(args.size, "llvm_ad_spectral", xml)
        except Exception as err:  # noqa: BLE001 (libLLVM present but unusable: report and go on)
            print(f"llvm_ad_spectral unavailable: {err}")

    # Timings on a shared 2-core machine vary by 20-25 % from one run to the next, for both
    # renderers alike: each round times every renderer in turn, and the median of the rounds
    # is reported (the errors are those of the first round's images, seeds 100 + i).
    for run in renderers.values():
        run(args.spps[0], 1)  # warm-up: compiles radiometria's step, Mitsuba's kernels
    results = {name: [] for name in renderers}
    times = {name: [[] for _ in args.spps] for name in renderers}
    for round_ in range(max(1, args.repeats)):
        for name, run in renderers.items():
            for i, spp in enumerate(args.spps):
                img, t = _timed(lambda run=run, spp=spp, i=i: run(spp, 100 + i))
                times[name][i].append(t)
                if round_ == 0:
                    results[name].append({"spp": spp, "rel_mse": rel_mse(img, reference),
                                          "mean_rgb": img.mean(axis=(0, 1)).tolist()})  # fmt: skip
    for name, rows in results.items():
        for row, ts in zip(rows, times[name], strict=True):
            row["seconds"], row["seconds_all"] = float(np.median(ts)), ts
            spread = f"({min(ts):.2f}-{max(ts):.2f})"
            print(f"{name:28s} spp {row['spp']:4d}  {row['seconds']:7.2f} s {spread:13s} "
                  f"relMSE {row['rel_mse']:.3e}")  # fmt: skip

    base = "mitsuba scalar_spectral"
    target = next(r["rel_mse"] for r in results[base] if r["spp"] == args.target_spp)
    print(f"\ncommon error: relMSE {target:.3e} (Mitsuba scalar_spectral at {args.target_spp} spp)")
    summary = {}
    for name, rows in results.items():
        t = _time_at_error([r["seconds"] for r in rows], [r["rel_mse"] for r in rows], target)
        summary[name] = t
    for name, t in summary.items():
        ratio = summary[base] / t
        print(f"  {name:28s} {t:7.2f} s to equal error   speed-up vs scalar_spectral {ratio:5.2f}x")
    ref_mean = reference.mean(axis=(0, 1))
    ours_mean = np.asarray(results["radiometria (sobol)"][-1]["mean_rgb"])
    print(f"\nmean RGB: reference {ref_mean}, radiometria (sobol, {args.spps[-1]} spp) {ours_mean}"
          f", ratio {ours_mean / ref_mean}")  # fmt: skip

    out = args.cache / f"bench_render_{tag}{args.size}.json"
    record = {"scene": args.scene, "size": args.size, "ref_spp": args.ref_spp, "target": target}
    record.update(results=results, time_to_target=summary)
    if xml is not None:
        out.write_text(json.dumps(record, indent=1))
        print(f"wrote {out}")
        return 0

    # The same scene from a Mitsuba XML file, through both renderers.
    import mitsuba as mi

    from radiometria.render import OwenSobol, render

    xml = args.cache / "cornell_box.xml"
    xml.write_text(cornell_box_xml(args.size, args.size))
    mi.set_variant("scalar_spectral")
    theirs = render_mitsuba(mi.load_file(str(xml)), 64, seed=7)
    ours = np.asarray(render(xml, spp=64, sampler=OwenSobol(), progress=False), np.float64)
    print(f"XML scene, 64 spp: Mitsuba mean {theirs.mean(axis=(0, 1))}, radiometria mean "
          f"{ours.mean(axis=(0, 1))}")  # fmt: skip

    out.write_text(json.dumps(record, indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
