"""jaxtyping aliases shared by the package (style.md section 6)."""

from jaxtyping import Array, ArrayLike, Bool, Float, Int, PRNGKeyArray

FloatLike = (
    Float[ArrayLike, "..."] | int
)  # an elementwise input; Python floats and ints are accepted
XYZ = Float[Array, "*batch 3"]  # channels are on the LAST axis (colour's convention)
RGB = Float[Array, "*batch 3"]
Directions = Float[Array, "*batch 3"]
Key = PRNGKeyArray

__all__ = [
    "Array",
    "ArrayLike",
    "Bool",
    "Directions",
    "Float",
    "FloatLike",
    "Int",
    "Key",
    "RGB",
    "XYZ",
]
