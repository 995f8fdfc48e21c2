"""The result of a normal impact (report 3.2, and 3.4 through `axial_impact`): its
fields (the vocabulary of `barrierjax.hinge.response`), its histories scaled by the
impact speed with the deflected shape built from them, and the rigid barrier of phi <= 1."""

import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..._custom_types import Scalar, Vector
from ..response import ImpactHistory, ImpactResult


class NormalImpactHistory(ImpactHistory):
    """Time histories of a normal impact, dimensionless (report 3.2 scales), under the
    names of `barrierjax.hinge.response.HISTORY_UNITS`.

    The first half of the samples covers the accelerative phase, the second the
    decelerative phase. Energies are in units of P_b L. Nothing slides: the tangential
    velocity, the position along the barrier, the friction and slope work are zero, and
    the two hinges are one distance. `deflected_shape[k, j]` is W(x[j], time[k]), x the
    distance from the impact point (the shape is symmetric about it) on `N_SHAPE` points
    from 0 to 1.25 times the final hinge distance.

    With axial force (report 3.4) a third block of `n_history` samples covers the
    plastic-string stage, before the final sample at rest; a stage that does not occur
    repeats the state it would have started from. `beam_kinetic_energy` is then the
    string's in that block, `string_work` the plastic work of stretching it since
    `t_string`, `axial_force` N/N0, `string_profile` (n_history, cells + 1) its
    displacement at the nodes X_j = s_final j / cells of the half-span during the string
    stage, and `string_flow_rule` (cells + 1) the share of each node's moving time in
    which the plastic flow lies outside the flow rule's corner cone, N0 eps' >= 2 M0
    |kappa'| (the report's (3.4.49), corrected: `string.py`).
    """

    axial_force: Vector | None = None
    string_profile: Float[Array, "samples nodes"] | None = None
    string_flow_rule: Float[Array, " nodes"] | None = None


class NormalImpact(ImpactResult):
    """Result of `normal_impact` and `axial_impact`, dimensionless, under the names of
    `barrierjax.hinge.response.RESULT_UNITS` (report 3.2 notation in brackets).

    - `damage`: vehicle crush D; `duration`: time of rest (T**);
    - `max_deflection`, `barrier_displacement`: the final displacement under the vehicle,
      the barrier's largest (W**);
    - `hinge_position`, `rear_hinge_position`: the final hinge distance (alpha), one each
      side;
    - `exit_speed`, `exit_angle_deg`: zero, the vehicle comes to rest with the barrier;
    - `crush_work, backing_work, hinge_work`: where the vehicle's kinetic energy
      mu V0^2 / 2 went, in units of P_b L (with axial force the hinge work includes the
      hinges' stretching, N times the beam's elongation); `friction_work`, `slope_work`:
      zero (nothing slides);
    - `string_work`: the plastic work of N0 stretching the string after `t_string`
      (3.4.45), 0 without a string stage;
    - `s_star, t_star, v_star, w_star`: hinge distance, time, beam velocity and beam
      displacement under the vehicle at the end of the accelerative phase (S*, T*, V*, W*);
    - `t_string`: with axial force (report 3.4), the time at which N reaches N0 and the
      beam becomes a plastic string; `inf` if it never does (and always without). The
      final state is then the string's: `hinge_position` is the span that moved,
      `damage` includes the crush in the string stage and, where the string began while
      the vehicle still crushed, `t_star`, `v_star` and `w_star` describe the beam at
      `t_string`;
    - `history`: a `NormalImpactHistory`, or None when not requested.

    With force ratio <= 1 the barrier stays rigid (no hinge: S = 0, W = 0) and the
    vehicle alone crushes to rest.
    """

    s_star: Scalar
    t_star: Scalar
    v_star: Scalar
    w_star: Scalar
    t_string: Scalar
    history: NormalImpactHistory | None


def normal_result(
    *, damage, duration, displacement, hinge, crush_work, backing_work, hinge_work, **rest
) -> NormalImpact:
    """A `NormalImpact` from the state at rest: the shared fields that a normal impact
    fixes (one hinge distance each side, no exit, no sliding) filled in."""
    zero = jnp.zeros_like(damage)
    return NormalImpact(
        damage=damage,
        duration=duration,
        max_deflection=displacement,
        barrier_displacement=displacement,
        hinge_position=hinge,
        rear_hinge_position=hinge,
        exit_speed=zero,
        exit_angle_deg=zero,
        crush_work=crush_work,
        backing_work=backing_work,
        hinge_work=hinge_work,
        friction_work=zero,
        slope_work=zero,
        **rest,
    )


def rigid_barrier(mu, phi, speed, n_history, string_cells=None) -> NormalImpact:
    """phi <= 1: the barrier never yields and the vehicle crushes to rest at P0 (with
    `string_cells`, the history has the blocks and fields of one with axial force, at
    N/N0 = 0 and without a string)."""
    zero = jnp.zeros_like(mu)
    t_stop = mu * speed / phi
    damage = 0.5 * mu * speed**2 / phi
    history = None
    if n_history:
        axial = string_cells is not None
        t = t_stop * jnp.linspace(0.0, 1.0, (3 if axial else 2) * n_history)
        vehicle = speed - phi / mu * t
        zeros = jnp.zeros_like(t)
        raw = dict(
            time=t,
            vehicle_velocity=vehicle,
            barrier_velocity=zeros,
            hinge=zeros,
            displacement=zeros,
            contact_force=jnp.full_like(t, phi),
            crush=speed * t - 0.5 * phi / mu * t**2,
            backing_work=zeros,
            hinge_work=zeros,
            beam_kinetic_energy=zeros,
        )
        if axial:
            raw |= dict(
                axial_force=zeros,
                string_work=zeros,
                profile=jnp.zeros((n_history, string_cells + 1)),
                flow_rule=jnp.zeros(string_cells + 1),
            )
        history = scaled_history(raw, mu, 1.0, zero, zero + jnp.inf)
    return normal_result(
        damage=damage,
        duration=t_stop,
        displacement=zero,
        hinge=zero,
        crush_work=phi * damage,
        backing_work=zero,
        hinge_work=zero,
        string_work=zero,
        s_star=zero,
        t_star=t_stop,
        v_star=zero,
        w_star=zero,
        t_string=zero + jnp.inf,
        history=history,
    )


def finish_history(raw, mu, phi, speed, acc, damage_per_speed2, s_final) -> NormalImpactHistory:
    """Add the contact force and the crush of 3.2 to speed-free histories, and scale."""
    s = raw["hinge"]
    n = s.shape[0] // 2
    in_first = jnp.arange(2 * n) < n
    force = jnp.where(in_first, phi, mu * (s**2 + 3.0) / (2.0 * s * (s + 2.0 * mu)))
    t1 = jnp.minimum(raw["time"], acc.t_star)
    crush = t1 - 0.5 * (acc.deceleration + acc.acceleration) * t1**2
    crush = jnp.where(in_first, crush, damage_per_speed2)
    raw = dict(raw, contact_force=force, crush=crush)
    return scaled_history(raw, mu, speed, s_final, jnp.full_like(mu, jnp.inf))


# The points of the deflected shape, from the impact point to 1.25 times the final hinge
# distance (the shape is zero beyond the hinge).
N_SHAPE, _SHAPE_REACH = 129, 1.25


def scaled_history(raw, mu, speed, s_final, t_string) -> NormalImpactHistory:
    """Speed-free histories (tau, v, w and works per unit speed) scaled by the impact
    speed, with the kinetic energies and the deflected shape. Without axial force (no
    `string_work` in `raw`) the string's fields are zero or None."""
    vehicle = raw["vehicle_velocity"] * speed
    beam = raw["barrier_velocity"] * speed
    if "beam_kinetic_energy" in raw:
        beam_kinetic_energy = raw["beam_kinetic_energy"] * speed**2
    else:
        beam_kinetic_energy = beam**2 * raw["hinge"] / 3.0  # v = V (1 - |X|/S) (3.2.1)
    displacement = raw["displacement"] * speed**2
    hinge_work = raw["hinge_work"] * speed**2
    crush = raw["crush"] * speed**2
    x = jnp.linspace(0.0, _SHAPE_REACH * s_final, N_SHAPE)
    shape = deflected_shape(x, raw["hinge"], displacement, hinge_work)
    profile = raw.get("profile")
    if profile is not None:
        profile = profile * speed**2
        shape = with_string_profile(shape, x, profile, s_final, t_string)
    zeros = jnp.zeros_like(vehicle)
    string_work = raw.get("string_work")
    return NormalImpactHistory(
        time=raw["time"] * speed,
        vehicle_velocity=vehicle,
        vehicle_tangential_velocity=zeros,
        vehicle_position=zeros,
        vehicle_displacement=displacement + crush,
        barrier_velocity=beam,
        barrier_displacement=displacement,
        contact_force=raw["contact_force"],
        crush=crush,
        hinge_position=raw["hinge"],
        rear_hinge_position=raw["hinge"],
        backing_work=raw["backing_work"] * speed**2,
        hinge_work=hinge_work,
        friction_work=zeros,
        slope_work=zeros,
        string_work=zeros if string_work is None else string_work * speed**2,
        beam_kinetic_energy=beam_kinetic_energy,
        vehicle_kinetic_energy=0.5 * mu * vehicle**2,
        x=x,
        deflected_shape=shape,
        axial_force=raw.get("axial_force"),
        string_profile=profile,
        string_flow_rule=raw.get("flow_rule"),
    )


def deflected_shape(x, hinge, displacement, hinge_work):
    """W(X, T) on the grid `x` from the histories of S, W and the hinge work (all
    dimensionless), for the velocity field V (1 - |X|/S) of (3.2.1).

    A point at X moves once the hinge has passed it (at T_X, with S(T_X) = X, or at T = 0
    if X <= S*), so W(X, T) = [W(T) - W(T_X)] - X [H(T) - H(T_X)] with H = integral V/S dT
    = 2 x hinge work. S is non-decreasing (the first sample of the decelerative phase
    repeats the last of the accelerative one), so W and H at hinge passage are
    interpolated against it."""
    h = 2.0 * hinge_work
    w_at_pass = jnp.interp(x, hinge, displacement, left=0.0)
    h_at_pass = jnp.interp(x, hinge, h, left=0.0)
    passed = x[None, :] <= hinge[:, None]
    shape = (displacement[:, None] - w_at_pass) - x * (h[:, None] - h_at_pass)
    return jnp.where(passed, jnp.maximum(shape, 0.0), 0.0)


def with_string_profile(shape, x, profile, s_final, t_string):
    """The deflected shape during the plastic-string stage, where the mechanism of (3.2.1)
    no longer holds: the string's own profile (at nodes spread over the final half-span),
    for the string block of the history and the state at rest after it (its last `n + 1`
    rows, n = profile rows), where the string was reached."""
    n = profile.shape[0]
    nodes = s_final * jnp.linspace(0.0, 1.0, profile.shape[1])
    on_grid = jax.vmap(lambda row: jnp.interp(x, nodes, row, right=0.0))(profile)
    string_rows = jnp.concatenate([on_grid, on_grid[-1:]])
    reached = jnp.isfinite(t_string)
    return shape.at[-(n + 1) :].set(jnp.where(reached, string_rows, shape[-(n + 1) :]))
