"""Offline builder of the packaged Sobol direction numbers (not run at import).

Source: S. Joe and F. Y. Kuo, "Constructing Sobol sequences with better two-dimensional
projections", SIAM J. Sci. Comput. 30 (2008) 2635-2654 (`Joe2008`), file `new-joe-kuo-6.21201`
(https://web.maths.unsw.edu.au/~fkuo/sobol/), 21201 dimensions, distributed under a BSD-style
licence (copyright (c) 2008, Frances Y. Kuo and Stephen Joe). The copy read here is the one that
SciPy ships, `scipy/stats/_sobol_direction_numbers.npz` (arrays `poly` (21201,) and `vinit`
(21201, 18)), which is the same table re-encoded: `poly = 2^s + 2 a + 1` holds the degree `s`
and coefficients `a` of the primitive polynomial, `vinit[j, :s]` the initial direction integers
`m_1 .. m_s`.

The packaged file `data/sobol_joe_kuo_6_21201.npz` keeps exactly the information of the Joe-Kuo
text file, compactly: `s` (uint8, degree), `a` (uint32, polynomial coefficients) and `m_bits`
(uint8, `np.packbits` of the initial direction integers of all dimensions in order, `m_k` written
with its k bits, most significant first, since `m_k` is odd and `< 2^k`). Dimension 1 is the
van der Corput sequence (`s = 0`). `radiometria.montecarlo._sobol` unpacks them.
`provenance.json` records the source, the licence and the sha256 of both the SciPy file read
and the file written.

Run `python -m radiometria.montecarlo._make_data` (SciPy installed) to rebuild;
`tests/montecarlo/test_sobol.py` checks the packaged table against SciPy's file.
"""

import datetime
import hashlib
import json
from pathlib import Path

import numpy as np

from .._io import atomic_write_bytes, write_npz_deterministic

DATA_DIR = Path(__file__).parent / "data"
SOBOL_FILE = "sobol_joe_kuo_6_21201.npz"

LICENCE = """\
Licence of the Joe-Kuo direction numbers (new-joe-kuo-6.21201), as published at
https://web.maths.unsw.edu.au/~fkuo/sobol/:

Copyright (c) 2008, Frances Y. Kuo and Stephen Joe
All rights reserved.

Redistribution and use in source and binary forms, with or without modification, are permitted
provided that the following conditions are met:
* Redistributions of source code must retain the above copyright notice, this list of conditions
  and the following disclaimer.
* Redistributions in binary form must reproduce the above copyright notice, this list of
  conditions and the following disclaimer in the documentation and/or other materials provided
  with the distribution.
* Neither the names of the copyright holders nor the names of the University of New South Wales
  and the University of Waikato and its contributors may be used to endorse or promote products
  derived from this software without specific prior written permission.

THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS ``AS IS'' AND ANY EXPRESS OR IMPLIED
WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE IMPLIED WARRANTIES OF MERCHANTABILITY AND FITNESS
FOR A PARTICULAR PURPOSE ARE DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDERS BE LIABLE FOR ANY
DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL DAMAGES (INCLUDING, BUT NOT
LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES; LOSS OF USE, DATA, OR PROFITS; OR
BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON ANY THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT
LIABILITY, OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE OF THIS
SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
"""


def scipy_direction_file() -> Path:
    """Path of SciPy's packaged copy of the Joe-Kuo table."""
    import scipy.stats

    return Path(scipy.stats.__file__).parent / "_sobol_direction_numbers.npz"


def compact_from_scipy(poly: np.ndarray, vinit: np.ndarray) -> dict[str, np.ndarray]:
    """SciPy's `(poly, vinit)` -> the compact Joe-Kuo encoding `(s, a, m)`."""
    poly = np.asarray(poly, dtype=np.int64)
    vinit = np.asarray(vinit, dtype=np.int64)
    s = np.zeros(poly.shape, dtype=np.int64)
    p = poly.copy()
    while np.any(p > 1):
        s += p > 1
        p >>= 1
    a = (poly - (1 << s) - 1) >> 1
    a[0] = 0  # dimension 1 has no polynomial (poly = 1)
    if np.any(a < 0) or np.any((poly[1:] & 1) != 1):
        raise ValueError("SciPy's `poly` is not of the form 2^s + 2a + 1.")
    m = np.concatenate([vinit[j, : s[j]] for j in range(len(poly))]).astype(np.int64)
    k = np.concatenate([np.arange(1, sj + 1) for sj in s])  # m_k needs k bits
    if np.any(m >= (1 << k)) or np.any(m % 2 == 0):
        raise ValueError("initial direction integers must be odd and < 2^k.")
    bits = np.concatenate([(m[i] >> np.arange(k[i] - 1, -1, -1)) & 1 for i in range(len(m))])
    return {
        "s": s.astype(np.uint8),
        "a": a.astype(np.uint32),
        "m_bits": np.packbits(bits.astype(np.uint8)),
    }


def build(out_dir: Path = DATA_DIR) -> Path:
    """Write the compact table and `provenance.json` into `out_dir`; return the table's path."""
    import scipy

    src = scipy_direction_file()
    with np.load(src) as z:
        compact = compact_from_scipy(z["poly"], z["vinit"])
    out_dir.mkdir(parents=True, exist_ok=True)
    path = write_npz_deterministic(out_dir / SOBOL_FILE, compact, mode=0o644)
    prov = {
        SOBOL_FILE: {
            "content": "Sobol direction numbers new-joe-kuo-6.21201 (21201 dimensions), compact "
            "Joe-Kuo encoding: s (degree, uint8), a (polynomial coefficients, uint32), m (initial "
            "direction integers m_1..m_s of every dimension, concatenated, uint32)",
            "primary_source": "S. Joe and F. Y. Kuo, Constructing Sobol sequences with better "
            "two-dimensional projections, SIAM J. Sci. Comput. 30 (2008) 2635-2654; "
            "https://web.maths.unsw.edu.au/~fkuo/sobol/ (file new-joe-kuo-6.21201)",
            "licence": "BSD-style (Copyright (c) 2008, Frances Y. Kuo and Stephen Joe); full text "
            "in the `licence_text` field",
            "licence_text": LICENCE,
            "derived_from": f"scipy/stats/_sobol_direction_numbers.npz (SciPy {scipy.__version__}, "
            "BSD-3-Clause), arrays poly (21201,), vinit (21201, 18)",
            "derived_from_sha256": hashlib.sha256(src.read_bytes()).hexdigest(),
            "builder": "python -m radiometria.montecarlo._make_data",
            "retrieved": datetime.date.today().isoformat(),
            "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
        }
    }
    text = json.dumps(prov, indent=2, sort_keys=True) + "\n"
    atomic_write_bytes(out_dir / "provenance.json", text.encode(), mode=0o644)
    return path


if __name__ == "__main__":
    print(build())
