"""Time to equal error on two media scenes: radiometria's `volpath` against Mitsuba 3's.

Same machine, same run, same Mitsuba XML files read by both renderers:

- `homogeneous`: a scattering, chromatic-albedo medium (HG g = 0.5) in a `null` sphere and an
  absorbing chromatic (RGB sigma_t) medium in a `dielectric` sphere, lit by a large area light;
- `heterogeneous`: a `.vol` density ramp (written here) in a `null` cube, lit the same way.

One high-spp Mitsuba `scalar_spectral` image of each scene is the reference (cached in
`--cache`). Each renderer then renders spp = 4, 8, ... with fresh seeds; for each image the
wall time (after a warm-up render that compiles) and the relative MSE against the reference,
`mean((x - ref)^2 / (ref^2 + 0.01))`, are recorded, and log-log interpolation gives each
renderer's time to reach Mitsuba `scalar_spectral`'s error at `--target-spp`. Renderers:
radiometria (the scene's `volpath`, independent sampler), Mitsuba 3 `scalar_spectral` and,
when libLLVM is found, `llvm_ad_spectral`. The helpers (timing, interpolation, relMSE, libLLVM
lookup) are `bench_render.py`'s.

    .venv/bin/python benchmarks/bench_media.py [--size 256] [--ref-spp 1024] [--quick]
        [--scenes homogeneous heterogeneous] [--no-llvm]

The default size is `bench_render.py`'s (256 x 256), so that the ratios compare with the
surface scenes'. At 64 x 64 Mitsuba reaches the target error in 0.04 s, and the fixed cost of
a call (dispatch, the film's development, the copy to the host) weighs on the ratio: the
homogeneous scene measured 0.34x there and 1.17x at 256 x 256, with the same code.
"""

import argparse
import json
import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import numpy as np  # noqa: E402
from bench_render import LLVM_CANDIDATES, _time_at_error, _timed  # noqa: E402 (sets XLA_FLAGS)

from tests.render._mitsuba import rel_mse, render_mitsuba  # noqa: E402

HEAD = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="35"/>
    <transform name="to_world"><lookat origin="0, 0, 6" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    <film type="hdrfilm"><integer name="width" value="{size}"/>
      <integer name="height" value="{size}"/><rfilter type="box"/></film>
  </sensor>
  <integrator type="volpath"><integer name="max_depth" value="16"/></integrator>
  <shape type="rectangle"><transform name="to_world"><scale value="8"/><translate z="-3"/>
    </transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="90"/>
    <translate y="3"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/>
    </bsdf><emitter type="area"><rgb name="radiance" value="3, 3, 3"/></emitter></shape>
"""
SCENES = {
    "homogeneous": HEAD
    + """
  <medium type="homogeneous" id="fog"><float name="sigma_t" value="2"/>
    <rgb name="albedo" value="0.95, 0.8, 0.6"/><phase type="hg"><float name="g" value="0.5"/>
    </phase></medium>
  <shape type="sphere"><float name="radius" value="0.9"/><point name="center" x="-1" y="0" z="0"/>
    <bsdf type="null"/><ref name="interior" id="fog"/></shape>
  <medium type="homogeneous" id="tint"><rgb name="sigma_t" value="0.2, 0.5, 1.0"/>
    <float name="scale" value="3"/><float name="albedo" value="0.8"/></medium>
  <shape type="sphere"><float name="radius" value="0.9"/><point name="center" x="1" y="0" z="0"/>
    <bsdf type="dielectric"/><ref name="interior" id="tint"/></shape>
</scene>
""",
    "heterogeneous": HEAD
    + """
  <medium type="heterogeneous" id="grid"><volume name="sigma_t" type="gridvolume">
    <string name="filename" value="{vol}"/><transform name="to_world"><scale value="2.4"/>
    <translate value="-1.2, -1.2, -1.2"/></transform></volume><float name="scale" value="2"/>
    <rgb name="albedo" value="0.9, 0.7, 0.5"/></medium>
  <shape type="cube"><transform name="to_world"><scale value="1.2"/></transform>
    <bsdf type="null"/><ref name="interior" id="grid"/></shape>
</scene>
""",
}


def _write_scenes(cache: Path, size: int) -> dict[str, Path]:
    from radiometria.render._scenes._volume_files import write_vol

    vol = cache / "ramp.vol"
    z, y, x = np.meshgrid(*[(np.arange(n) + 0.5) / n for n in (16, 16, 16)], indexing="ij")
    write_vol(vol, 0.1 + 2.0 * x * (1.2 - y) * (0.5 + z))
    out = {}
    for name, text in SCENES.items():
        out[name] = cache / f"{name}_{size}.xml"
        out[name].write_text(text.format(size=size, vol=vol))
    return out


def _ours(path):
    from radiometria.render import load_scene, render

    desc = load_scene(path)

    def run(spp, seed):
        return np.asarray(render(desc, spp=spp, seed=seed, progress=False), np.float64)

    return run


def _mitsuba(path, variant):
    import mitsuba as mi

    mi.set_variant(variant)
    scene = mi.load_file(str(path))

    def run(spp, seed):
        mi.set_variant(variant)
        return render_mitsuba(scene, spp, seed=seed)

    return run


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--ref-spp", type=int, default=1024)
    parser.add_argument("--spps", type=int, nargs="+", default=[4, 8, 16, 32, 64])
    parser.add_argument("--target-spp", type=int, default=16, help="Mitsuba spp of the target")
    parser.add_argument("--cache", type=Path, default=ROOT / "out" / "bench_media")
    parser.add_argument("--quick", action="store_true", help="32 x 32, reference 512 spp")
    parser.add_argument("--scenes", nargs="+", choices=sorted(SCENES), default=sorted(SCENES))
    parser.add_argument("--no-llvm", action="store_true", help="skip llvm_ad_spectral")
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.ref_spp, args.spps = 32, 512, [4, 8, 16, 32]
    args.cache.mkdir(parents=True, exist_ok=True)

    import jax

    print(f"devices: {jax.devices()}; cores: {os.cpu_count()}")
    llvm = os.environ.get("DRJIT_LIBLLVM_PATH") or next(
        (p for p in LLVM_CANDIDATES if Path(p).exists()), None
    )
    record = {"size": args.size, "ref_spp": args.ref_spp, "scenes": {}}
    for scene, path in _write_scenes(args.cache, args.size).items():
        if scene not in args.scenes:
            continue
        ref_path = args.cache / f"mitsuba_ref_{scene}_{args.size}_{args.ref_spp}.npy"
        if ref_path.exists():
            reference = np.load(ref_path)
        else:
            print(f"[{scene}] reference: Mitsuba scalar_spectral, {args.ref_spp} spp ...")
            mitsuba = _mitsuba(path, "scalar_spectral")
            reference, t = _timed(lambda m=mitsuba: m(args.ref_spp, 12345))
            np.save(ref_path, reference)
            print(f"  {t:.1f} s")
        renderers = {
            "radiometria volpath": _ours(path),
            "mitsuba scalar_spectral": _mitsuba(path, "scalar_spectral"),
        }
        if llvm and not args.no_llvm:
            os.environ["DRJIT_LIBLLVM_PATH"] = llvm
            try:
                renderers["mitsuba llvm_ad_spectral"] = _mitsuba(path, "llvm_ad_spectral")
            except Exception as err:  # noqa: BLE001 (libLLVM present but unusable: go on)
                print(f"llvm_ad_spectral unavailable: {err}")
        results = {}
        for name, run in renderers.items():
            run(args.spps[0], 1)  # warm-up: compiles radiometria's step, Mitsuba's kernels
            rows = []
            for i, spp in enumerate(args.spps):
                img, t = _timed(lambda run=run, spp=spp, i=i: run(spp, 100 + i))
                rows.append({"spp": spp, "seconds": t, "rel_mse": rel_mse(img, reference),
                             "mean_rgb": img.mean(axis=(0, 1)).tolist()})  # fmt: skip
                print(f"[{scene}] {name:26s} spp {spp:4d} {t:7.2f} s  "
                      f"relMSE {rows[-1]['rel_mse']:.3e}")  # fmt: skip
            results[name] = rows
        base = "mitsuba scalar_spectral"
        target = next(r["rel_mse"] for r in results[base] if r["spp"] == args.target_spp)
        print(
            f"[{scene}] common error: relMSE {target:.3e} (scalar_spectral, {args.target_spp} spp)"
        )
        summary = {
            name: _time_at_error([r["seconds"] for r in rows], [r["rel_mse"] for r in rows], target)
            for name, rows in results.items()
        }
        for name, t in summary.items():
            print(f"[{scene}]   {name:26s} {t:7.2f} s to equal error   "
                  f"speed-up vs scalar_spectral {summary[base] / t:5.2f}x")  # fmt: skip
        ours = np.asarray(results["radiometria volpath"][-1]["mean_rgb"])
        print(f"[{scene}] mean RGB: reference {reference.mean(axis=(0, 1))}, radiometria "
              f"({args.spps[-1]} spp) {ours}")  # fmt: skip
        record["scenes"][scene] = {"target": target, "results": results, "time_to_target": summary}
    out = args.cache / f"bench_media_{args.size}.json"
    out.write_text(json.dumps(record, indent=1))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
