"""Shared numerical kernels: quadrature rules, the phase-switching ODE driver (diffrax), the
recorded step loop, Newton's method with its implicit derivative, and batching."""
