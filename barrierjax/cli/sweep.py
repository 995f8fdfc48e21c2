"""`barrierjax sweep`: a scene over ranges of its keys into a Parquet (or CSV) file, with a
progress bar, resumable (`barrierjax.sweep`)."""

from __future__ import annotations

from pathlib import Path

from .output import EXIT_FAILED, EXIT_OK, EXIT_USAGE, CommandError, progress

__all__ = ["format_sweep_summary", "sweep_command"]


def format_sweep_summary(columns: dict, out: Path, seconds: float) -> str:
    """Each column's least, mean and largest value over the solved rows, where the rows
    went, and the rows skipped (`--skip-failures`: their `failure` is not empty)."""
    import numpy as np

    columns = dict(columns)
    failures = columns.pop("failure", None)
    n = len(next(iter(columns.values())))
    width = max(len(name) for name in columns)
    lines = [f"{n} scenarios in {seconds:.1f} s ({n / seconds:,.0f} per second) -> {out}"]
    failed = [] if failures is None else np.flatnonzero([bool(f) for f in failures])
    if len(failed):
        lines.append(f"{len(failed)} could not be solved (their results are null, their "
                     f"error in the column failure); the first, row {failed[0]}: "
                     f"{failures[failed[0]]}")  # fmt: skip
    lines += ["", f"{'column'.ljust(width)}  {'least':>12}  {'mean':>12}  {'largest':>12}"]
    for name, values in columns.items():
        values = np.asarray(values, float)
        lines.append(f"{name.ljust(width)}  {np.nanmin(values):12.5g}  "
                     f"{np.nanmean(values):12.5g}  {np.nanmax(values):12.5g}")  # fmt: skip
    return "\n".join(lines)


def _plot(columns: dict, inputs: list[str], path: Path):
    """Each output of note against each varied input, on a subsample of the rows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    varies = lambda name: name in columns and np.nanmax(columns[name]) > np.nanmin(columns[name])
    outputs = [name for name in ("damage", "max_deflection", "duration", "exit_angle_deg",
                                 "dynamic_deflection", "working_width", "exit_angle", "oiv_y")
               if varies(name)]  # fmt: skip
    n = len(columns[inputs[0]])
    rows = np.random.default_rng(0).choice(n, min(n, 20000), replace=False)
    fig, axes = plt.subplots(len(outputs), len(inputs), squeeze=False,
                             figsize=(3.2 * len(inputs), 2.4 * len(outputs)))  # fmt: skip
    for i, output in enumerate(outputs):
        for j, key in enumerate(inputs):
            ax = axes[i, j]
            ax.plot(columns[key][rows], columns[output][rows], ",", alpha=0.5)
            ax.set_xlabel(key if i == len(outputs) - 1 else "")
            ax.set_ylabel(output if j == 0 else "")
    fig.suptitle(f"{n} scenarios ({len(rows)} plotted)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _distributed(args) -> bool:
    """Join the processes of a multi-host sweep (`jax.distributed.initialize`) where
    --coordinator is given; returns whether this process leads (writes the files)."""
    options = (args.coordinator, args.processes, args.process_id)
    if all(option is None for option in options):
        return True
    if any(option is None for option in options):
        raise CommandError("--coordinator, --processes and --process-id go together", EXIT_USAGE)
    if not 0 <= args.process_id < args.processes:
        raise CommandError(
            f"--process-id must be in 0..{args.processes - 1}; got {args.process_id}", EXIT_USAGE
        )
    import jax

    # Collectives between CPU processes (the gather of each chunk) go through gloo; a
    # GPU's go through NCCL whatever this says.
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(args.coordinator, args.processes, args.process_id)
    return args.process_id == 0


def sweep_command(args) -> int:
    """`barrierjax sweep [SCENE.toml] --vary KEY=LOW:HIGH ... --samples N --out FILE`."""
    import time

    from tqdm import tqdm

    from .. import scene_file
    from ..hinge import SolveError
    from ..sweep import Sweep, SweepError, parse_vary, parts_folder, run_sweep

    lead = _distributed(args)
    fields = scene_file.FIELDS
    if args.scene is None:
        scene = scene_file.default_scene()
    else:
        from ..system.scene import is_system_scene, parse_system_scene

        data = scene_file.read_toml(args.scene)
        if is_system_scene(data):  # a crash test of a barrier system
            from ..system.sweep import SWEEP_FIELDS

            scene, fields = parse_system_scene(data), SWEEP_FIELDS
        else:
            scene = scene_file.parse_scene(data)
    try:
        varies = [parse_vary(text, fields) for text in args.vary or ()]
        sweep = Sweep(varies, args.samples, args.seed, args.distribution, args.chunk,
                      args.skip_failures, args.rtol)  # fmt: skip
        start = time.perf_counter()
        with tqdm(total=args.samples, unit="scenario", unit_scale=True, file=None,
                  desc="sweep", leave=False, disable=not lead) as bar:  # fmt: skip
            columns = run_sweep(scene, sweep, args.out, resume=args.resume, progress=bar.update)
        seconds = time.perf_counter() - start
    except SweepError as error:
        raise CommandError(str(error), EXIT_USAGE) from None
    except SolveError as error:  # a scenario the model could not solve
        raise CommandError(str(error), EXIT_FAILED) from None
    except KeyboardInterrupt:
        raise CommandError(
            f"interrupted: the finished chunks are in {parts_folder(args.out)}; "
            f"the same command with --resume carries on",
            130,
        ) from None
    if not lead:  # process 0 of a jax.distributed sweep writes, sums up and plots
        return EXIT_OK
    print(format_sweep_summary(columns, args.out, seconds))
    if not args.no_plots:
        path = args.out.with_suffix(".png")
        _plot(columns, [v.key for v in varies], path)
        progress(f"writing {path}")
    return EXIT_OK
