"""Figures for `radiometria.media` and the volumetric path tracer (thesis section 1.3, ch. 4
and 9): transmittance estimators against optical depth, Henyey-Greenstein lobes, and a
rendered scene with chromatic media."""

import tempfile
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from ..media import (
    HenyeyGreenstein,
    delta_tracking_transmittance,
    ratio_tracking_transmittance,
    residual_ratio_tracking_transmittance,
)
from ..render import render
from ._registry import figure, save
from ._render import _display

#: Tracking rates of the estimators figure, relative to the extinction: ratio tracking's
#: majorant, and residual ratio tracking's control and residual majorant.
RATIO_MAJORANT = 1.5
RESIDUAL_CONTROL = 0.8
RESIDUAL_MAJORANT = 0.5


def transmittance_estimators_data(*, smoke: bool = False, n: int | None = None) -> dict:
    r"""What the transmittance-estimators figure plots: the sample mean and variance of delta,
    ratio and residual ratio tracking through a medium of constant extinction
    $\sigma_t = 1$ m$^{-1}$ over segments of length $\tau$ (so the optical depth is $\tau$).

    Ratio tracking runs at the majorant `RATIO_MAJORANT` $\sigma_t$; residual ratio tracking
    with the control `RESIDUAL_CONTROL` $\sigma_t$ and the residual majorant
    `RESIDUAL_MAJORANT` $\sigma_t$. Returns `tau` (m,) [dimensionless], `n` (estimates per
    depth; 1024 in smoke mode, else 16384, or `n`), `T` = $e^{-\tau}$ (m,), and for
    `"delta"`, `"ratio"`, `"residual"` a dict of `mean` and `var` (m,) [dimensionless],
    all estimates made with `jax.random.key(0)`.
    """
    n = n if n is not None else (1024 if smoke else 16384)
    tau = np.geomspace(0.05, 8.0, 12 if smoke else 24)
    t_max = jnp.asarray(np.repeat(tau, n))
    m = t_max.shape[0]
    origins = jnp.zeros((m, 3), t_max.dtype)
    directions = jnp.broadcast_to(jnp.asarray([0.0, 0.0, 1.0], t_max.dtype), (m, 3))

    def unit(p):
        return jnp.ones(p.shape[0], p.dtype)

    key = jax.random.key(0)
    estimates = {
        "delta": delta_tracking_transmittance(
            unit, origins, directions, t_max, 1.0, key=jax.random.fold_in(key, 0)
        ),
        "ratio": ratio_tracking_transmittance(
            unit, origins, directions, t_max, RATIO_MAJORANT, key=jax.random.fold_in(key, 1)
        ),
        "residual": residual_ratio_tracking_transmittance(
            unit,
            origins,
            directions,
            t_max,
            RESIDUAL_CONTROL,
            RESIDUAL_MAJORANT,
            key=jax.random.fold_in(key, 2),
        ),  # fmt: skip
    }
    out = {"tau": tau, "n": n, "T": np.exp(-tau)}
    for name, x in estimates.items():
        x = np.asarray(x, np.float64).reshape(tau.size, n)
        out[name] = {"mean": x.mean(axis=1), "var": x.var(axis=1, ddof=1)}
    return out


@figure("fig_4_transmittance_estimators")
def fig_4_transmittance_estimators(out_dir, *, smoke: bool = False) -> list[Path]:
    """Transmittance estimators against optical depth: their means against Beer-Lambert,
    $e^{-\\tau}$ (thesis eq. 1.12), and their variances (delta tracking's is $T(1 - T)$;
    ratio tracking's falls with $T^2$; residual ratio tracking's is smaller still). Data:
    `transmittance_estimators_data()`."""
    import matplotlib.pyplot as plt

    d = transmittance_estimators_data(smoke=smoke)
    tau = d["tau"]
    labels = {"delta": "delta tracking", "ratio": "ratio tracking", "residual": "residual ratio"}
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.0, 4.0))
    a.plot(tau, d["T"], "k-", lw=2, label=r"$e^{-\tau}$")
    b.plot(tau, d["T"] * (1 - d["T"]), "k:", lw=1, label=r"$T(1-T)$")
    for (name, label), marker in zip(labels.items(), "os^", strict=True):
        a.plot(tau, d[name]["mean"], marker, ms=4, mfc="none", label=label)
        var = np.where(d[name]["var"] > 0, d[name]["var"], np.nan)  # none seen: off the log axis
        b.plot(tau, var, marker + "-", ms=4, mfc="none", label=label)
    a.set(xscale="log", yscale="log", xlabel=r"optical depth $\tau$", ylabel="mean estimate")
    b.set(xscale="log", yscale="log", xlabel=r"optical depth $\tau$", ylabel="variance")
    a.set_title(f"Transmittance estimators ({d['n']} estimates per depth)")
    b.set_title("Variance of one estimate")
    a.legend(frameon=False)
    b.legend(frameon=False)
    return save(fig, out_dir, "fig_4_transmittance_estimators")


PHASE_G = (-0.5, 0.0, 0.3, 0.7, 0.9)


def phase_lobes_data(*, smoke: bool = False) -> dict:
    """What the phase-lobes figure plots: `HenyeyGreenstein(g).p` for `g` in `PHASE_G` at
    scattering angles `theta` (n,) on [0, pi] [rad] (n = 181 in smoke mode, else 721),
    between `wo` = +z (pbrt's convention: the direction back towards where light came from)
    and `wi`; `p` is a dict g -> (n,) [sr^-1]."""
    theta = np.linspace(0.0, np.pi, 181 if smoke else 721)
    # scattering angle theta between the propagation directions -wo and wi
    wi = np.stack([np.sin(theta), np.zeros_like(theta), -np.cos(theta)], axis=-1)
    wo = np.broadcast_to([0.0, 0.0, 1.0], wi.shape)
    p = {g: np.asarray(HenyeyGreenstein(g).p(jnp.asarray(wo), jnp.asarray(wi))) for g in PHASE_G}
    return {"theta": theta, "g": PHASE_G, "p": p}


@figure("fig_4_phase_lobes")
def fig_4_phase_lobes(out_dir, *, smoke: bool = False) -> list[Path]:
    """Henyey-Greenstein lobes for several mean cosines g: polar plot of p(theta) (log radius)
    and p against the scattering angle. Data: `phase_lobes_data()`."""
    import matplotlib.pyplot as plt

    d = phase_lobes_data(smoke=smoke)
    theta = d["theta"]
    fig = plt.figure(figsize=(10.0, 4.2))
    polar = fig.add_subplot(1, 2, 1, projection="polar")
    lin = fig.add_subplot(1, 2, 2)
    for g in d["g"]:
        p = d["p"][g]
        r = np.log10(p) + 3.0  # log radius, 1e-3 sr^-1 at the centre
        polar.plot(np.r_[theta, 2 * np.pi - theta[::-1]], np.r_[r, r[::-1]], label=f"g = {g}")
        lin.plot(np.degrees(theta), p, label=f"g = {g}")
    polar.set_title(r"$\log_{10} p + 3$ (light travels towards $\theta = 0$)")
    polar.set_rlim(0, None)
    polar.set_rlabel_position(200)
    lin.set(yscale="log", xlabel=r"scattering angle $\theta$ [deg]", ylabel=r"$p$ [sr$^{-1}$]")
    lin.set_title("Henyey-Greenstein phase function")
    lin.legend(frameon=False)
    return save(fig, out_dir, "fig_4_phase_lobes")


#: The rendered scene: a purely absorbing slab with RGB sigma_t (blue absorbed most), a
#: scattering cloud with a chromatic albedo, and a chromatic medium inside a glass sphere, in
#: front of a white area light and under a dim constant sky.
MEDIA_SCENE = """<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 7" target="0, 0, 0" up="0, 1, 0"/>
    </transform>
    <film type="hdrfilm"><integer name="width" value="{width}"/>
      <integer name="height" value="{height}"/><rfilter type="box"/></film>
  </sensor>
  <integrator type="volpath"><integer name="max_depth" value="16"/></integrator>
  <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
  <shape type="rectangle"><transform name="to_world"><scale value="10"/><translate z="-3"/>
    </transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
  <medium type="homogeneous" id="dye"><rgb name="sigma_t" value="0.1, 0.4, 1.0"/>
    <float name="scale" value="{slab_scale}"/><float name="albedo" value="0"/></medium>
  <shape type="cube"><transform name="to_world"><scale x="0.8" y="1.4" z="{half_depth}"/>
    <translate x="-2.1"/></transform><bsdf type="null"/><ref name="interior" id="dye"/></shape>
  <medium type="homogeneous" id="cloud"><float name="sigma_t" value="2.5"/>
    <rgb name="albedo" value="0.98, 0.85, 0.5"/><phase type="hg"><float name="g" value="0.6"/>
    </phase></medium>
  <shape type="sphere"><float name="radius" value="0.9"/><point name="center" x="0" y="0" z="0"/>
    <bsdf type="null"/><ref name="interior" id="cloud"/></shape>
  <medium type="homogeneous" id="tint"><rgb name="sigma_t" value="1.0, 0.3, 0.8"/>
    <float name="scale" value="1.5"/><float name="albedo" value="0.7"/></medium>
  <shape type="sphere"><float name="radius" value="0.9"/><point name="center" x="2.1" y="0" z="0"/>
    <bsdf type="dielectric"/><ref name="interior" id="tint"/></shape>
</scene>
"""


def chromatic_media_data(
    *, smoke: bool = False, tmp_dir: Path | str | None = None, spp: int | None = None
) -> dict:
    """What the chromatic-media figure plots: `render` of `MEDIA_SCENE` (written to
    `tmp_dir`, a temporary folder by default) with the scene's `volpath`.

    Returns `image` (h, w, 3) linear sRGB [relative radiance] (48 x 24 px at 8 spp in smoke
    mode, else 320 x 160 at 256 spp; `spp` overrides), `xml` (the scene text), `slab_depth`
    (the absorbing slab's thickness, 0.6 [m]) and `slab_sigma_t_rgb` (its RGB sigma_t
    [m^-1]), and `slab_pixels` (h, w), the pixels that see the light through the slab
    only (front and back faces).
    """
    width, height = (48, 24) if smoke else (320, 160)
    spp = spp if spp is not None else (8 if smoke else 256)
    depth, scale = 0.6, 2.0
    xml = MEDIA_SCENE.format(width=width, height=height, slab_scale=scale, half_depth=depth / 2)
    with tempfile.TemporaryDirectory(dir=tmp_dir) as tmp:
        path = Path(tmp) / "chromatic_media.xml"
        path.write_text(xml)
        image = np.asarray(render(path, spp=spp, seed=0, progress=False), np.float64)
    # pixels whose rays cross the slab (x in [-2.9, -1.3], |y| <= 1.4, |z| <= depth / 2)
    # through its front and back faces, with a margin of a few pixels
    half_width = 7.0 * np.tan(np.radians(45.0) / 2)  # at the plane z = 0
    x = ((np.arange(width) + 0.5) / width * 2 - 1) * half_width
    y = (1 - (np.arange(height) + 0.5) / height * 2) * half_width * height / width
    inside = np.ones((height, width), bool)
    for z in (depth / 2, -depth / 2):
        f = (7.0 - z) / 7.0
        inside &= ((x * f > -2.75) & (x * f < -1.45))[None, :] & (np.abs(y * f) < 1.2)[:, None]
    return {
        "image": image,
        "xml": xml,
        "slab_depth": depth,
        "slab_sigma_t_rgb": scale * np.array([0.1, 0.4, 1.0]),
        "slab_pixels": inside,
    }


@figure("fig_9_chromatic_media")
def fig_9_chromatic_media(out_dir, *, smoke: bool = False) -> list[Path]:
    """Chromatic media rendered with `volpath` (thesis ch. 9): left, a purely absorbing slab
    whose extinction grows towards the blue (Beer-Lambert, eq. 1.12: the light behind it
    turns orange); middle, a forward-scattering cloud (HG g = 0.6) with a chromatic albedo;
    right, a scattering medium inside a glass sphere. Data: `chromatic_media_data()`."""
    import matplotlib.pyplot as plt

    d = chromatic_media_data(smoke=smoke)
    fig, ax = plt.subplots(figsize=(9.0, 4.8))
    ax.imshow(_display(d["image"]), interpolation="nearest")
    ax.set_axis_off()
    ax.set_title("Absorbing slab, scattering cloud, medium behind glass (volpath)")
    return save(fig, out_dir, "fig_9_chromatic_media")
