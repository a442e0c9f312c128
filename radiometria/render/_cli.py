"""`radiometria render` and the render half of `radiometria demo`.

Everything a user can get wrong is checked before any rendering starts: the sample count, the
image size, the depth, the output format (by extension: `.exr` is linear sRGB with float32
channels R, G, B; `.png` is 8-bit sRGB-encoded) and whether the output can be written.
`--spectral`, or an output named `*.spectral.exr`, writes the film's spectral radiance as well,
in the OpenEXR layout of Fichet et al. (2021) (`radiometria.camera.write_spectral_exr`).
"""

import argparse
import importlib.metadata
import sys
from pathlib import Path

from .._timing import mark, timing_enabled
from .._warmstart import (
    DEFAULT_SPP,
    MAX_IMAGE_SIDE as MAX_IMAGE_SIDE,
    check_int as _check_int,
    check_output as _check_output,
    parse_defines as _defines,
    recording_opened_files,
    render_settings,
    save_entry,
    with_scene_defaults,
)
from ..camera import write_exr, write_png, write_spectral_exr
from ._cache import (
    checks_without_callbacks,
    clear_compilation_cache,
    compilation_cache_dir,
    compilation_cache_disabled,
    compilation_cache_info,
    jax_activity,
)
from ._checkpoint import save_checkpoint as save_checkpoint  # the warm start's checkpoints
from ._driver import RenderInterrupted, render
from ._integrators import AbstractIntegrator
from ._registry import SAMPLERS
from ._scenes import compile_scene, load_scene, scene_integrator, scene_sampler

__all__ = [
    "MAX_IMAGE_SIDE",
    "cache_clear_command",
    "cache_info_command",
    "demo_render",
    "render_command",
]

SPECTRAL_BINS = 47  # --spectral: 10 nm bins over [360, 830] nm


def _write(path: Path, rgb, metadata: dict) -> Path:
    if isinstance(rgb, tuple):  # a spectral render: (image, spectral, wavelengths_nm)
        image, spectral, wavelengths_nm = rgb
        meta = {**metadata, "spectral_bins": int(spectral.shape[-1])}
        return write_spectral_exr(path, spectral, wavelengths_nm, rgb=image, metadata=meta)
    if path.suffix.lower() == ".exr":
        return write_exr(path, rgb, metadata)
    return write_png(path, rgb)


def _integrator(description, name: str | None, max_depth: int | None) -> AbstractIntegrator:
    """The integrator of `--integrator` (default: the scene's), with `--max-depth` applied."""
    try:
        return scene_integrator(description, name=name, max_depth=max_depth)
    except ValueError as e:
        msg = str(e)
        if msg.startswith(("integrator ", "max_depth ")):  # name the flag the user typed
            msg = "--" + msg.replace("max_depth", "max-depth", 1)
        raise ValueError(msg) from None


def _render_to(
    scene_name: str,
    *,
    spp,
    width,
    height,
    seed,
    max_depth,
    integrator=None,
    sampler=None,
    progress=True,
    defines=None,
    step_cache=None,
    resolved=None,
    **long_render,
):
    """Render a scene as the command line does; `long_render` are `render`'s checkpoint and
    preview arguments, `defines` the `-D name=value` parameters of an XML scene, `step_cache`
    `(directory, request)` to write the render's step entry (`radiometria._warmstart`).
    `spp` and `seed` may be `None`: the scene file's sampler sets them (else 64 and 0), and
    `resolved` (a dict), when given, receives the file's values as `{"spp", "seed"}`."""
    if sampler is not None and sampler not in SAMPLERS:
        raise ValueError(f"--sampler must be one of {sorted(SAMPLERS)}, got {sampler!r}.")
    params = _defines(defines)
    if params and not str(scene_name).lower().endswith(".xml"):
        raise ValueError(
            f"-D {next(iter(params))}=... sets a Mitsuba XML <default>; {str(scene_name)!r} "
            "is not an .xml scene."
        )
    if timing_enabled():
        jax_activity.start()
        mark("command checked" + jax_activity.summary())
    with recording_opened_files() as read:  # what the scene reads: the step entry checks it
        description = load_scene(scene_name, params=params or None)
        mark("scene loaded" + jax_activity.summary())
        chosen = _integrator(description, integrator, max_depth)
        # --sampler, else the file's sampler, else the one with the lowest error per unit time.
        chosen_sampler = (
            scene_sampler(description, default="sobol") if sampler is None else SAMPLERS[sampler]()
        )
        # Compiled here rather than in `render`, as `render` would (the loader has checked the
        # values: no host callbacks, `_cache.py`), so that the timing sees the phase.
        with checks_without_callbacks():
            scene, camera, rfilter = compile_scene(description, width=width, height=height)
    mark("scene compiled" + jax_activity.summary())
    # The scene's sampler sets what the command line leaves open (--spp, --seed).
    file_defaults = {"spp": description.spp, "seed": description.seed}
    if resolved is not None:
        resolved.update(file_defaults)
    spp = int(spp if spp is not None else description.spp or DEFAULT_SPP)
    seed = int(seed if seed is not None else description.seed or 0)
    metadata = {
        "software": f"radiometria {importlib.metadata.version('radiometria')}",
        "scene": str(scene_name),
        "spp": int(spp),
        "seed": int(seed),
        "integrator": chosen.NAME,
        "sampler": chosen_sampler.NAME,
        "colorspace": "linear sRGB (Rec. 709 primaries, D65)",
    }
    if max_depth is not None:
        metadata["max_depth"] = int(max_depth)
    if step_cache is not None:
        directory, request = step_cache

        def save(*, meta, **entry):
            save_entry(
                directory, request, meta={**meta, "metadata": metadata,
                "scene_defaults": file_defaults}, dependencies=read, **entry,
            )  # fmt: skip

        long_render["_step_cache"] = save
    rgb = render(
        scene,
        camera=camera,
        rfilter=rfilter,
        spp=spp,
        seed=seed,
        integrator=chosen,
        sampler=chosen_sampler,
        progress=progress,
        **long_render,
    )
    mark("rendered" + jax_activity.summary())
    return rgb, metadata


def render_command(args: argparse.Namespace, *, step_cache=None) -> int:
    """Run `radiometria render SCENE --spp N --out FILE [...]`; return the exit status.

    Bad arguments raise `ValueError`, `TypeError` or `OSError` (the command turns them into
    exit status 2 with the message) before anything is rendered. Long renders write a
    checkpoint (`--checkpoint`, default `OUT.checkpoint.npz`) every `--checkpoint-every`
    seconds; `--resume` continues from it, bit for bit. SIGINT or SIGTERM stop after the step
    in flight: the checkpoint and the partial image (EXR metadata `spp_reached`) are written,
    and the command exits with 130 or 143 without a traceback.
    """
    opts = render_settings(args)
    out, spectral, checkpoint = opts.out, opts.spectral, opts.checkpoint
    extra = {"spectral_bins": SPECTRAL_BINS} if spectral else {}
    file_defaults: dict = {}  # the scene's sampler: spp and seed where the options leave them

    def settings():
        o = with_scene_defaults(opts, file_defaults)
        return dict(scene=str(args.scene), spp=o.spp, seed=o.seed)

    def preview(rgb, spp_reached):
        _write(out, rgb, {**settings(), "spp_reached": int(spp_reached)})

    try:
        rgb, metadata = _render_to(
            args.scene,
            spp=opts.spp,
            width=opts.width,
            height=opts.height,
            seed=opts.seed,
            resolved=file_defaults,
            max_depth=opts.max_depth,
            integrator=args.integrator,
            sampler=args.sampler,
            defines=getattr(args, "define", None),
            step_cache=step_cache,
            checkpoint=None if spectral else checkpoint,
            checkpoint_every=args.checkpoint_every,
            resume=args.resume,
            preview=preview if args.preview_every is not None else None,
            preview_every=args.preview_every or 0.0,
            **extra,
        )
    except RenderInterrupted as stop:
        spp = settings()["spp"]
        _write(out, stop.image, {**settings(), "spp_reached": int(stop.spp_reached)})
        where = (
            f"; checkpoint {stop.checkpoint} (continue with --resume)" if stop.checkpoint else ""
        )
        print(
            f"radiometria: interrupted by {stop.signal_name} at {stop.spp_reached} of {spp} spp; "
            f"partial image {out}{where}",
            file=sys.stderr,
        )
        return 130 if stop.signal_name == "SIGINT" else 143
    _write(out, rgb, {**metadata, "spp_reached": int(metadata["spp"])})
    mark("image written" + jax_activity.summary())
    if not args.checkpoint and checkpoint.exists():
        checkpoint.unlink()  # the default checkpoint of a finished render is not needed
    print(out)
    return 0


def demo_render(out_dir: Path, *, spp: int, smoke: bool) -> list[Path]:
    """Render the built-in Cornell box into `out_dir/cornell_box.exr` and `.png`.

    **Arguments:**

    - `out_dir`: output directory (created if missing).
    - `spp`: samples per pixel (>= 1).
    - `smoke`: a tiny render for CI (32 x 32 pixels, at most 4 spp).

    **Returns:**

    The written paths.
    """
    spp = _check_int(spp, "spp", 1)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    exr = _check_output(out_dir / "cornell_box.exr")
    png = _check_output(out_dir / "cornell_box.png")
    size = 32 if smoke else None
    rgb, metadata = _render_to(
        "cornell-box",
        spp=min(spp, 4) if smoke else spp,
        width=size,
        height=size,
        seed=0,
        max_depth=None,
    )
    return [_write(exr, rgb, metadata), _write(png, rgb, metadata)]


def cache_info_command(args: argparse.Namespace) -> int:
    """Run `radiometria cache info [--dir DIR]`: the cache's directory, state, programs, size."""
    info = compilation_cache_info(args.dir)
    state = "off (RADIOMETRIA_NO_CACHE)" if compilation_cache_disabled() else "on"
    print(f"compilation cache: {info.path}")
    print(f"state: {state}")
    print(f"programs: {info.entries}")
    print(f"render steps: {info.steps}")
    print(f"size: {info.size_bytes / 2**20:.1f} MiB")
    return 0


def cache_clear_command(args: argparse.Namespace) -> int:
    """Run `radiometria cache clear [--dir DIR]`: delete the compiled programs."""
    steps = compilation_cache_info(args.dir).steps
    removed = clear_compilation_cache(args.dir)
    print(
        f"removed {removed} compiled programs and {steps} render steps from "
        f"{args.dir or compilation_cache_dir()}"
    )
    return 0
