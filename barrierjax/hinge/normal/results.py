"""The result of a normal impact (report 3.2, and 3.4 through `axial_impact`): its
fields, its histories scaled by the impact speed, and the rigid barrier of phi <= 1."""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..._custom_types import Scalar, Vector


class NormalImpactHistory(eqx.Module):
    """Time histories of a normal impact, dimensionless (report 3.2 scales).

    The first half of the samples covers the accelerative phase, the second the
    decelerative phase. Energies are in units of P_b L.

    With axial force (report 3.4) a third block of `n_history` samples covers the
    plastic-string stage, before the final sample at rest; a stage that does not occur
    repeats the state it would have started from. `beam_kinetic_energy` is then the
    string's in that block, `string_work` the plastic work of stretching it since
    `t_string`, and `string_profile` (n_history, cells + 1) its displacement at the
    nodes X_j = s_final j / cells of the half-span during the string stage, and
    `string_flow_rule` (cells + 1) the share of each node's moving time in which the
    plastic flow lies outside the flow rule's corner cone, N0 eps' >= 2 M0 |kappa'|
    (the report's (3.4.49), corrected: `string.py`).
    """

    time: Vector
    vehicle_velocity: Vector
    barrier_velocity: Vector
    hinge: Vector
    displacement: Vector
    contact_force: Vector
    crush: Vector
    backing_work: Vector
    hinge_work: Vector
    beam_kinetic_energy: Vector
    vehicle_kinetic_energy: Vector
    axial_force: Vector | None = None  # N/N0, with axial force (report 3.4) only
    string_work: Vector | None = None
    string_profile: Float[Array, "samples nodes"] | None = None
    string_flow_rule: Float[Array, " nodes"] | None = None


class NormalImpact(eqx.Module):
    """Result of `normal_impact`, dimensionless (report 3.2 notation in brackets).

    - `s_star, t_star, v_star, w_star`: hinge distance, time, beam velocity and beam
      displacement under the vehicle at the end of the accelerative phase (S*, T*, V*, W*);
    - `damage`: vehicle crush D;
    - `s_final, t_final, w_final`: final hinge distance (alpha), time of rest (T**) and
      final displacement under the vehicle;
    - `crush_work, backing_work, hinge_work`: where the vehicle's kinetic energy
      mu V0^2 / 2 went, in units of P_b L (with axial force the hinge work includes the
      hinges' stretching, N times the beam's elongation);
    - `t_string`: with axial force (report 3.4), the time at which N reaches N0 and the
      beam becomes a plastic string; `inf` if it never does (and always without);
    - `string_work`: the plastic work of N0 stretching the string after `t_string`
      (3.4.45), 0 without a string stage. The final state is then the string's: `s_final`
      is the span that moved, `damage` includes the crush in the string stage and, where
      the string began while the vehicle still crushed, `t_star`, `v_star` and `w_star`
      describe the beam at `t_string`;
    - `history`: a `NormalImpactHistory`, or None when not requested.

    With force ratio <= 1 the barrier stays rigid (no hinge: S = 0, W = 0) and the
    vehicle alone crushes to rest.
    """

    s_star: Scalar
    t_star: Scalar
    v_star: Scalar
    w_star: Scalar
    damage: Scalar
    s_final: Scalar
    t_final: Scalar
    w_final: Scalar
    crush_work: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    t_string: Scalar
    string_work: Scalar
    history: NormalImpactHistory | None


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
        history = NormalImpactHistory(
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
            vehicle_kinetic_energy=0.5 * mu * vehicle**2,
            axial_force=zeros if axial else None,
            string_work=zeros if axial else None,
            string_profile=jnp.zeros((n_history, string_cells + 1)) if axial else None,
            string_flow_rule=jnp.zeros(string_cells + 1) if axial else None,
        )
    return NormalImpact(
        s_star=zero,
        t_star=t_stop,
        v_star=zero,
        w_star=zero,
        damage=damage,
        s_final=zero,
        t_final=t_stop,
        w_final=zero,
        crush_work=phi * damage,
        backing_work=zero,
        hinge_work=zero,
        t_string=zero + jnp.inf,
        string_work=zero,
        history=history,
    )


def finish_history(raw, mu, phi, speed, acc, damage_per_speed2) -> NormalImpactHistory:
    """Add the contact force and the crush of 3.2 to speed-free histories, and scale."""
    s = raw["hinge"]
    n = s.shape[0] // 2
    in_first = jnp.arange(2 * n) < n
    force = jnp.where(in_first, phi, mu * (s**2 + 3.0) / (2.0 * s * (s + 2.0 * mu)))
    t1 = jnp.minimum(raw["time"], acc.t_star)
    crush = t1 - 0.5 * (acc.deceleration + acc.acceleration) * t1**2
    crush = jnp.where(in_first, crush, damage_per_speed2)
    return scaled_history(dict(raw, contact_force=force, crush=crush), mu, speed)


def scaled_history(raw, mu, speed) -> NormalImpactHistory:
    """Speed-free histories (tau, v, w and works per unit speed) scaled by the impact
    speed, with the kinetic energies."""
    vehicle = raw["vehicle_velocity"] * speed
    beam = raw["barrier_velocity"] * speed
    if "beam_kinetic_energy" in raw:
        beam_kinetic_energy = raw["beam_kinetic_energy"] * speed**2
    else:
        beam_kinetic_energy = beam**2 * raw["hinge"] / 3.0  # v = V (1 - |X|/S) (3.2.1)
    string_work = raw.get("string_work")
    return NormalImpactHistory(
        time=raw["time"] * speed,
        vehicle_velocity=vehicle,
        barrier_velocity=beam,
        hinge=raw["hinge"],
        displacement=raw["displacement"] * speed**2,
        contact_force=raw["contact_force"],
        crush=raw["crush"] * speed**2,
        backing_work=raw["backing_work"] * speed**2,
        hinge_work=raw["hinge_work"] * speed**2,
        beam_kinetic_energy=beam_kinetic_energy,
        vehicle_kinetic_energy=0.5 * mu * vehicle**2,
        axial_force=raw.get("axial_force"),
        string_work=None if string_work is None else string_work * speed**2,
        string_profile=raw["profile"] * speed**2 if "profile" in raw else None,
        string_flow_rule=raw.get("flow_rule"),
    )
