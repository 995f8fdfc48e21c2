"""Constitutive laws of dynamic plasticity (report chapter 2)."""
