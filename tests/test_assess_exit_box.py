"""Exit boxes: a straight exit path against its closed form, a path that leaves the box,
the oblique model's result, gradients and bad input."""

from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import barrierjax as bj
from barrierjax import scene_file
from barrierjax.assess import matrices
from barrierjax.assess.exit_box import exit_box_check, result_exit_box
from barrierjax.assess.matrices import EXIT_BOXES, mash_exit_box


def straight(offset0, angle_deg, length):
    along = jnp.linspace(0.0, length, 11)
    return along, offset0 + along * jnp.tan(jnp.radians(angle_deg))


def test_straight_path_closed_form():
    a, b = 5.0, 10.0
    along, offset = straight(1.5, 15.0, 4.0)  # sampled over 4 m, straight beyond
    check = exit_box_check(along, offset, a, b)
    expected = 1.5 + b * np.tan(np.radians(15.0))
    assert float(check.largest_offset) == pytest.approx(expected, rel=1e-12)
    assert bool(check.passed) and float(check.margin) == pytest.approx(a - expected, rel=1e-12)
    steep = exit_box_check(*straight(1.5, 25.0, 4.0), a, b)
    assert not bool(steep.passed) and float(steep.margin) < 0


def test_path_beyond_the_box_length_is_not_judged():
    along = jnp.asarray([0.0, 5.0, 10.0, 12.0, 20.0])
    offset = jnp.asarray([1.0, 2.0, 3.0, 9.0, 9.0])
    assert float(exit_box_check(along, offset, 4.0, 10.0).largest_offset) == 3.0


def test_a_path_sampled_across_the_box_end_is_judged_at_it():
    """A straight path rising at 15 degrees, sampled every 3 m past B = 10 m: its offset
    at B is the largest within the box, between the samples at 9 and 12 m (the sample
    at 9 m alone under-reads it by 1 m's rise). A vehicle at rest short of B stays put."""
    along = jnp.arange(0.0, 22.0, 3.0)
    offset = 1.5 + along * jnp.tan(jnp.radians(15.0))
    check = exit_box_check(along, offset, 5.0, 10.0)
    expected = 1.5 + 10.0 * np.tan(np.radians(15.0))
    assert float(check.largest_offset) == pytest.approx(expected, rel=1e-12)
    grad = jax.grad(lambda o: exit_box_check(along, o, 5.0, 10.0).margin)(offset)
    np.testing.assert_allclose(grad, -np.array([0, 0, 0, 2 / 3, 1 / 3, 0, 0, 0]), atol=1e-15)
    stopped = exit_box_check(
        jnp.asarray([0.0, 2.0, 4.0, 4.0]), jnp.asarray([1.0, 2.0, 2.5, 2.5]), 5.0, 10.0
    )
    assert float(stopped.largest_offset) == 2.5


def test_gradient_of_the_margin_in_the_exit_angle():
    def margin(angle):
        return exit_box_check(*straight(1.5, angle, 4.0), 5.0, 10.0).margin

    grad = float(jax.grad(margin)(15.0))
    expected = -10.0 / np.cos(np.radians(15.0)) ** 2 * np.pi / 180.0
    assert grad == pytest.approx(expected, rel=1e-10)


def test_the_exit_angle_counts_wherever_the_vehicle_leaves():
    """The straight exit path is judged over the box's whole length, wherever along the
    barrier the vehicle leaves: from x = 0.415 m, (x + B) - x rounds above B, and the
    check once dropped the path's far end, judging the exit offset alone."""
    history = SimpleNamespace(
        vehicle_displacement=jnp.asarray([0.0, 0.3]), vehicle_position=jnp.asarray([0.0, 0.0])
    )
    _, b = mash_exit_box(5.0, 2.0)
    for start in (0.0, 0.415, 0.54, 3.29565875):
        history.vehicle_position = jnp.asarray([0.0, start])
        result = SimpleNamespace(history=history, exit_angle_deg=jnp.asarray(15.0))
        check = result_exit_box(result, 5.0, 2.0)
        expected = 2.0 - 0.3 + b * np.tan(np.radians(15.0))
        assert float(check.largest_offset) == pytest.approx(expected, rel=1e-12), start


def test_oblique_result_against_its_exit_angle():
    """MASH 3-11 conditions (examples/oblique_scene.toml): the vehicle leaves at the
    result's exit angle; the box check is its straight line from the exit point."""
    scene = scene_file.load_scene("examples/oblique_scene.toml")
    result = bj.simulate(scene)
    pickup = matrices.test_vehicle("2270P", "mash")
    check = result_exit_box(result, pickup.length, pickup.width)
    a, b = mash_exit_box(pickup.length, pickup.width)
    exit_offset = pickup.width - float(result.history.vehicle_displacement[-1])
    expected = exit_offset + b * np.tan(np.radians(float(result.exit_angle_deg)))
    assert float(check.largest_offset) == pytest.approx(expected, rel=1e-12)
    assert bool(check.passed) == (expected <= float(a))
    assert set(EXIT_BOXES) == {"MASH", "CEN car", "CEN heavy"}


def test_bad_inputs():
    with pytest.raises(ValueError, match="along and offset must be 1-D paths"):
        exit_box_check(jnp.zeros(3), jnp.zeros(2), 1.0, 1.0)
    scene = scene_file.load_scene("examples/oblique_scene.toml")
    with pytest.raises(ValueError, match="box must be one of"):
        result_exit_box(bj.simulate(scene, n_history=0), 5.0, 2.0, box="ISO")
    with pytest.raises(ValueError, match="no history"):
        result_exit_box(bj.simulate(scene, n_history=0), 5.0, 2.0)
    # A negative or NaN box judged a path (margin -4.5 m, or NaN); a negative vehicle
    # width passed.
    path = jnp.linspace(0.0, 10.0, 5), jnp.zeros(5)
    boxes = ((-4.0, 10.0, "width_a"), (np.nan, 10.0, "width_a"), (4.0, 0.0, "length_b"))
    for width, length, name in boxes:
        with pytest.raises(ValueError, match=f"{name} must be positive and finite"):
            exit_box_check(*path, width, length)
    with pytest.raises(ValueError, match="vehicle_width must be positive and finite"):
        result_exit_box(bj.simulate(scene, n_history=0), 5.0, -2.0)
