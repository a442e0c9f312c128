"""Checkpoints of long renders: resume is bit-identical, foreign or broken files are refused."""

import numpy as np
import pytest

import radiometria.render as rr
from radiometria.render._checkpoint import load_checkpoint

KW = dict(width=16, height=16, batch=64, progress=False, sampler=rr.OwenSobol())


class _StopError(Exception):
    pass


@pytest.fixture(scope="module")
def description():
    return rr.load_scene("cornell-box")


def test_resume_after_interruption_is_bit_identical(description, tmp_path):
    """Stop a render after three steps (a preview callback raises), resume from the checkpoint
    it wrote, and get the uninterrupted image exactly."""
    full = np.asarray(rr.render(description, spp=8, **KW))
    ck = tmp_path / "render.npz"
    seen = []

    def stop_after_three(image, spp_reached):
        seen.append(spp_reached)
        assert image.shape == (16, 16, 3) and np.all(np.isfinite(image))
        if len(seen) == 3:
            raise _StopError

    with pytest.raises(_StopError):
        rr.render(description, spp=8, checkpoint=ck, checkpoint_every=0.0,
                  preview=stop_after_three, preview_every=0.0, **KW)  # fmt: skip
    assert seen == sorted(seen) and ck.exists()
    resumed = np.asarray(rr.render(description, spp=8, checkpoint=ck, resume=True, **KW))
    np.testing.assert_array_equal(resumed, full)


def test_foreign_checkpoint_is_refused_with_the_differences(description, tmp_path):
    ck = tmp_path / "render.npz"

    def stop(image, spp_reached):
        raise _StopError

    with pytest.raises(_StopError):
        rr.render(description, spp=8, checkpoint=ck, checkpoint_every=0.0, preview=stop,
                  preview_every=0.0, **KW)  # fmt: skip
    with pytest.raises(
        rr.CheckpointError, match=r"render\.npz: .*another render.*seed: 0 in the file, 5 now"
    ):  # noqa: E501
        rr.render(description, spp=8, seed=5, checkpoint=ck, resume=True, **KW)
    other = rr.load_scene("cornell-box-measured")
    with pytest.raises(rr.CheckpointError, match=r"scene: "):
        rr.render(other, spp=8, checkpoint=ck, resume=True, **KW)


def test_broken_checkpoints_name_the_file(tmp_path):
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"\x00not a zip")
    with pytest.raises(rr.CheckpointError, match=r"bad\.npz: not a radiometria render checkpoint"):
        load_checkpoint(bad, {"width": 1, "height": 1})
    with pytest.raises(FileNotFoundError, match="checkpoint not found"):
        load_checkpoint(tmp_path / "missing.npz", {})


def test_resume_needs_a_checkpoint(description):
    with pytest.raises(ValueError, match="needs `checkpoint`"):
        rr.render(description, spp=1, resume=True, **KW)
