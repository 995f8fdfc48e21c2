"""Type aliases shared across barrierjax (after diffrax's `_custom_types.py`)."""

from jaxtyping import Array, ArrayLike, Float

RealScalarLike = float | int | ArrayLike
FloatScalar = Float[Array, ""]
FloatVector = Float[Array, " n"]
