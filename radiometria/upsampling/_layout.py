"""The table's column layout (thesis section 2.2.3; `RGBToSpectrumLUT`'s docstring in
`_lut.py`), shared by the fitter (`_fit_lut.py`) and the infrared-tail stage (`_tails.py`)."""

import numpy as np


def column_directions(resolution: int, dtype) -> np.ndarray:
    """Unit-brightness RGB of every column (3 res res, 3): e[l] = 1, e[l+1] = x, e[l+2] = y."""
    t = np.arange(resolution, dtype=np.float64) / (resolution - 1)
    j, i = np.meshgrid(np.arange(resolution), np.arange(resolution), indexing="ij")
    e = np.zeros((3, resolution, resolution, 3))
    for ch in range(3):
        e[ch, :, :, ch] = 1.0
        e[ch, :, :, (ch + 1) % 3] = t[i]
        e[ch, :, :, (ch + 2) % 3] = t[j]
    return e.reshape(-1, 3).astype(dtype)
