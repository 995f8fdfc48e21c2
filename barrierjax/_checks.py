"""Input validation that names the offending field.

Concrete inputs are checked eagerly and raise `ValueError`; traced inputs (inside
`jit`, `vmap` or `grad`) are checked at run time with `equinox.error_if`, so a bad
value never propagates silently into NaN.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer


def _is_traced(value) -> bool:
    return isinstance(value, Tracer)


# How to get float64, where a model or a value needs it. At the program's start: JAX lowers
# the constants a function closes over in the precision of its first call, and a program
# traced again after the switch can fail to lower.
ENABLE_FLOAT64 = (
    'enable float64 at the program\'s start: jax.config.update("jax_enable_x64", True)'
)

_LISTED = 8  # a message lists the values of an array up to this size, else the first bad one


def _fail(name: str, rule: str, value, ok) -> ValueError:
    array = np.asarray(value)
    if array.size <= _LISTED:
        return ValueError(f"{name} must be {rule}; got {array.tolist()!r}")
    bad = ~np.broadcast_to(np.asarray(ok, dtype=bool), array.shape)
    first = np.unravel_index(np.argmax(bad), array.shape)
    where = first[0] if len(first) == 1 else first
    return ValueError(
        f"{name} must be {rule}; {int(bad.sum())} of its {array.size} values are not "
        f"(the first at index {where}: {array[first].item()!r})"
    )


def check(name: str, value, predicate, rule: str):
    """Return `value` as an array after checking `predicate(value)` elementwise."""
    if _is_traced(value):
        ok = predicate(value)
        return eqx.error_if(value, ~jnp.all(ok), f"{name} must be {rule}")
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"{name} must be {rule}, a number or an array of them; got {value!r}"
        ) from None
    with np.errstate(invalid="ignore"):
        ok = predicate(array)
    if _is_traced(ok):  # a concrete value against a traced bound
        return eqx.error_if(float_array(value), ~jnp.all(ok), f"{name} must be {rule}")
    if not np.all(ok):
        raise _fail(name, rule, value, ok)
    dtype = jnp.result_type(float)
    if dtype != np.float64:
        with np.errstate(over="ignore"):
            overflows = np.isfinite(array) & ~np.isfinite(array.astype(dtype))
        if np.any(overflows):
            raise _fail(
                name,
                f"{rule} in {np.dtype(dtype).name} (or {ENABLE_FLOAT64})",
                value,
                ~overflows,
            )
    return float_array(value)


def float_array(value, dtype=None):
    """`value` as an array of `dtype` (default JAX's float type). A concrete one is put on
    the device as it is (or converted on the host): `jnp.asarray` converts by an eager
    operation, a program to compile, or to find in the cache, in each new process."""
    dtype = jnp.result_type(float) if dtype is None else dtype
    if _is_traced(value):
        return jnp.asarray(value, dtype)
    if isinstance(value, jax.Array) and value.dtype == dtype and not value.weak_type:
        return value
    return jax.device_put(np.asarray(value, dtype))


def positive(name: str, value):
    """Finite and strictly positive."""
    return check(name, value, lambda x: (x > 0) & (x < jnp.inf), "positive and finite")


def positives(**named):
    """`positive` for each name=value, in order: a tuple of the checked values."""
    return tuple(positive(name, value) for name, value in named.items())


def non_negative(name: str, value):
    """Finite and non-negative."""
    return check(name, value, lambda x: (x >= 0) & (x < jnp.inf), "non-negative and finite")


def in_range(name: str, value, low: float, high: float):
    """In the half-open interval (low, high]."""
    return check(name, value, lambda x: (x > low) & (x <= high), f"in ({low:g}, {high:g}]")


def tolerance(name: str, rtol) -> float:
    """A relative tolerance given as a Python number, checked to lie in (0, 1), as a
    float (`check` states the same rule for a traced one)."""
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"{name} must be in (0, 1); got {rtol!r}")
    return float(rtol)


def solve_method(method: str) -> str:
    """The normal impact's method: "closed_form" or "ode"."""
    if method not in ("closed_form", "ode"):
        raise ValueError(f"method must be 'closed_form' or 'ode'; got {method!r}")
    return method


def step_budget(max_steps) -> int | None:
    """A step budget: None (the model's own), or an integer of at least 16."""
    if max_steps is not None and (
        isinstance(max_steps, str) or int(max_steps) != max_steps or max_steps < 16
    ):
        raise ValueError(f"max_steps must be None or an integer >= 16; got {max_steps!r}")
    return None if max_steps is None else int(max_steps)


def history_samples(n_history, *, optional: bool = True) -> int:
    """A history's sample count: an integer >= 2, or 0 for none where `optional`."""
    rule = "0 or an integer >= 2" if optional else "an integer >= 2"
    try:
        count = float(n_history) if not isinstance(n_history, str) else math.nan
    except (TypeError, ValueError):
        count = math.nan
    whole = math.isfinite(count) and int(count) == count
    if not whole or count < 2 and not (optional and count == 0):
        raise ValueError(f"n_history must be {rule}; got {n_history!r}")
    return int(count)
