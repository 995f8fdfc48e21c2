"""The `barrierjax` command line.

    barrierjax run [SCENE.toml] [--json] [--out DIR] [--no-plots]
    barrierjax run cantilever-N [--rate-independent] [--scheme S] [--dt S] [--t-end S]
                                [--elements N] [--json] [--out DIR] [--no-plots]
    barrierjax assess RECORD.csv [--standard mash|en1317|nchrp350] [--cfc N]
                                 [--asi-edition 2010|1998] [--json] [--out DIR] [--no-plots]
    barrierjax figures [--out DIR] [--only NUMBER ...] [--jobs N]
    barrierjax optimize [SCENE.toml --level LEVEL] [--road-class C] [--deflection-limit L]
                        [--json]
    barrierjax sweep [SCENE.toml] --vary KEY=LOW:HIGH [--vary ...] --samples N [--seed S]
                     [--distribution uniform|lhs|normal] --out FILE [--resume]
                     [--coordinator HOST:PORT --processes N --process-id I]

`run` solves a scene file (the built-in default scene without one; format in
`barrierjax.scene_file`) with `barrierjax.simulate`, prints a summary (or one JSON object
in SI units with `--json`) and writes plots of the histories; `run cantilever-1` (-2, -3)
runs the report's beam Example 1 (2, 3) of 4.3 with `barrierjax.beam.report_example`
instead, in the report's inch-pound units. `figures` writes the
report's figures (`barrierjax.figures.FIGURES`). `optimize` runs the default barrier
design of `barrierjax.design`, or with `--level` the robust sizing of the scene's barrier. `sweep` solves a scene over ranges of its keys into a
Parquet or CSV file (`barrierjax.sweep`).

The command is thin: the work is done by public functions (`scene_file.load_scene`,
`simulate`, `result_dict`, `format_summary`, `plotting.write_run_plots`,
`figures.write_figures`). Progress goes to stderr, results to stdout. A bad scene file or
an unsupported scene ends with one line `error: [section] key: ...` on stderr and exit
status 2, never a traceback.

One module per command: `run` (and the scene summary, `result_dict`, `format_summary`),
`cantilever` (`run cantilever-N`), `figures`, `optimize`; `output` holds what they share
(`CommandError`, exit statuses, progress messages, double precision, printing results).
This package holds the parser and `main`.

Every command keeps what it compiles in JAX's persistent compilation cache
(`barrierjax.compilation_cache`: under the user's cache folder, `BARRIERJAX_CACHE_DIR` to
move it, `BARRIERJAX_CACHE_DIR=off` to go without), and the traced programs of the
models' entry points beside it (`keeping_programs`), so that its second run loads the models
instead of tracing and compiling them.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import NoReturn

from .. import compilation_cache
from .assess import assess_command
from .cantilever import (
    CANTILEVER,
    CANTILEVER_OPTIONS,
    NEWTON_WARNING,
    cantilever_dict,
    format_cantilever_summary,
)
from .figures import figures_command
from .optimize import optimize_command
from .output import (
    EXIT_FAILED,
    EXIT_OK,
    EXIT_USAGE,
    CommandError,
    check_out_folder,
    enable_x64,
)
from .run import STANDARD_GRAVITY, format_summary, result_dict, run_command
from .sweep import sweep_command

__all__ = [
    "CANTILEVER",
    "CANTILEVER_OPTIONS",
    "EXIT_FAILED",
    "EXIT_OK",
    "EXIT_USAGE",
    "NEWTON_WARNING",
    "STANDARD_GRAVITY",
    "CommandError",
    "build_parser",
    "cantilever_dict",
    "command",
    "format_cantilever_summary",
    "format_summary",
    "main",
    "result_dict",
]


def _add_command(commands, name, handler, *, json_help=None, out=None, **texts):
    """Add the command `name`, run as `handler(args)`, to the subparsers `commands`, with
    `texts` (help, description, epilog) for its help, and the options that commands share:
    with `json_help` (its help), the flag --json; with `out` = (default folder, what the
    command writes there), --out DIR. Returns the command's parser."""
    parser = commands.add_parser(name, **texts)
    if json_help is not None:
        parser.add_argument("--json", action="store_true", help=json_help)
    if out is not None:
        folder, contents = out
        parser.add_argument(
            "--out",
            type=Path,
            default=Path(folder),
            metavar="DIR",
            help=f"folder for the {contents} (default: ./{folder})",
        )
    parser.set_defaults(handler=handler, out_folder=out is not None)
    return parser


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the `barrierjax` command."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        release = version("barrierjax")
    except PackageNotFoundError:  # pragma: no cover - running from a bare checkout
        release = "unknown"
    parser = argparse.ArgumentParser(
        prog="barrierjax",
        description="Differentiable impact-dynamics models for highway barriers "
        "(rigid-plastic vehicle, beam and backing; report section 3.2).",
        epilog="Run 'barrierjax COMMAND --help' for a command's options.",
    )
    parser.add_argument("--version", action="version", version=f"barrierjax {release}")
    commands = parser.add_subparsers(title="commands", dest="command", metavar="COMMAND")

    run = _add_command(
        commands,
        "run",
        run_command,
        json_help="print one JSON object with the results in SI units (keys damage_m, "
        "max_deflection_m, duration_s, peak_deceleration_g, ...) and nothing else on stdout",
        out=("barrierjax-out", "plots"),
        help="simulate a scene file (or the default scene)",
        description="Simulate the impact of a vehicle on a barrier described by a TOML "
        "scene file, print a summary with units (or one JSON object in SI units), and "
        "write plots of the histories.",
        epilog="Scene file: sections [barrier] (plastic_moment, mass_per_length, "
        "backing_strength, axial_capacity optional), [vehicle] (mass, crush_force), "
        "[impact] (speed, angle optional, default '90 deg', friction optional, default 0); "
        'quantities are strings with units, e.g. plastic_moment = "105 kN*m", '
        'speed = "40 km/h", or inch-pound units such as "1e6 lbf*in". Without a file '
        "the default scene is run: a steel tube HSS 203x152x6.4 on a foam backing struck "
        "normally by a 2270 kg pickup at 40 km/h (barrierjax/default_scene.toml). "
        "Errors in the file exit with status 2 and one line naming the key.",
    )
    run.add_argument(
        "scene",
        nargs="?",
        type=Path,
        metavar="SCENE.toml",
        help="scene file (default: the built-in default scene)",
    )
    run.add_argument("--no-plots", action="store_true", help="do not write plots")
    run.add_argument("--rtol", type=float, metavar="R",
                     help="the impact model's relative tolerance (default: the model's, "
                     "1e-8 where it integrates in time): a scene run again at a smaller one "
                     "shows how far its results are from converged")  # fmt: skip
    beam = run.add_argument_group(
        "cantilever-N",
        "'barrierjax run cantilever-1' (-2, -3) runs the report's Example 1 (2, 3) of 4.3, "
        "a cantilever struck at its tip (barrierjax.beam.report_example), prints the tip's "
        "displacement at rest (at its largest deflection) and at the end in the report's inch-pound units, and "
        "writes deformed_shape.png, tip_histories.png and root_histories.png",
    )
    beam.add_argument(
        "--rate-independent",
        action="store_true",
        help="elastic-perfectly plastic at the static yield stress instead of Cowper-Symonds",
    )
    beam.add_argument(
        "--scheme",
        choices=("damped-newmark", "newmark", "linear-acceleration", "report"),
        help="time integration (default damped-newmark; 'report' is the report's scheme, "
        "unstable at its steps)",
    )
    beam.add_argument("--dt", type=float, metavar="S", help="step after the pulse (s)")
    beam.add_argument("--t-end", type=float, metavar="S", help="end of the run (s)")
    beam.add_argument("--elements", type=int, metavar="N", help="number of elements")

    assess = _add_command(
        commands,
        "assess",
        assess_command,
        json_help="print one JSON object in SI (t_impact, oiv_x, oiv_y, ora_x, ora_y, thiv, "
        "phd, asi, criteria, ...) and nothing else on stdout",
        out=("barrierjax-assess", "plots"),
        help="occupant risk of a crash-test accelerometer record (MASH, EN 1317)",
        description="Read a crash-test record (CSV with a header row: t, ax, ay and "
        "optionally az, yaw_rate, each optionally with its unit in brackets, e.g. "
        "'t [ms]', 'ax [g]', 'yaw_rate [deg/s]'; SI without), compute OIV, ORA, THIV, PHD "
        "and ASI, print them against the standard's limits and write plots.",
        epilog="Exit status: 0 the record passes every criterion, 1 it fails one, 2 the "
        "record cannot be assessed (one line says which column or row, and why).",
    )
    assess.add_argument("record", type=Path, metavar="RECORD.csv", help="the record")
    assess.add_argument(
        "--standard",
        choices=("mash", "en1317", "nchrp350"),
        default="mash",
        help="the limits to judge by (default mash)",
    )
    assess.add_argument(
        "--cfc",
        type=int,
        choices=(0, 60, 180, 600, 1000),
        default=180,
        help="SAE J211 channel filter class applied to the accelerations first (default "
        "180; 0 for none, a record already filtered)",
    )
    assess.add_argument(
        "--asi-edition",
        choices=("2010", "1998"),
        default="2010",
        help="EN 1317-1 edition of the ASI: 2010 (13 Hz filter, default) or 1998 (50 ms average)",
    )
    assess.add_argument("--no-plots", action="store_true", help="do not write plots")

    figures = _add_command(
        commands,
        "figures",
        figures_command,
        out=("barrierjax-figures", "figures"),
        help="write the report's figures as PNG files",
        description="Reproduce the report's figures (chapters 2 to 4) as PNG files named by "
        "figure number (fig_3_2_2.png, ...), printing each path written.",
    )
    figures.add_argument(
        "--only",
        nargs="+",
        metavar="NUMBER",
        help="figure numbers to write, e.g. 3.2.4 (default: all)",
    )
    figures.add_argument(
        "--jobs",
        type=int,
        metavar="N",
        help="processes drawing the figures side by side, each a chapter's at a time "
        "(default: one a core; 1 draws them all in this process)",
    )

    optimize = _add_command(
        commands,
        "optimize",
        optimize_command,
        json_help="print the report as one JSON object",
        help="size a barrier by gradients, checked by brute force",
        description="Without --level: size the default tube rail and backing for the least "
        "mean crush of two normal impacts under a deflection limit "
        "(barrierjax.design.optimize_default). With --level: size the scene's barrier (the "
        "default scene without one) for the least expected crush over real-world impacts "
        "(NCHRP Report 665 impact severity, US fleet mass) with every crash test of the "
        "MASH level meeting its criteria (barrierjax.design.optimize_robust); prints the "
        "design, each criterion's margin against the scene's own barrier, and the "
        "brute-force grid's check.",
    )
    optimize.add_argument("scene", nargs="?", type=Path, metavar="SCENE.toml",
                          help="the scene whose barrier and vehicle crush to start from "
                          "(with --level; default: the built-in default scene)")  # fmt: skip
    optimize.add_argument("--level", metavar="LEVEL",
                          help="a MASH test level, e.g. MASH-TL3")  # fmt: skip
    optimize.add_argument("--road-class", default="Interstate",
                          choices=("Interstate", "US Route", "State Route", "County Road",
                                   "City Street", "all"),
                          help="the impact-severity distribution's road class (NCHRP Report "
                          "665 Table 78; default Interstate)")  # fmt: skip
    optimize.add_argument("--deflection-limit", default="0.6 m", metavar="LENGTH",
                          help="the largest deflection allowed in a crash test (the site's "
                          "limit; default '0.6 m')")  # fmt: skip
    sweep = _add_command(
        commands,
        "sweep",
        sweep_command,
        help="solve a scene over ranges of its keys into a Parquet or CSV file",
        description="Draw --samples scenarios of the scene (the default scene without one) "
        "with each --vary key between its bounds, solve them in batches and write one row "
        "each (the varied inputs and every scalar result, SI) to --out, chunk by chunk: an "
        "interrupted sweep carries on with --resume. Prints a summary and plots each output "
        "against each input (OUT.png).",
    )
    sweep.add_argument("scene", nargs="?", type=Path, metavar="SCENE.toml",
                       help="the scene (default: the built-in default scene)")  # fmt: skip
    sweep.add_argument("--vary", action="append", metavar="KEY=LOW:HIGH",
                       help="a dotted scene key and its range, in the key's units or with "
                       "units: impact.speed=30km/h:60km/h, vehicle.mass=1000:2500")  # fmt: skip
    sweep.add_argument("--samples", type=int, required=True, metavar="N")
    sweep.add_argument("--seed", type=int, default=0, metavar="S")
    sweep.add_argument("--distribution", default="uniform",
                       help="uniform (default), lhs (Latin hypercube) or normal (mean at "
                       "the middle, the half-range two standard deviations, clipped)")  # fmt: skip
    sweep.add_argument("--out", type=Path, required=True, metavar="FILE",
                       help="the rows: FILE.parquet, or FILE.csv")  # fmt: skip
    sweep.add_argument("--resume", action="store_true",
                       help="carry on an interrupted sweep (its chunks in FILE.parts/)")  # fmt: skip
    sweep.add_argument("--chunk", type=int, default=65536, metavar="N",
                       help="scenarios solved at once (default 65536)")  # fmt: skip
    sweep.add_argument("--rtol", type=float, metavar="R",
                       help="the impact models' relative tolerance (default: each model's, "
                       "1e-8 where they integrate in time); looser runs faster: "
                       "benchmarks/README.md, 'Tolerance and speed', measures what each "
                       "costs and how far it moves the results")  # fmt: skip
    sweep.add_argument("--skip-failures", action="store_true",
                       help="a scenario the model cannot solve becomes a row of nulls with "
                       "its error in the column failure (default: it ends the sweep)")  # fmt: skip
    sweep.add_argument("--no-plots", action="store_true", help="do not write the plot")
    sweep.add_argument("--coordinator", metavar="HOST:PORT",
                       help="run as one of --processes processes (jax.distributed): the "
                       "address of process 0; start the same command on every host")  # fmt: skip
    sweep.add_argument("--processes", type=int, metavar="N", help="with --coordinator")
    sweep.add_argument("--process-id", type=int, metavar="I",
                       help="with --coordinator: this process, 0 to N-1 (0 writes the file)")  # fmt: skip
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the `barrierjax` command with `argv` (default: `sys.argv[1:]`); returns the
    exit status (0 success, 1 failure, 2 bad usage or bad scene)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # --help, --version, or a usage error already printed
        return exit_.code if isinstance(exit_.code, int) else EXIT_USAGE
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    enable_x64()
    from ..scene_file import SceneFileError

    try:
        if getattr(args, "out_folder", False) and not getattr(args, "no_plots", False):
            check_out_folder(args.out)
        with compilation_cache.keeping_programs():
            return args.handler(args)
    except SceneFileError as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_USAGE
    except CommandError as error:
        print(f"error: {error}", file=sys.stderr)
        return error.status
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


def command() -> NoReturn:
    """The `barrierjax` executable: `main()`, then out of the process at once, its output
    flushed. Python's own exit would first take jax, XLA and matplotlib apart, which adds
    about 0.3 s to every command (2 cores); nothing of the command is left to finish then
    (files are closed as they are written). An exception still exits as Python does."""
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
