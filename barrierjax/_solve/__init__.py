"""Shared numerical kernels: quadrature rules and the phase-switching ODE driver."""
