"""Quickstart: a steel-tube barrier on foam struck by a 2270 kg pickup (SI units)."""

import equinox as eqx
import jax
import jax.numpy as jnp

jax.config.update("jax_enable_x64", True)

import barrierjax as bj

barrier = bj.Barrier(plastic_moment=105.5e3, mass_per_length=34.2, backing_strength=60e3)
vehicle = bj.Vehicle(mass=2270.0, crush_force=450e3)
scene = bj.Scene(barrier, vehicle, bj.Impact(speed=40 / 3.6))  # normal impact, m/s

result = bj.simulate(scene)
g = result.groups
print(f"mu = {float(g.mass_ratio):.3g}, phi = {float(g.force_ratio):.3g}")
print(f"vehicle crush   {float(result.damage) * 1e3:7.1f} mm")
print(f"max deflection  {float(result.max_deflection) * 1e3:7.1f} mm")
print(f"duration        {float(result.duration) * 1e3:7.1f} ms")
print(f"deceleration    {float(result.peak_deceleration) / 9.80665:7.1f} g")

# A sweep over impact speed: vmap over a Scene whose impact speed is an array.
speeds = jnp.linspace(20.0, 100.0, 9) / 3.6
scenes = bj.Scene(barrier, vehicle, bj.Impact(speed=speeds))
axes = jax.tree.map(lambda _: None, scenes)  # map over the speed only
axes = eqx.tree_at(lambda s: s.impact.speed, axes, 0, is_leaf=lambda x: x is None)
sweep = jax.vmap(lambda s: bj.simulate(s, n_history=0), in_axes=(axes,))(scenes)
for v, w in zip(speeds * 3.6, sweep.max_deflection):
    print(f"{float(v):5.0f} km/h -> deflection {float(w) * 1e3:6.0f} mm")
