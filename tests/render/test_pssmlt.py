"""Primary-sample-space MLT (`pssmlt`): its image against the path tracer's (the mean through
the bootstrap's standard error, 4 x 4 pixel blocks by a z-test), bad parameters, the command
line (issue 14)."""

import numpy as np
import pytest

from radiometria.camera import BoxFilter, read_exr
from radiometria.cli import main
from radiometria.montecarlo import pixel_z_test
from radiometria.render import (
    PSSMLT,
    OwenSobol,
    Path,
    compile_scene,
    load_scene,
    render,
)

# 16 x 16 pixels, 64 mutations per pixel over 32 chains: the same compiled program as the
# command-line test below (16 x 16 at 4 spp: 1024 mutations, 32 chains by default).
_SIZE, _MPP, _DEPTH, _CHAINS = 16, 64, 2, 32
_MLT = PSSMLT(max_depth=_DEPTH, chains=_CHAINS)
_BATCH = 4096


def _blocks(image):
    # pixels summed in 4 x 4 blocks: (4, 4, 3)
    return image.reshape(4, 4, 4, 4, 3).sum(axis=(1, 3))


@pytest.fixture(scope="module")
def path_reference():
    # The path tracer with the box filter (MLT bins its contributions into pixels), 8
    # independent Owen-Sobol renders: the mean and the variance of the mean.
    images = np.stack([
        np.asarray(render("cornell-box", spp=64, width=_SIZE, height=_SIZE, seed=s,
                          sampler=OwenSobol(), integrator=Path(max_depth=_DEPTH),
                          rfilter=BoxFilter(), return_xyz=True, batch=_BATCH, progress=False),
                   np.float64)
        for s in range(8)
    ])  # fmt: skip
    return images


@pytest.mark.slow
def test_pssmlt_agrees_with_path(path_reference):
    # (1) Mean: each deposit is g / i with i = sum of X + Y + Z over g's pixels, so the
    # image's mean X + Y + Z is exactly the bootstrap's c; c must agree with the path
    # tracer's mean X + Y + Z within 4 standard errors (the bootstrap's and the reference's).
    # (2) Blocks: the 4 x 4 pixel blocks of independent MLT renders (variance across seeds)
    # pass the z-test against the path tracer's blocks; the mirrored image (red and green
    # walls swapped) and a 10 % brighter mean fail.
    ref = path_reference
    ref_mean = ref.sum(-1).mean(axis=(1, 2))  # per render
    scene = compile_scene(load_scene("cornell-box"), width=_SIZE, height=_SIZE)
    c, se = _MLT.bootstrap(scene[0], scene[1], spp=_MPP, seed=0, batch=_BATCH)
    se_ref = ref_mean.std(ddof=1) / np.sqrt(len(ref_mean))
    tol = 4 * np.hypot(se, se_ref)
    assert abs(c - ref_mean.mean()) < tol, (c, ref_mean.mean(), tol)
    assert abs(1.1 * c - ref_mean.mean()) > tol
    assert 0 < se < 0.05 * c  # the bootstrap's standard error is what bounds the mean
    mlt = np.stack([
        np.asarray(render("cornell-box", spp=_MPP, width=_SIZE, height=_SIZE, seed=s,
                          integrator=_MLT, return_xyz=True, batch=_BATCH, progress=False),
                   np.float64)
        for s in range(6)
    ])  # fmt: skip
    np.testing.assert_allclose(mlt[0].sum(-1).mean(), c, rtol=1e-4)
    ours, theirs = np.stack([_blocks(m) for m in mlt]), np.stack([_blocks(r) for r in ref])
    var = ours.var(0, ddof=1) / len(ours) + theirs.var(0, ddof=1) / len(theirs)

    def z_test(image):
        return pixel_z_test(image, theirs.mean(0), var, 1, None, variance_floor=1e-10,
                            required_fraction=0.95)  # fmt: skip

    result = z_test(ours.mean(0))
    assert result.passed, result.message
    bad = z_test(ours.mean(0)[:, ::-1])
    assert not bad.passed, bad.message
    # Deterministic for a seed.
    again = render("cornell-box", spp=_MPP, width=_SIZE, height=_SIZE, seed=0, integrator=_MLT,
                   return_xyz=True, batch=_BATCH, progress=False)  # fmt: skip
    np.testing.assert_array_equal(again, mlt[0].astype(np.float32))


def test_pssmlt_bad_parameters():
    with pytest.raises(ValueError, match=r"sigma.*\(0, 1\).*0"):
        PSSMLT(sigma=0.0)
    with pytest.raises(ValueError, match=r"sigma.*-0.1"):
        PSSMLT(sigma=-0.1)
    with pytest.raises(ValueError, match=r"large_step_probability.*\[0, 1\].*1.5"):
        PSSMLT(large_step_probability=1.5)
    with pytest.raises(ValueError, match=r"large_step_probability.*-0.2"):
        PSSMLT(large_step_probability=-0.2)
    with pytest.raises(ValueError, match=r"chains.*>= 1.*0"):
        PSSMLT(chains=0)
    with pytest.raises(ValueError, match=r"bootstrap_samples.*>= 1.*, got 0"):
        PSSMLT(bootstrap_samples=0)
    with pytest.raises(ValueError, match=r"mutations_per_pixel.*-3"):
        PSSMLT(mutations_per_pixel=-3)
    with pytest.raises(ValueError, match="max_depth.*>= 1.*0"):
        PSSMLT(max_depth=0)
    with pytest.raises(ValueError, match="heuristic"):
        PSSMLT(heuristic="max")
    with pytest.raises(ValueError, match="scene.xml: unknown pssmlt parameter.*'sigmaa'"):
        PSSMLT.from_properties({"sigmaa": 0.1}, where="scene.xml")
    with pytest.raises(ValueError, match="scene.xml: pssmlt: .*sigma"):
        PSSMLT.from_properties({"sigma": 2.0}, where="scene.xml")
    m = PSSMLT.from_properties({"max_depth": 3, "sigma": 0.05, "large_step_probability": 0.5})
    assert (m.max_depth, m.sigma, m.large_step_probability) == (3, 0.05, 0.5)
    with pytest.raises(TypeError, match="render"):
        m.radiance(None, None, None, None, None, None)
    for option in ({"spectral_bins": 4}, {"reconstruction": "importance"}):
        with pytest.raises(ValueError, match=f"{next(iter(option))}.*PSSMLT"):
            render("cornell-box", spp=1, width=4, height=4, integrator=m, **option)


@pytest.mark.slow
def test_pssmlt_from_the_command_line(tmp_path):
    exr = tmp_path / "x.exr"
    argv = ["render", "cornell-box", "--width", "16", "--height", "16", "--spp", "4"]
    argv += ["--integrator", "pssmlt", "--max-depth", str(_DEPTH), "--out", str(exr)]
    assert main(argv) == 0
    rgb, meta = read_exr(exr)
    assert rgb.shape == (16, 16, 3) and np.all(np.isfinite(rgb)) and rgb.mean() > 0
    assert meta["integrator"] == "pssmlt"
