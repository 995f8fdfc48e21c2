"""The guardrail under a static point load (`barrierjax.system.static`): an elastic rail on
posts against an independent Euler-Bernoulli beam on elastic supports, closely spaced posts
against Hetenyi's beam on a continuous elastic foundation, and statics in the plastic range."""

import numpy as np
import pytest

from barrierjax import system
from barrierjax.materials.plasticity import RateIndependentPlasticity

E, A, I = 200e9, 1.29e-3, 1.4e-6


def _guardrail(spacing, spans, post_stiffness, *, yield_stress=1e12, post_strength=1e9,
               anchor=1e7, elements_per_span=4):  # fmt: skip
    section = system.rail_section(A, I, RateIndependentPlasticity(E, yield_stress))
    posts = system.post_springs(post_stiffness, post_strength, 10.0, 1e6, 1e9)
    return system.guardrail(spans * spacing, spacing, section=section, density=7850.0,
                            posts=posts, anchor_stiffness=anchor,
                            elements_per_span=elements_per_span)  # fmt: skip


def _beam_on_supports(x, posts, post_stiffness, anchor, load_node, load):
    """Lateral deflections at the nodes x of an Euler-Bernoulli beam (cubic elements, exact
    for nodal loads) on springs at the nodes `posts` and at both ends."""
    n, K = len(x), np.zeros((2 * len(x), 2 * len(x)))
    for e in range(n - 1):
        L = x[e + 1] - x[e]
        k = E * I / L**3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L**2, -6 * L, 2 * L**2],
                                     [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L**2, -6 * L, 4 * L**2]])  # fmt: skip
        K[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += k
    for p in posts:
        K[2 * p, 2 * p] += post_stiffness
    K[0, 0] += anchor
    K[-2, -2] += anchor
    P = np.zeros(2 * n)
    P[2 * load_node] = load
    return np.linalg.solve(K, P)[::2]


@pytest.mark.parametrize("where", ["mid-span", "post"])
def test_elastic_rail_on_posts_is_the_beam_on_elastic_supports(where):
    spacing, k = 1.905, 1.5e6
    g = _guardrail(spacing, 16, k)
    x = np.asarray(g.rail.coords)[:, 0]
    node = 34 if where == "mid-span" else 32  # 4 elements per span: node 32 is a post
    r = system.static_pushover(g, 1e3, x[node], increments=2)
    reference = _beam_on_supports(x, g.post_nodes, k, 1e7, node, 1e3)
    assert np.asarray(r.load) == pytest.approx([500.0, 1000.0])
    assert np.asarray(r.rail_deflection[-1]) == pytest.approx(
        reference, abs=1e-6 * np.max(reference)
    )
    assert float(r.displacement[-1]) == pytest.approx(reference[node], rel=1e-6)
    assert float(r.displacement[0]) == pytest.approx(reference[node] / 2, rel=1e-6)


def test_a_load_between_nodes_is_carried_as_the_cubic_interpolates_it():
    """At a quarter of an element, the consistent nodal forces: the nodes deflect as the
    reference beam's with one more node under the load (nodally exact for the cubic
    element); under the load itself, the cubic between the nodes is 1.2 % short of it."""
    spacing, k = 1.905, 1.5e6
    g = _guardrail(spacing, 8, k, elements_per_span=2)
    x = np.asarray(g.rail.coords)[:, 0]
    at = x[8] + 0.25 * (x[9] - x[8])
    r = system.static_pushover(g, 1e3, at, increments=1)
    refined = np.insert(x, 9, at)
    posts = [p if p <= 8 else p + 1 for p in g.post_nodes]
    reference = _beam_on_supports(refined, posts, k, 1e7, 9, 1e3)
    nodes = np.delete(reference, 9)
    assert np.asarray(r.rail_deflection[-1]) == pytest.approx(nodes, abs=1e-6 * np.max(nodes))
    assert float(r.displacement[-1]) == pytest.approx(reference[9], rel=2e-2)


def test_closely_spaced_posts_are_hetenyis_continuous_foundation():
    """Posts every 0.2 m with k = kf s: an infinite beam on a foundation of modulus kf
    deflects P beta / (2 kf) under the load, beta = (kf / 4 EI)^(1/4) (Hetenyi 1946). The
    rail is 40 m, 39 / beta, loaded at its middle; the discrete supports differ by
    O((beta s)^4)."""
    kf, spacing = 1e6, 0.2
    g = _guardrail(spacing, 200, kf * spacing, elements_per_span=1, anchor=0.0)
    beta = (kf / (4 * E * I)) ** 0.25
    r = system.static_pushover(g, 1e3, 20.0, increments=1)
    assert float(r.displacement[-1]) == pytest.approx(1e3 * beta / (2 * kf), rel=2e-3)


def test_the_posts_and_anchors_carry_the_load_past_yield():
    """Statics at every increment, the posts yielding and the rail bending plastically: the
    posts' lateral forces and the anchors' sum to the load; no post beyond its strength;
    the pushover stiffness falls as posts yield."""
    g = _guardrail(1.905, 8, 1.5e6, yield_stress=345e6, post_strength=20e3)
    x = np.asarray(g.rail.coords)[:, 0]
    r = system.static_pushover(g, 50e3, x[16], increments=20)
    post_force = np.asarray(r.post_force)
    anchors = 1e7 * np.asarray(r.rail_deflection)[:, [0, -1]].sum(1)
    assert post_force.sum(1) + anchors == pytest.approx(np.asarray(r.load), rel=1e-8)
    assert np.max(np.abs(post_force)) <= 20e3 * (1 + 1e-12)
    assert np.any(np.isclose(np.abs(post_force[-1]), 20e3))
    stiffness = np.diff(np.asarray(r.load), prepend=0.0) / np.diff(
        np.asarray(r.displacement), prepend=0.0
    )
    assert stiffness[-1] < 0.5 * stiffness[0]


def test_bad_pushover_inputs_name_the_field():
    g = _guardrail(1.905, 4, 1.5e6)
    with pytest.raises(ValueError, match="x must lie on the rail"):
        system.static_pushover(g, 1e3, 8.0)
    with pytest.raises(ValueError, match="force"):
        system.static_pushover(g, -1e3, 2.0)
    with pytest.raises(ValueError, match="more than the guardrail carries"):
        plastic = _guardrail(1.905, 4, 1.5e6, yield_stress=345e6, post_strength=20e3)
        system.static_pushover(plastic, 1e6, 3.81, increments=2)
    with pytest.raises(ValueError, match="increments"):
        system.static_pushover(g, 1e3, 2.0, increments=0)
