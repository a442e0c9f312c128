"""Render checkpoints: the film's sums, the steps done and the render's identity, on disk.

A render is a fixed sequence of steps (tiles of pixels x groups of passes, `_driver._plan`),
and the counter-based samplers make every step's samples a function of `(seed, pass, pixel)`
alone. So the film's accumulated sums after step `i`, together with `i`, are the whole state
of a render: resuming from them runs the same remaining steps on the same sums, in the same
order, and gives the same image bit for bit as an uninterrupted render.

A checkpoint is a `.npz` file (written atomically and deterministically, no pickles) holding
`xyz_sum (H, W, 3)`, `weight_sum (H, W)` (float32), `next_step` and the render's identity as
JSON: the library version, a SHA-256 of the compiled scene, camera, filter, integrator and
sampler (their arrays and structure), the seed, spp, image size and the step layout. Resuming
with anything different is refused with the fields that differ named.
"""

import hashlib
import importlib.metadata
import json
from pathlib import Path

import jax
import numpy as np

from .._io import hash_array, write_npz_deterministic

__all__ = ["CheckpointError", "load_checkpoint", "render_identity", "save_checkpoint"]

_FORMAT = 1


class CheckpointError(ValueError):
    """A checkpoint file is unreadable, malformed, or belongs to another render; the message
    names the file and what differs (thesis ch. 8: long renders)."""


def render_identity(kernel, *, seed: int, spp: int, width: int, height: int, layout) -> dict:
    """What a checkpoint must match: version, scene/strategy hash, seed, spp, size, layout."""
    digest = hashlib.sha256()
    leaves, treedef = jax.tree_util.tree_flatten(kernel)
    digest.update(str(treedef).encode())
    for leaf in leaves:
        hash_array(digest, leaf)
    return {
        "format": _FORMAT,
        "version": importlib.metadata.version("radiometria"),
        "scene": digest.hexdigest(),
        "seed": int(seed),
        "spp": int(spp),
        "width": int(width),
        "height": int(height),
        "layout": [int(x) for x in layout],
    }


def save_checkpoint(path, xyz_sum, weight_sum, next_step: int, identity: dict) -> Path:
    """Write a checkpoint atomically (a temporary file renamed into place)."""
    arrays = {
        "xyz_sum": np.asarray(xyz_sum, np.float32),
        "weight_sum": np.asarray(weight_sum, np.float32),
        "next_step": np.asarray(int(next_step), np.int64),
        "identity": np.asarray(json.dumps(identity, sort_keys=True)),
    }
    return write_npz_deterministic(Path(path), arrays)


def load_checkpoint(path, identity: dict) -> tuple[np.ndarray, np.ndarray, int]:
    """`(xyz_sum, weight_sum, next_step)` of a checkpoint made by the same render.

    Raises `FileNotFoundError` for a missing file and `CheckpointError` naming the file for a
    malformed one or one whose identity differs from `identity` (the differing fields named).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"checkpoint not found: {path}")
    try:
        with np.load(path, allow_pickle=False) as data:
            stored = json.loads(str(data["identity"].reshape(-1)[0]))
            xyz, w = np.asarray(data["xyz_sum"]), np.asarray(data["weight_sum"])
            next_step = int(data["next_step"].reshape(-1)[0])
    except (OSError, ValueError, KeyError, EOFError) as e:
        raise CheckpointError(f"{path}: not a radiometria render checkpoint ({e}).") from None
    differ = sorted(k for k in set(identity) | set(stored) if identity.get(k) != stored.get(k))
    if differ:
        detail = ", ".join(
            f"{k}: {stored.get(k)!r} in the file, {identity.get(k)!r} now" for k in differ
        )
        raise CheckpointError(
            f"{path}: the checkpoint belongs to another render ({detail}); render again "
            "without --resume, or give the same scene, spp, size, seed and version."
        )
    h, wd = identity["height"], identity["width"]
    if xyz.shape != (h, wd, 3) or w.shape != (h, wd) or not 0 <= next_step:
        raise CheckpointError(f"{path}: film arrays or step count are malformed.")
    return xyz, w, next_step
