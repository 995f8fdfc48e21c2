"""XLA options that barrierjax needs, set when the package is imported (before JAX creates
its CPU backend, where the user has not run a JAX computation yet).

XLA's CPU runtime (jaxlib 0.10.2) runs a program's independent operations concurrently
under its "concurrency-optimized" scheduler, and with it the gradient of a `jax.vmap` of 16
beam runs (`beam.integrate`, report Example 1) never finished: every thread of the pool
waited for work while the caller waited for the result. Without that scheduler the same
program ran in 19 s the first time and 12.6 s after, and the models' other programs were
as fast as before. A later hang of the same program, without the scheduler, showed the
cause under gdb: both threads of the two-thread pool inside jaxlib's batched LU
factorisation (`lapack_dgetrf_ffi`), each waiting for tasks that only the other could run,
two independent factorisations having started at once. The beam's step now orders its
factorisations, and with that the program finishes under the scheduler too (twice in two
tries, 20 s each, 2026-11-27). The option stays off, as the first fix left it: its
removal was not tested further (benchmarks/README.md, "A deadlock").
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
