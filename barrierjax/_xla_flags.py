"""XLA options that barrierjax needs, set when the package is imported (before JAX creates
its CPU backend, where the user has not run a JAX computation yet).

XLA's CPU runtime (jaxlib 0.10.2) runs a program's independent operations concurrently
under its "concurrency-optimized" scheduler, and with it the gradient of a `jax.vmap` of 16
beam runs (`beam.integrate`, report Example 1) never finishes: every thread of the pool
waits for work while the caller waits for the result (no CPU time is spent; 4 runs finish).
Without that scheduler the same program runs in 19 s the first time and 12.6 s after, and
the models' other programs are as fast as before (benchmarks/README.md, "A deadlock").
"""

import os

_SCHEDULER = "xla_cpu_enable_concurrency_optimized_scheduler"


def set_default_flags() -> None:
    """Add `--xla_cpu_enable_concurrency_optimized_scheduler=false` to `XLA_FLAGS`, unless
    the variable already sets that option. It takes effect only where JAX has not yet run a
    computation in this process (XLA reads its flags once, when the backend starts): import
    barrierjax before your first JAX computation."""
    flags = os.environ.get("XLA_FLAGS", "")
    if _SCHEDULER not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} --{_SCHEDULER}=false".strip()


set_default_flags()
