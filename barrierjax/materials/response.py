"""Stress history of a uniaxial law under a prescribed strain history.

Every law offers `init_state()` and the per-step update
`law.update(stress, state, d_strain, dt) -> (stress, state)`; `update_with_tangent` adds the
consistent tangent d(stress)/d(d_strain) of that discrete update (a forward-mode derivative, so
exact for the converged backward-Euler and return-mapping updates). Overstress laws also
offer `explicit_update`, `report_update` and the vector field `plastic_rate`.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check

METHODS = ("implicit", "report", "explicit", "diffrax")


class UniaxialResponse(eqx.Module):
    """One entry per sample time."""

    times: jnp.ndarray
    strain: jnp.ndarray
    stress: jnp.ndarray
    plastic_strain: jnp.ndarray


def update_with_tangent(law, stress, state, d_strain, dt):
    """`law.update` and its consistent tangent: (stress, state, d stress / d d_strain)."""
    (new_stress, new_state), (tangent, _) = jax.jvp(
        lambda de: law.update(stress, state, de, dt), (d_strain,), (jnp.ones_like(d_strain),)
    )
    return new_stress, new_state, tangent


def _stepper(law, method, iterations):
    if method == "implicit":
        return law.update
    if method == "explicit" and hasattr(law, "explicit_update"):
        return law.explicit_update
    if method == "report" and hasattr(law, "report_update"):
        return lambda *args: law.report_update(*args, iterations=iterations)
    raise ValueError(f"method must be 'implicit' for {type(law).__name__}; got {method!r}")


def _by_steps(law, times, strains, step, substeps, initial):
    stress0, state0 = initial

    def interval(carry, segment):
        dt, d_strain = segment

        def substep(carry, _):
            return step(*carry, d_strain / substeps, dt / substeps), None

        if substeps == 1:
            carry = step(*carry, d_strain, dt)
        else:
            carry = jax.lax.scan(substep, carry, None, length=substeps)[0]
        return carry, carry[0]

    _, stress = jax.lax.scan(interval, (stress0, state0), (jnp.diff(times), jnp.diff(strains)))
    return jnp.concatenate([stress0[None], stress])


def _by_diffrax(law, times, strains, initial, rtol, atol, max_steps, adjoint):
    import diffrax  # (on first use: see `_solve.phases`)

    if not hasattr(law, "plastic_rate"):
        raise ValueError(f"method must be 'implicit' for {type(law).__name__}; got 'diffrax'")
    if adjoint is None:
        adjoint = diffrax.RecursiveCheckpointAdjoint()
    slopes = jnp.diff(strains) / jnp.diff(times)
    last = times.shape[0] - 2

    def field(t, state, args):
        i = jnp.clip(jnp.searchsorted(times, t, side="right") - 1, 0, last)
        strain = strains[i] + slopes[i] * (t - times[i])
        stress = law.E * (strain - state.plastic_strain)
        return law.plastic_rate(stress, state, slopes[i])

    controller = diffrax.ClipStepSizeController(
        diffrax.PIDController(rtol=rtol, atol=atol, pcoeff=0.3, icoeff=0.4), jump_ts=times
    )
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(field),
        diffrax.Kvaerno5(),
        times[0],
        times[-1],
        (times[1] - times[0]) / 16,
        initial[1],
        saveat=diffrax.SaveAt(ts=times),
        stepsize_controller=controller,
        max_steps=max_steps,
        adjoint=adjoint,
    )
    return law.E * (strains - solution.ys.plastic_strain)


def uniaxial_response(
    law,
    times,
    strains,
    *,
    method="implicit",
    substeps=1,
    iterations=0,
    rtol=1e-8,
    atol=1e-12,
    max_steps=65536,
    adjoint=None,
):
    """Stress under the strain history through (times[i], strains[i]), linear in between.

    The material is virgin and unstressed at zero strain; strains[0] is applied at times[0]
    as an instantaneous step (dt = 0, elastic for every law here). Methods:
    - "implicit": `law.update` (backward Euler, return mapping, or the hereditary law's
      exponential update), `substeps` equal steps per sample interval;
    - "report": the report's scheme (4.2.8)-(4.2.10), with `iterations` of (4.2.11);
    - "explicit": forward Euler (to show where it fails);
    - "diffrax": Kvaerno5 with a PID controller (`rtol`, `atol` on the plastic strain; first
      step 1/16 of the first interval), steps
      clipped at the samples; `adjoint` defaults to diffrax's RecursiveCheckpointAdjoint (use
      `diffrax.ForwardMode()` under `jax.jacfwd`).
    "report", "explicit" and "diffrax" need an overstress law.
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}; got {method!r}")
    if int(substeps) < 1:
        raise ValueError(f"substeps must be a positive integer; got {substeps!r}")
    if np.ndim(times) != 1 or np.shape(times)[0] < 2:
        raise ValueError(f"times must be 1-d with at least 2 samples; got shape {np.shape(times)}")
    if np.shape(strains) != np.shape(times):
        raise ValueError(
            f"strains must have the shape of times {np.shape(times)}; got {np.shape(strains)}"
        )
    times = check("times", times, lambda t: t[1:] > t[:-1], "strictly increasing")
    strains = jnp.asarray(strains, dtype=times.dtype)
    zero = jnp.zeros_like(times[0])
    initial = law.update(zero, law.init_state(), strains[0], zero)

    if method == "diffrax":
        stress = _by_diffrax(law, times, strains, initial, rtol, atol, max_steps, adjoint)
    else:
        step = _stepper(law, method, iterations)
        stress = _by_steps(law, times, strains, step, int(substeps), initial)
    return UniaxialResponse(times, strains, stress, strains - stress / law.E)
