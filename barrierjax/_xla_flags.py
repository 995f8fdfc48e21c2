"""XLA options that barrierjax needs, set when the package is imported (before JAX creates
its CPU backend, where the user has not run a JAX computation yet).

`xla_cpu_enable_concurrency_optimized_scheduler=false`. XLA's CPU runtime (jaxlib 0.10.2)
runs a program's independent operations concurrently under its "concurrency-optimized"
scheduler, and with it the gradient of a `jax.vmap` of 16 beam runs (`beam.integrate`,
report Example 1) never finished: every thread of the pool waited for work while the caller
waited for the result. Without that scheduler the same program ran in 19 s the first time
and 12.6 s after, and the models' other programs were as fast as before. A later hang of
the same program, without the scheduler, showed the cause under gdb: both threads of the
two-thread pool inside jaxlib's batched LU factorisation (`lapack_dgetrf_ffi`), each waiting
for tasks that only the other could run, two independent factorisations having started at
once. The beam's step now orders its factorisations, and with that the program finishes
under the scheduler too (twice in two tries, 20 s each, 2026-11-27). The option stays off,
as the first fix left it: its removal was not tested further (benchmarks/README.md, "A
deadlock").

`xla_cpu_use_fusion_emitters=false`, on jaxlib 0.10 only. XLA's CPU compiler of jaxlib 0.10
emits each fusion through MLIR by default; with its older LLVM IR emitters the models'
first calls take 0.42 to 1.03 times as long (median 0.7) and 0.43 to 0.93 times the peak
memory (median 0.6), and most of their programs run as fast or faster
(benchmarks/README.md, "Twelfth pass"). Not the oblique model's batch: its step, thousands
of products fused for hundreds of lanes, ran 1.4 times slower, so that program asks for the
MLIR emitters back (`batched_step_options`). jaxlib 0.11.2 has dropped the option, and XLA
aborts the process on an option it does not know, so it is set only where it was found:
jaxlib 0.10.1 and 0.10.2.

`xla_cpu_prefer_vector_width=512`, for the oblique model's batch alone
(`batched_step_options`). XLA's CPU compiler asks LLVM for vectors of 256 bits unless told
otherwise; on a processor with AVX-512 (this project's 2-core machine, an AMD EPYC), 512
ran that batch 9 % faster, with the same results to the last bit: 1e4 scenarios at rtol
1e-6, 26.0 us a scenario against 28.6 (medians of five fresh processes each, in turn;
benchmarks/README.md, "Seventeenth pass"). Where the processor has no wider vectors, LLVM
keeps to the widths it has. The option is XLA's of long standing (its name is in the
libraries of jaxlib 0.10.2 and 0.11.2), so it is asked for on every jaxlib.
"""

import importlib.metadata
import os

_SCHEDULER = "xla_cpu_enable_concurrency_optimized_scheduler"
_FUSION_EMITTERS = "xla_cpu_use_fusion_emitters"
_VECTOR_WIDTH = "xla_cpu_prefer_vector_width"


def _jaxlib_minor() -> tuple[int, int] | None:
    try:
        major, minor = importlib.metadata.version("jaxlib").split(".")[:2]
        return int(major), int(minor)
    except (importlib.metadata.PackageNotFoundError, ValueError):
        return None


def default_flags() -> dict[str, str]:
    """The options `set_default_flags` adds, for the installed jaxlib."""
    flags = {_SCHEDULER: "false"}
    if _jaxlib_minor() == (0, 10):
        flags[_FUSION_EMITTERS] = "false"
    return flags


def batched_step_options() -> dict[str, bool | int]:
    """`jax.jit`'s `compiler_options` for a program that steps many scenarios side by side
    (the oblique model's batch): vectors of 512 bits, and XLA's MLIR fusion emitters (which
    run it faster than the LLVM IR ones `set_default_flags` chooses) on a jaxlib with that
    option, whatever `XLA_FLAGS` says for the other programs."""
    options: dict[str, bool | int] = {_VECTOR_WIDTH: 512}
    if _FUSION_EMITTERS in default_flags():
        options[_FUSION_EMITTERS] = True
    return options


def set_default_flags() -> None:
    """Add each of `default_flags()` to `XLA_FLAGS`, unless the variable already sets that
    option. It takes effect only where JAX has not yet run a computation in this process
    (XLA reads its flags once, when the backend starts): import barrierjax before your first
    JAX computation."""
    flags = os.environ.get("XLA_FLAGS", "")
    for name, value in default_flags().items():
        if name not in flags:
            flags = f"{flags} --{name}={value}".strip()
    os.environ["XLA_FLAGS"] = flags


set_default_flags()
