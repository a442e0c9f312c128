"""Moved to `radiometria.render._geometry`; re-exported here until render/ is restructured."""

from ._geometry._brute_force import (
    intersect_brute_force_any as intersect_brute_force_any,
    intersect_brute_force_closest as intersect_brute_force_closest,
)
from ._geometry._queries import (
    intersect_any as intersect_any,
    intersect_closest as intersect_closest,
)
from ._geometry._triangle import Hit as Hit
