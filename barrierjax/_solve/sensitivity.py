"""Forward sensitivities: differentiate a solve of few scalar parameters in forward mode,
whichever way the caller differentiates.

Reverse mode through an adaptive ODE solve stores (or recomputes) every step; forward mode
carries the tangents along with the solution instead. With two or three parameters the
forward Jacobian is the cheaper of the two (few tangents, no stored steps), so the wrapped
function's JVP materialises that Jacobian and returns its product with the tangents. The
product is linear in the tangents and the Jacobian depends on the primals alone, so JAX
transposes it for `jax.grad` as J^T times the cotangent, never touching the solver's loop.
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np


def forward_jacobian_jvp(fn, n_differentiable=None, value_and_jacobian=None, arrays_from=None):
    """`fn(*scalars) -> PyTree` with a custom JVP built from its forward Jacobian.

    For scalars the primal is computed once, alongside all the directional derivatives (a
    `vmap` of `jax.jvp` over the unit directions), so every derivative costs one forward
    solve that carries `n_differentiable` tangents.

    `fn` may also take arrays of one shape holding independent problems, each output's
    leading axes that shape. The Jacobian is then taken problem by problem, and each
    direction is a problem of its own: one forward solve of `n_differentiable` copies of
    the batch, stacked along the leading axis, each copy carrying the tangent of one
    parameter. That repeats the primal arithmetic, but a tangent then has its primal's
    shape. With the directions as a `vmap` axis instead, XLA's CPU loop emitter (jax 0.10)
    recomputed the primal values inside the wide fusions of the tangents: a batch of 10
    oblique impacts took 0.90 s for its gradient against 7.9 ms forward (115 times, 650 at
    100); see benchmarks/README.md.

    Only the first `n_differentiable` arguments (default: all) are differentiated; the
    rest (tolerances, traced so that changing them does not recompile) get no derivative.
    `value_and_jacobian(*params) -> (out, jacobian)` (default `forward_jacobian` of `fn`)
    gives the primal and the Jacobian where one is differentiated: for example the same
    solve written to compile fast, where `fn` is written to run fast; and where it is a
    jitted function, every derivative of `fn`, whichever arguments carry tangents, runs one
    compiled program.

    With `arrays_from`, a `vmap` of the wrapped function over its first `n_differentiable`
    arguments, of that many problems or more, calls `fn` and `value_and_jacobian` on the
    arrays they map over (flattened into one axis of problems), where their own batching
    applies (sorted chunks, a queue), rather than the scalar solve under `vmap`, which
    steps every member until the slowest is done: a `vmap` of the gradient of 1,024 axial
    impacts took 18 minutes, against 54 s on the arrays.
    """
    if value_and_jacobian is None:
        value_and_jacobian = lambda *params: forward_jacobian(fn, params, n_differentiable)
    solve = fn
    if arrays_from is not None:
        solve = _batched_as_arrays(fn, n_differentiable, arrays_from)
        value_and_jacobian = _batched_as_arrays(
            value_and_jacobian, n_differentiable, arrays_from, directions_at=1
        )

    @jax.custom_jvp
    def wrapped(*params):
        return solve(*params)

    @wrapped.defjvp
    def _jvp(params, tangents):
        n = len(params) if n_differentiable is None else n_differentiable
        out, jacobian = value_and_jacobian(*params)
        leaves, tree = jax.tree.flatten(out)
        inexact = [jnp.issubdtype(o.dtype, jnp.inexact) for o in leaves]
        jacobians = [j for j, real in zip(tree.flatten_up_to(jacobian), inexact) if real]
        products = iter(_along(jacobians, jnp.stack(tangents[:n])))
        float0 = lambda o: np.zeros(o.shape, jax.dtypes.float0)  # counts and flags
        return out, tree.unflatten(
            [next(products) if real else float0(o) for o, real in zip(leaves, inexact)]
        )

    return wrapped


@jax.jit
def _along(jacobians, tangent):
    """Each Jacobian (directions leading) times the tangent: one program, not an operation
    at a time, where the JVP runs outside a jit."""
    weights = lambda j: tangent.reshape(tangent.shape + (1,) * (j.ndim - tangent.ndim))
    return [jnp.sum(weights(j) * j, axis=0) for j in jacobians]


def forward_jacobian(fn, params, n_differentiable=None):
    """(fn(*params), its Jacobian in the first `n_differentiable` params, directions
    leading), as `forward_jacobian_jvp` takes it."""
    n = len(params) if n_differentiable is None else n_differentiable
    inputs, fixed = params[:n], params[n:]
    basis = jnp.eye(n, dtype=jnp.result_type(*inputs))
    if jnp.ndim(inputs[0]) == 0:

        def along(direction):
            per_problem = tuple(d * jnp.ones_like(x) for d, x in zip(direction, inputs))
            return jax.jvp(lambda *x: fn(*x, *fixed), inputs, per_problem)

        return jax.vmap(along, out_axes=(None, 0))(basis)
    return _directions_as_problems(fn, inputs, fixed, basis)


def _directions_as_problems(fn, inputs, fixed, basis):
    """(fn(*inputs, *fixed), its Jacobian with the directions leading) from one solve of
    `len(basis)` copies of the batch `inputs`, copy k carrying the tangent of direction k."""
    n = len(basis)
    batch = jnp.shape(inputs[0])[0]
    stacked = tuple(jnp.concatenate([x] * n) for x in inputs)
    directions = tuple(
        jnp.concatenate([basis[k, i] * jnp.ones_like(x) for k in range(n)])
        for i, x in enumerate(inputs)
    )
    out, tangents = jax.jvp(lambda *x: fn(*x, *fixed), stacked, directions)
    first = jax.tree.map(lambda o: o[:batch], out)

    # (Counts' and flags' tangents too: float0, never read, but shaped as the others.)
    by_direction = lambda t: t.reshape((n, batch) + t.shape[1:])
    return first, jax.tree.map(by_direction, tangents)


def _batched_as_arrays(fn, n_problem, smallest, directions_at=None):
    """`fn`, whose `vmap` over its first `n_problem` arguments (those of them not mapped
    over broadcast) is `fn` called on them flattened into one axis of problems, the
    results' leading axes reshaped back. `directions_at`: the index of the one result that
    holds, per leaf, a leading axis of directions before the problems' (a Jacobian). A
    `vmap` over any other argument, or of fewer than `smallest` problems, batches `fn` as
    JAX does."""

    @jax.custom_batching.custom_vmap
    def batched(*args):
        return fn(*args)

    @batched.def_vmap
    def rule(axis_size, in_batched, *args):
        mapped = [any(jax.tree.leaves(b)) for b in in_batched]
        as_arrays = any(mapped) and not any(mapped[n_problem:])
        shape = (axis_size, *jnp.shape(args[mapped.index(True)])[1:]) if as_arrays else ()
        if not as_arrays or math.prod(shape) < smallest:
            axes = [jax.tree.map(lambda b: 0 if b else None, b) for b in in_batched]
            out = jax.vmap(fn, in_axes=tuple(axes))(*args) if any(mapped) else fn(*args)
            return out, jax.tree.map(lambda _: any(mapped), out)
        problems = [jnp.broadcast_to(a, shape).reshape(-1) for a in args[:n_problem]]
        # (Through `batched` again: an outer `vmap` then flattens its axis in too.)
        out = batched(*problems, *args[n_problem:])
        unflat = lambda leaf, lead=0: jnp.moveaxis(
            leaf.reshape(leaf.shape[:lead] + shape + leaf.shape[lead + 1 :]), lead, 0
        )
        if directions_at is None:
            out = jax.tree.map(unflat, out)
        else:
            leads = [int(k == directions_at) for k in range(len(out))]
            out = tuple(
                jax.tree.map(functools.partial(unflat, lead=lead), part)
                for part, lead in zip(out, leads)
            )
        return out, jax.tree.map(lambda _: True, out)

    return batched
