"""Moved to `._geometry._native` and `._geometry._registry`; re-exported until render/ is split."""

from ._geometry._native import native_status as native_status
from ._geometry._registry import resolve_backend as resolve_backend
