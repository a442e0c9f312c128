"""Fix-ups of the measured Cornell box data (`data/cornell_box_measured.json`).

The Cornell Program of Computer Graphics measurements (mm; reflectance spectra 400-700 nm
every 4 nm; light spectrum) list quads with mixed orientation, so each quad is re-oriented
here: a shape made of one quad (walls, floor, ceiling, light) faces the centre of the room's
box, a shape of several quads (the two blocks) faces away from its own centroid. The light,
which the data puts in the ceiling plane, is lowered by `MEASURED_LIGHT_OFFSET_MM` = 0.1 mm so
it is in front of the ceiling.
"""

import numpy as np

from ._description import ShapeDescription

__all__ = ["MEASURED_LIGHT_OFFSET_MM", "orient_measured"]

MEASURED_LIGHT_OFFSET_MM = 0.1


def orient_measured(shapes: list[ShapeDescription]) -> None:
    """Re-orient the measured Cornell box quads and lower its light (see the module docstring)."""
    allv = np.concatenate([s.vertices for s in shapes])
    room_centre = 0.5 * (allv.min(0) + allv.max(0))
    for s in shapes:
        v = np.asarray(s.vertices, dtype=np.float64)
        f = np.asarray(s.faces)
        n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        tri_centre = v[f].mean(axis=1)
        if len(f) <= 2:  # one quad: face the room's interior
            want = room_centre - tri_centre
        else:  # a block: face away from its own centroid
            want = tri_centre - v.mean(axis=0)
        flip = np.sum(n * want, axis=1) < 0
        s.faces = np.where(flip[:, None], f[:, [0, 2, 1]], f)
        if s.emitter is not None:
            v = v.copy()
            v[:, 1] -= MEASURED_LIGHT_OFFSET_MM
            s.vertices = v
