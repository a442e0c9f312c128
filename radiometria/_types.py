"""jaxtyping aliases shared by the package (style.md section 6)."""

from jaxtyping import Array, ArrayLike, Float, Int, PRNGKeyArray

FloatLike = (
    Float[ArrayLike, "..."] | int
)  # an elementwise input; Python floats and ints are accepted
Key = PRNGKeyArray

__all__ = [
    "Array",
    "ArrayLike",
    "Float",
    "FloatLike",
    "Int",
    "Key",
]
