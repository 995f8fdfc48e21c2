"""Type aliases shared across barrierjax (after diffrax's `_custom_types.py`)."""

from jaxtyping import Array, Float

Scalar = Float[Array, ""]
Vector = Float[Array, " n"]
Batchable = Float[Array, "..."]  # a scene leaf: a scalar, or a batch of them
