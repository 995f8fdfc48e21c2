"""One result vocabulary: every impact model, `simulate` and the CLI's JSON name the same
quantities alike (`barrierjax.hinge.response`), and each model's result closes the same
energy balance under those names."""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

import barrierjax as bj
from barrierjax.cli import result_dict
from barrierjax.hinge import axial_impact, normal_impact, oblique_impact
from barrierjax.hinge.response import HISTORY_UNITS, RESULT_UNITS, kinetic_energy_balance

MU, PHI, SPEED = 2.0, 3.0, 0.8

# n_history=200 throughout: `simulate` below then reuses these executables.
MODELS = {
    "normal, closed form": lambda: normal_impact(MU, PHI, SPEED, n_history=200),
    "normal, ode": lambda: normal_impact(MU, PHI, SPEED, method="ode", n_history=200),
    # A string stage: N reaches N0 (the speed is high enough for eta0 = 0.3).
    "axial": lambda: axial_impact(MU, PHI, 2.0, 0.3, n_history=200),
    "oblique": lambda: oblique_impact(MU, PHI, SPEED, 0.5, friction=0.2, rtol=1e-9, n_history=200),
}
SPEEDS = {
    "normal, closed form": (SPEED, 0.0),
    "normal, ode": (SPEED, 0.0),
    "axial": (2.0, 0.0),
    "oblique": (SPEED, 0.5),
}
# The balance holds to each model's accuracy: the string stage's discretisation (128
# cells) is the loosest.
BALANCE = {"normal, closed form": 1e-10, "normal, ode": 1e-7, "axial": 1e-4, "oblique": 1e-6}


def _names(module) -> set[str]:
    return {f.name for f in dataclasses.fields(module)}


@pytest.fixture(scope="module", params=list(MODELS))
def model(request):
    return request.param, MODELS[request.param]()


def test_every_model_result_has_the_shared_fields(model):
    name, result = model
    assert set(RESULT_UNITS) <= _names(result), name
    assert set(HISTORY_UNITS) <= _names(result.history), name
    n = result.history.time.shape[-1]
    for field in HISTORY_UNITS:
        value = getattr(result.history, field)
        expected = {"x": (value.shape[-1],), "deflected_shape": (n, result.history.x.shape[-1])}
        assert value.shape == expected.get(field, (n,)), (name, field)
        assert np.all(np.isfinite(value)), (name, field)


def test_every_model_closes_the_energy_balance_under_the_shared_names(model):
    name, result = model
    normal, tangential = SPEEDS[name]
    initial = 0.5 * MU * (normal**2 + tangential**2)
    error = kinetic_energy_balance(result, MU, normal, tangential)
    assert abs(float(error)) < BALANCE[name] * initial, name
    # And at every sample of the history (where the barrier still moves, its kinetic
    # energy counts).
    h = result.history
    spent = h.vehicle_kinetic_energy + h.beam_kinetic_energy + PHI * h.crush
    spent += sum(getattr(h, f) for f in HISTORY_UNITS if f.endswith("_work"))
    np.testing.assert_allclose(spent, initial, rtol=BALANCE[name] * 10, err_msg=name)


def test_a_normal_impact_fills_what_it_does_not_produce_with_zeros_or_equals(model):
    name, result = model
    if name == "oblique":
        assert float(result.string_work) == 0.0
        assert float(result.exit_speed) == pytest.approx(
            float(jnp.hypot(result.exit_normal_speed, result.exit_tangential_speed)), rel=1e-14
        )
        return
    for field in ("exit_speed", "exit_angle_deg", "friction_work", "slope_work"):
        assert float(getattr(result, field)) == 0.0, (name, field)
    assert float(result.rear_hinge_position) == float(result.hinge_position)
    assert float(result.max_deflection) == float(result.barrier_displacement)
    h = result.history
    assert np.all(h.vehicle_tangential_velocity == 0.0) and np.all(h.vehicle_position == 0.0)
    np.testing.assert_allclose(h.vehicle_displacement, h.barrier_displacement + h.crush)


SCENES = {
    "normal": bj.Scene(
        bj.Barrier(plastic_moment=105e3, mass_per_length=34.0, backing_strength=60e3),
        bj.Vehicle(mass=2270.0, crush_force=450e3),
        bj.Impact(speed=40 / 3.6),
    ),
}
SCENES["axial"] = eqx.tree_at(
    lambda s: s.barrier, SCENES["normal"], bj.Barrier(105e3, 34.0, 60e3, axial_capacity=1.5e6)
)
SCENES["oblique"] = eqx.tree_at(
    lambda s: s.impact, SCENES["normal"], bj.Impact(speed=40 / 3.6, angle_deg=25.0)
)
_SUFFIX = {"length": "_m", "time": "_s", "velocity": "_m_s", "energy": "_J", None: ""}


@pytest.mark.parametrize("kind", list(SCENES))
def test_simulate_and_the_cli_json_use_the_shared_names(kind):
    scene = SCENES[kind]
    # (n_history=200: the oblique scene shares the executable of MODELS["oblique"].)
    result = bj.simulate(scene, n_history=200)
    assert set(RESULT_UNITS) <= _names(result)
    assert _names(result.history) == set(HISTORY_UNITS)
    scales = result.groups.scales
    for field, unit in RESULT_UNITS.items():
        scale = 1.0 if unit is None else float(getattr(scales, unit))
        assert float(getattr(result, field)) == pytest.approx(
            float(getattr(result.model, field)) * scale, rel=1e-12, abs=1e-300
        ), (kind, field)
    data = result_dict(scene, result, kind)
    for field, unit in RESULT_UNITS.items():
        assert data[field + _SUFFIX[unit]] == pytest.approx(float(getattr(result, field)), rel=1e-12)
    assert abs(data["energy_balance_error_J"]) < 1e-4 * data["kinetic_energy_J"]


@pytest.mark.parametrize(
    "call",
    [
        lambda n: normal_impact(MU, PHI, SPEED, n_history=n),
        lambda n: axial_impact(MU, PHI, SPEED, 0.3, n_history=n),
        lambda n: oblique_impact(MU, PHI, SPEED, 0.5, n_history=n),
    ],
)
@pytest.mark.parametrize("n_history", [1, -2, 2.5, float("nan"), "20"])
def test_the_history_keyword_is_checked_alike(call, n_history):
    with pytest.raises(ValueError, match="n_history must be 0 or an integer >= 2"):
        call(n_history)


def test_moving_load_needs_a_history():
    from barrierjax.hinge import moving_load

    with pytest.raises(ValueError, match="n_history must be an integer >= 2"):
        moving_load(2.0, 1.0, 10.0, n_history=0)
