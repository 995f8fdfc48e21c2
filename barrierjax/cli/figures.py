"""`barrierjax figures`: write the report's figures (`barrierjax.figures.FIGURES`)."""

from __future__ import annotations

from .output import EXIT_OK, CommandError, progress

__all__ = ["figures_command"]


def figures_command(args) -> int:
    """`barrierjax figures [--out DIR] [--only NUMBER ...]`: returns the exit status."""
    from .. import figures

    numbers = args.only or list(figures.FIGURES)
    unknown = [n for n in numbers if n not in figures.FIGURES]
    if unknown:
        raise CommandError(
            f"--only: no figure {', '.join(unknown)} (known: {', '.join(figures.FIGURES)})"
        )
    for path in figures.write_figures(
        args.out, numbers, progress=lambda p: progress(f"writing {p}")
    ):
        print(path)
    return EXIT_OK
