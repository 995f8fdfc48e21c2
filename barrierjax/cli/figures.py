"""`barrierjax figures`: write the report's figures (`barrierjax.figures.FIGURES`).

The figures of one chapter module share programs (and some their runs), so a module's
figures are drawn by one process; with `--jobs N` (default: one a core) N processes draw
the modules' groups side by side, the largest first, each compiling what its own figures
need. On 2 cores all 25 took 69 s in one process the first time (20 s when the cache held
their programs), 48 s (14 s) in two."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed

from .._solve.batching import usable_cores
from .output import EXIT_OK, CommandError, enable_x64, progress

__all__ = ["figures_command"]


def figures_command(args) -> int:
    """`barrierjax figures [--out DIR] [--only NUMBER ...] [--jobs N]`: returns the exit
    status."""
    from .. import figures

    numbers = args.only or list(figures.FIGURES)
    unknown = [n for n in numbers if n not in figures.FIGURES]
    if unknown:
        raise CommandError(
            f"--only: no figure {', '.join(unknown)} (known: {', '.join(figures.FIGURES)})"
        )
    if args.jobs is not None and args.jobs < 1:
        raise CommandError(f"--jobs must be a positive integer; got {args.jobs}")
    groups = _groups(numbers)
    jobs = min(args.jobs or usable_cores(), len(groups))
    if jobs > 1:
        written = _write_in_processes(args.out, groups, jobs)
        paths = [written[number] for number in numbers]
    else:
        paths = figures.write_figures(
            args.out, numbers, progress=lambda p: progress(f"writing {p}")
        )
    for path in paths:
        print(path)
    return EXIT_OK


def _groups(numbers) -> list[list[str]]:
    """`numbers` by the chapter module that draws them, each in the registry's order; the
    groups with the most figures first."""
    from .. import figures

    by_module: dict[str, list[str]] = {}
    for number in numbers:
        by_module.setdefault(figures.FIGURES[number].make.__module__, []).append(number)
    return sorted(by_module.values(), key=len, reverse=True)


def _write_in_processes(out, groups, jobs) -> dict:
    """Each group written by one of `jobs` fresh processes; {number: path}."""
    written = {}
    spawn = multiprocessing.get_context("spawn")  # a forked JAX runtime is not safe
    with ProcessPoolExecutor(jobs, mp_context=spawn) as pool:
        pending = {pool.submit(_write_group, out, group): group for group in groups}
        for done in as_completed(pending):
            for number, path in zip(pending[done], done.result()):
                progress(f"wrote {path}")
                written[number] = path
    return written


def _write_group(out, numbers):
    """A worker's part: `numbers` written as the command writes them in its own process."""
    from .. import compilation_cache, figures

    enable_x64()
    with compilation_cache.keeping_programs():
        return figures.write_figures(out, numbers)
