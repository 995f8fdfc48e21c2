"""The `barrierjax` command line.

    barrierjax run [SCENE.toml] [--json] [--out DIR] [--no-plots]
    barrierjax run cantilever-N [--rate-independent] [--scheme S] [--dt S] [--t-end S]
                                [--elements N] [--json] [--out DIR] [--no-plots]
    barrierjax figures [--out DIR] [--only NUMBER ...]
    barrierjax optimize [--json]

`run` solves a scene file (the built-in default scene without one; format in
`barrierjax.scene_file`) with `barrierjax.simulate`, prints a summary (or one JSON object
in SI units with `--json`) and writes plots of the histories; `run cantilever-1` (-2, -3)
runs the report's beam Example 1 (2, 3) of 4.3 with `barrierjax.beam.report_example`
instead, in the report's inch-pound units. `figures` writes the
report's figures (`barrierjax.figures.FIGURES`). `optimize` runs the default barrier
design of `barrierjax.design`.

The command is thin: the work is done by public functions (`scene_file.load_scene`,
`simulate`, `result_dict`, `format_summary`, `plotting.write_run_plots`,
`figures.write_figures`). Progress goes to stderr, results to stdout. A bad scene file or
an unsupported scene ends with one line `error: [section] key: ...` on stderr and exit
status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import re
import sys
import threading
from pathlib import Path

__all__ = ["STANDARD_GRAVITY", "format_summary", "main", "result_dict"]

STANDARD_GRAVITY = 9.80665  # m/s^2, to express decelerations in g

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class CommandError(Exception):
    """A failure to report in one line (`error: ...`) with an exit status, no traceback."""

    def __init__(self, message: str, status: int = EXIT_USAGE):
        super().__init__(" ".join(str(message).split()))
        self.status = status


def _progress(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


@contextlib.contextmanager
def _progress_after(message: str, delay: float = 0.2):
    """Print `message` to stderr if the block is still running after `delay` seconds, so
    that a scene refused at once ends with its one error line and nothing else."""
    timer = threading.Timer(delay, _progress, (message,))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def _enable_x64() -> None:
    import jax

    jax.config.update("jax_enable_x64", True)


# --------------------------------------------------------------------------------------
# The results of a run, as data and as text.


def _f(value) -> float:
    return float(value)


def result_dict(scene, result, name: str = "") -> dict:
    """The scene and its `simulate` result as a flat JSON-ready dict in SI units (keys
    carry the unit: `damage_m`, `duration_s`, `peak_deceleration_g`, energies in J)."""
    barrier, vehicle, impact = scene.barrier, scene.vehicle, scene.impact
    groups, scales = result.groups, result.groups.scales
    deceleration = _f(result.peak_deceleration)
    return {
        "scene": name,
        "model": (
            "oblique impact with convective terms (report 3.3)"
            if result.model.__class__.__name__ != "NormalImpact"
            else "normal impact, rigid-plastic vehicle, beam and backing (report 3.2)"
            if groups.axial_ratio is None
            else "normal impact on a beam held against axial motion (report 3.4)"
        ),
        "inputs": {
            "plastic_moment_N_m": _f(barrier.plastic_moment),
            "mass_per_length_kg_m": _f(barrier.mass_per_length),
            "backing_strength_N_m": _f(barrier.backing_strength),
            "axial_capacity_N": None
            if barrier.axial_capacity is None
            else _f(barrier.axial_capacity),
            "vehicle_mass_kg": _f(vehicle.mass),
            "crush_force_N": _f(vehicle.crush_force),
            "speed_m_s": _f(impact.speed),
            "angle_deg": _f(impact.angle_deg),
            "friction": _f(impact.friction),
        },
        "mass_ratio": _f(groups.mass_ratio),
        "force_ratio": _f(groups.force_ratio),
        "speed_dimensionless": _f(groups.normal_speed),
        "axial_ratio": None if groups.axial_ratio is None else _f(groups.axial_ratio),
        "length_scale_m": _f(scales.length),
        "force_scale_N": _f(scales.force),
        "time_scale_s": _f(scales.time),
        "damage_m": _f(result.damage),
        "max_deflection_m": _f(result.max_deflection),
        "duration_s": _f(result.duration),
        "accelerative_phase_s": _f(result.model.t_star * scales.time),
        "string_start_s": _string_start(result, scales),
        "peak_force_N": _f(result.peak_force),
        "peak_deceleration_m_s2": deceleration,
        "peak_deceleration_g": deceleration / STANDARD_GRAVITY,
        "hinge_extent_m": _f(result.hinge_extent),
        "exit_speed_m_s": _f(result.exit_speed),
        "exit_angle_deg": _f(result.exit_angle_deg),
        "kinetic_energy_J": _f(result.kinetic_energy),
        "crush_work_J": _f(result.crush_work),
        "backing_work_J": _f(result.backing_work),
        "hinge_work_J": _f(result.hinge_work),
        "friction_work_J": _f(result.friction_work),
        "slope_work_J": _f(result.slope_work),
        "string_work_J": _f(result.string_work),
        "exit_kinetic_energy_J": _f(0.5 * scene.vehicle.mass * result.exit_speed**2),
        "energy_balance_error_J": _f(
            result.crush_work
            + result.backing_work
            + result.hinge_work
            + result.friction_work
            + result.slope_work
            + result.string_work
            + 0.5 * scene.vehicle.mass * result.exit_speed**2
            - result.kinetic_energy
        ),
    }


def _string_start(result, scales) -> float | None:
    """When N reached N0 and the beam became a plastic string, or None if it never did."""
    t_string = getattr(result.model, "t_string", None)
    if t_string is None or not math.isfinite(float(t_string)):
        return None
    return _f(t_string * scales.time)


def _phases(data: dict) -> str:
    crushing = f"{data['accelerative_phase_s'] * 1e3:.1f} ms"
    string = data["string_start_s"]
    if string is None:
        return f"vehicle crushes for the first {crushing}"
    if string <= data["accelerative_phase_s"]:
        return f"plastic string from {string * 1e3:.1f} ms, in the crushing phase"
    return f"crushing phase {crushing}; plastic string from {string * 1e3:.1f} ms"


def format_summary(data: dict) -> str:
    """A readable summary of `result_dict(...)`: the scene, its dimensionless groups and
    the results with units, and where the vehicle's kinetic energy went."""
    i = data["inputs"]
    kinetic = data["kinetic_energy_J"]

    def share(joules):
        return f"{joules / 1e3:9.2f} kJ  {100.0 * joules / kinetic:5.1f} %"

    axial = i["axial_capacity_N"]
    lines = [
        f"Scene: {data['scene']}",
        f"  barrier  plastic moment    M0 = {i['plastic_moment_N_m'] / 1e3:10.2f} kN*m",
        f"           mass per length   m  = {i['mass_per_length_kg_m']:10.2f} kg/m",
        f"           backing strength  q0 = {i['backing_strength_N_m'] / 1e3:10.2f} kN/m",
        "           axial capacity    N0 = "
        + ("      none" if axial is None else f"{axial / 1e3:10.2f} kN"),
        f"  vehicle  mass              M  = {i['vehicle_mass_kg']:10.1f} kg",
        f"           crush force       P0 = {i['crush_force_N'] / 1e3:10.2f} kN",
        f"  impact   speed             v  = {i['speed_m_s']:10.3f} m/s"
        f" ({i['speed_m_s'] * 3.6:.1f} km/h)",
        f"           angle                = {i['angle_deg']:10.1f} deg",
        f"           friction             = {i['friction']:10.3f}",
        "",
        "Dimensionless groups (report 3.2)",
        f"  mass ratio   mu  = M / (m L)   = {data['mass_ratio']:.4g}",
        f"  force ratio  phi = P0 / P_b    = {data['force_ratio']:.4g}",
        f"  speed        V0  = v t0 / L    = {data['speed_dimensionless']:.4g}",
        *(
            []
            if data["axial_ratio"] is None
            else [f"  axial ratio  eta0 = N0 / P_b   = {data['axial_ratio']:.4g}"]
        ),
        f"  scales       L = {data['length_scale_m']:.4g} m, "
        f"P_b = {data['force_scale_N'] / 1e3:.4g} kN, t0 = {data['time_scale_s'] * 1e3:.4g} ms",
        "",
        f"Results: {data['model']}",
        f"  vehicle damage (crush)        {data['damage_m'] * 1e3:10.1f} mm",
        f"  max barrier deflection        {data['max_deflection_m'] * 1e3:10.1f} mm",
        f"  duration (contact to rest)    {data['duration_s'] * 1e3:10.1f} ms   ({_phases(data)})",
        f"  peak contact force            {data['peak_force_N'] / 1e3:10.1f} kN",
        f"  peak vehicle deceleration     {data['peak_deceleration_g']:10.1f} g"
        f"   ({data['peak_deceleration_m_s2']:.1f} m/s^2)",
        f"  hinge extent (each side)      {data['hinge_extent_m']:10.3f} m",
        f"  exit speed and angle          {data['exit_speed_m_s']:10.2f} m/s"
        f" at {data['exit_angle_deg']:.1f} deg",
        "",
        f"Energy partition (vehicle kinetic energy {kinetic / 1e3:.2f} kJ)",
        f"  vehicle crush          {share(data['crush_work_J'])}",
        f"  backing crush          {share(data['backing_work_J'])}",
        f"  beam plastic hinges    {share(data['hinge_work_J'])}",
        f"  friction               {share(data['friction_work_J'])}",
        f"  normal force x slope   {share(data['slope_work_J'])}",
        f"  plastic string         {share(data['string_work_J'])}",
        f"  kept by the vehicle    {share(data['exit_kinetic_energy_J'])}",
        f"  balance error          {data['energy_balance_error_J']:.2e} J",
    ]
    return "\n".join(lines)


# --------------------------------------------------------------------------------------
# Commands.


def _model_error(error: Exception) -> str:
    """The message a model raised at run time, without the traceback XLA wraps it in."""
    marker = "_EquinoxRuntimeError: "
    lines = [line for line in str(error).splitlines() if marker in line]
    return lines[-1].split(marker, 1)[1].strip() if lines else " ".join(str(error).split())


def _scene_error(error: Exception) -> CommandError:
    """A library error about a scene (ValueError, NotImplementedError), worded by the
    scene-file key it concerns."""
    from .scene_file import field_key

    message = " ".join(str(error).split())
    field = field_key(message)
    if field is not None:
        message = f"[{field.section}] {field.key}: {message}"
    return CommandError(message)


# --------------------------------------------------------------------------------------
# The report's cantilever examples (4.3), in its inch-pound-second units.

CANTILEVER = re.compile(r"cantilever-(\d+)")
CANTILEVER_OPTIONS = ("rate_independent", "scheme", "dt", "t_end", "elements")
NEWTON_WARNING = 1e-6  # relative residual above which a step is reported unconverged


def cantilever_dict(n: int, result, *, rate_dependent: bool, scheme: str) -> dict:
    """Example `n`'s data and its run `result` (a `CantileverResult`) as a flat JSON-ready
    dict in the report's units (keys carry them: `_in`, `_s`, `_rad`, `_lb_in`)."""
    from .beam.examples import (
        D_COWPER_SYMONDS,
        EXAMPLES,
        Q_COWPER_SYMONDS,
        plastic_moment,
        tip_rest,
    )

    data = EXAMPLES[n]
    rest = tip_rest(result)
    at_rest = rest.index >= 0
    times = result.times
    return {
        "example": n,
        "model": f"elastic-viscoplastic beam elements (report 4.2), Example {n} of 4.3",
        "law": f"Cowper-Symonds (4.3.1), D = {D_COWPER_SYMONDS:g} 1/s, q = {Q_COWPER_SYMONDS:g}"
        if rate_dependent
        else "elastic-perfectly plastic at the static yield stress",
        "scheme": scheme,
        "inputs": {
            "length_in": data["L"],
            "height_in": data["H"],
            "width_in": data["B"],
            "E_psi": data["E"],
            "sigma0_psi": data["sigma0"],
            "rho_lb_s2_in4": data["rho"],
            "tip_mass_lb_s2_in": data["tip_mass"],
            "impulse_lb_s": data["impulse"],
            "pulse_duration_s": data["duration"],
        },
        "n_elements": int(result.node_coordinates.shape[1] - 1),
        "saved_steps": int(times.shape[0] - 1),
        "end_time_s": _f(times[-1]),
        "plastic_moment_lb_in": _f(plastic_moment(n)),
        "tip_rest_time_s": rest.time if at_rest else None,
        "tip_rest_displacement_in": rest.tip_displacement.tolist() if at_rest else None,
        "root_rotation_at_rest_rad": rest.root_rotation if at_rest else None,
        "final_tip_displacement_in": [_f(x) for x in result.tip_displacement[-1]],
        "final_tip_rotation_rad": _f(result.tip_rotation[-1]),
        "final_root_rotation_rad": _f(result.root_rotation[-1]),
        "peak_root_moment_lb_in": _f(abs(result.root_moment).max()),
        "max_newton_residual": _f(result.residual.max()),
    }


def format_cantilever_summary(data: dict) -> str:
    """A readable summary of `cantilever_dict(...)`."""
    i = data["inputs"]
    rest = data["tip_rest_displacement_in"]
    final = data["final_tip_displacement_in"]
    lines = [
        f"Example {data['example']} of report 4.3: a cantilever struck at its tip",
        (
            f"  beam     L = {i['length_in']:g} in, H = {i['height_in']:g} in, "
            f"B = {i['width_in']:g} in, {data['n_elements']} elements"
        ),
        (
            f"           E = {i['E_psi']:.4g} psi, sigma0 = {i['sigma0_psi']:.5g} psi, "
            f"rho = {i['rho_lb_s2_in4']:.4g} lb s^2/in^4"
        ),
        f"           static plastic moment M0 = {data['plastic_moment_lb_in']:.4g} lb in",
        (
            f"  tip      mass {i['tip_mass_lb_s2_in']:.4g} lb s^2/in, impulse "
            f"{i['impulse_lb_s']:g} lb s over {i['pulse_duration_s'] * 1e3:g} ms"
        ),
        f"  law      {data['law']}",
        (
            f"  scheme   {data['scheme']}, {data['saved_steps']} steps to "
            f"{data['end_time_s'] * 1e3:g} ms"
        ),
        "",
        "Results",
    ]
    if rest is None:
        lines.append("  the tip has not come to rest by the end of the run (try a later --t-end)")
    else:
        lines += [
            f"  tip at rest (max deflection)  {data['tip_rest_time_s'] * 1e3:10.2f} ms",
            (
                f"  tip displacement then         {rest[1]:10.3f} in transverse, "
                f"{rest[0]:.3f} in axial"
            ),
            f"  root rotation then            {data['root_rotation_at_rest_rad']:10.4f} rad",
        ]
    lines += [
        f"  tip displacement at the end   {final[1]:10.3f} in transverse, {final[0]:.3f} in axial",
        f"  tip rotation at the end       {data['final_tip_rotation_rad']:10.4f} rad",
        f"  root rotation at the end      {data['final_root_rotation_rad']:10.4f} rad",
        (
            f"  peak root moment              {data['peak_root_moment_lb_in']:10.2f} lb in "
            f"({data['peak_root_moment_lb_in'] / data['plastic_moment_lb_in']:.3f} M0)"
        ),
        f"  largest Newton residual       {data['max_newton_residual']:10.2e} (relative)",
    ]
    if data["max_newton_residual"] > NEWTON_WARNING:
        lines.append(
            "  warning: Newton did not converge on some steps; a smaller --dt (more sub-steps) "
            "converges"
        )
    return "\n".join(lines)


def _check_cantilever_options(args) -> None:
    """Refuse bad step, end time and mesh at once, naming the option."""
    for flag, value in (("--dt", args.dt), ("--t-end", args.t_end)):
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise CommandError(f"{flag} must be positive and finite (seconds); got {value!r}")
    if args.elements is not None and args.elements < 1:
        raise CommandError(f"--elements must be a positive integer; got {args.elements!r}")


def _run_cantilever(args, n: int) -> int:
    import jax

    from .beam import report_example
    from .beam.examples import plastic_moment
    from .beam.plots import write_cantilever_plots

    _check_cantilever_options(args)
    rate_dependent = not args.rate_independent
    scheme = args.scheme or "damped-newmark"
    try:
        with _progress_after(f"compiling and solving Example {n} of report 4.3..."):
            result = report_example(
                n,
                rate_dependent=rate_dependent,
                scheme=scheme,
                dt=args.dt,
                t_end=args.t_end,
                n_elements=args.elements,
            )
            jax.block_until_ready(result)
    except ValueError as error:
        raise CommandError(f"cantilever-{n}: {error}") from None
    data = cantilever_dict(n, result, rate_dependent=rate_dependent, scheme=scheme)
    if not math.isfinite(data["final_tip_displacement_in"][1]):
        raise CommandError(
            f"cantilever-{n}: the solution is not finite (scheme {scheme!r}; the report's "
            "scheme is unstable at the report's steps)",
            EXIT_FAILED,
        )
    plots = []
    if not args.no_plots:
        law = "Cowper-Symonds" if rate_dependent else "elastic-perfectly plastic"
        plots = write_cantilever_plots(
            {law: result},
            plastic_moment(n),
            args.out,
            title=f"Example {n} of report 4.3 ({law}, {scheme})",
            progress=lambda p: _progress(f"writing {p}"),
        )
    return _report(args, data, plots, format_cantilever_summary)


def _report(args, data: dict, plots: list, summary) -> int:
    """Print a run's `data` (with its `plots`) as JSON, or as `summary(data)` and the plots."""
    data["plots"] = [str(p) for p in plots]
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(summary(data))
        if plots:
            print("\nPlots: " + ", ".join(str(p) for p in plots))
    return EXIT_OK


def _cantilever_number(args) -> int | None:
    """The example number of a `cantilever-N` scene argument, else None (after checking
    that no cantilever option was given with a scene file)."""
    match = None if args.scene is None else CANTILEVER.fullmatch(str(args.scene))
    if match is None:
        given = [o for o in CANTILEVER_OPTIONS if getattr(args, o) not in (None, False)]
        if given:
            flag = "--" + given[0].replace("_", "-")
            raise CommandError(f"{flag} applies to 'run cantilever-N' only, not to a scene")
        return None
    return int(match.group(1))


def _run(args) -> int:
    import jax

    from . import plotting, scene_file
    from .simulate import simulate

    n = _cantilever_number(args)
    if n is not None:
        return _run_cantilever(args, n)
    if args.scene is None:
        name = "default scene (barrierjax/default_scene.toml)"
        scene = scene_file.default_scene()
    else:
        name = str(args.scene)
        scene = scene_file.load_scene(args.scene)
    try:
        with _progress_after("compiling and solving the impact model (report 3.2/3.3)..."):
            result = simulate(scene)
            jax.block_until_ready(result)
    except jax.errors.JaxRuntimeError as error:  # a model's run-time check (equinox.error_if)
        raise CommandError(_model_error(error), EXIT_FAILED) from None
    except (NotImplementedError, ValueError) as error:
        raise _scene_error(error) from None
    data = result_dict(scene, result, name)
    bad = [k for k, v in data.items() if isinstance(v, float) and not math.isfinite(v)]
    if bad:
        raise CommandError(f"the solution is not finite ({', '.join(bad)})", EXIT_FAILED)
    plots = []
    if not args.no_plots:
        inputs = data["inputs"]
        angle = "" if inputs["angle_deg"] == 90.0 else f" at {inputs['angle_deg']:g} deg"
        title = (
            f"{Path(name).stem if args.scene else 'default scene'}: "
            f"{inputs['vehicle_mass_kg']:.0f} kg at {inputs['speed_m_s'] * 3.6:.1f} km/h"
            f"{angle} "
            rf"($\mu$ = {data['mass_ratio']:.3g}, $\phi$ = {data['force_ratio']:.3g})"
        )
        plots = plotting.write_run_plots(
            result, args.out, title=title, progress=lambda p: _progress(f"writing {p}")
        )
    return _report(args, data, plots, format_summary)


def _figures(args) -> int:
    from . import figures

    numbers = args.only or list(figures.FIGURES)
    unknown = [n for n in numbers if n not in figures.FIGURES]
    if unknown:
        raise CommandError(
            f"--only: no figure {', '.join(unknown)} (known: {', '.join(figures.FIGURES)})"
        )
    for path in figures.write_figures(
        args.out, numbers, progress=lambda p: _progress(f"writing {p}")
    ):
        print(path)
    return EXIT_OK


def _json_default(value):
    """Arrays and numpy scalars (as a design report may hold) as JSON numbers or lists."""
    import numpy as np

    array = np.asarray(value)
    if array.dtype.kind in "biuf":
        return array.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _optimize(args) -> int:
    import importlib

    try:
        design = importlib.import_module("barrierjax.design")
    except ModuleNotFoundError as error:
        if error.name not in ("barrierjax.design",):
            raise
        design = None
    optimize_default = getattr(design, "optimize_default", None)
    if optimize_default is None:
        raise CommandError(
            "optimize: barrierjax.design.optimize_default is not available in this version",
            EXIT_FAILED,
        )
    _progress("optimizing the default design (compiling the model and its gradient)...")
    report = optimize_default()
    if args.json:
        print(json.dumps(report.as_dict(), indent=2, default=_json_default))
    else:
        print(report.summary())
    return EXIT_OK


# --------------------------------------------------------------------------------------
# Parser and entry point.


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

    run = commands.add_parser(
        "run",
        help="simulate a scene file (or the default scene)",
        description="Simulate the impact of a vehicle on a barrier described by a TOML "
        "scene file, print a summary with units (or one JSON object in SI units), and "
        "write plots of the histories.",
        epilog="Scene file: sections [barrier] (plastic_moment, mass_per_length, "
        "backing_strength, axial_capacity optional), [vehicle] (mass, crush_force), "
        "[impact] (speed, angle optional, default '90 deg', friction optional, default 0); "
        "quantities are strings with units, e.g. plastic_moment = \"105 kN*m\", "
        "speed = \"40 km/h\", or inch-pound units such as \"1e6 lbf*in\". Without a file "
        "the default scene is run: a steel tube HSS 203x152x6.4 on a foam backing struck "
        "normally by a 2270 kg pickup at 40 km/h (barrierjax/default_scene.toml). "
        "Errors in the file exit with status 2 and one line naming the key.",
    )
    run.add_argument(
        "scene", nargs="?", type=Path, metavar="SCENE.toml",
        help="scene file (default: the built-in default scene)",
    )
    run.add_argument(
        "--json", action="store_true",
        help="print one JSON object with the results in SI units (keys damage_m, "
        "max_deflection_m, duration_s, peak_deceleration_g, ...) and nothing else on stdout",
    )
    run.add_argument(
        "--out", type=Path, default=Path("barrierjax-out"), metavar="DIR",
        help="folder for the plots (default: ./barrierjax-out)",
    )
    run.add_argument("--no-plots", action="store_true", help="do not write plots")
    beam = run.add_argument_group(
        "cantilever-N",
        "'barrierjax run cantilever-1' (-2, -3) runs the report's Example 1 (2, 3) of 4.3, "
        "a cantilever struck at its tip (barrierjax.beam.report_example), prints the tip's "
        "displacement at rest (at its largest deflection) and at the end in the report's inch-pound units, and "
        "writes deformed_shape.png, tip_histories.png and root_histories.png",
    )
    beam.add_argument(
        "--rate-independent", action="store_true",
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
    run.set_defaults(handler=_run)

    figures = commands.add_parser(
        "figures",
        help="write the report's figures as PNG files",
        description="Reproduce the report's figures (sections 3.2 and 3.3 so far) as PNG "
        "files named by figure number (fig_3_2_2.png, ...), printing each path written.",
    )
    figures.add_argument(
        "--out", type=Path, default=Path("barrierjax-figures"), metavar="DIR",
        help="folder for the figures (default: ./barrierjax-figures)",
    )
    figures.add_argument(
        "--only", nargs="+", metavar="NUMBER",
        help="figure numbers to write, e.g. 3.2.4 (default: all)",
    )
    figures.set_defaults(handler=_figures)

    optimize = commands.add_parser(
        "optimize",
        help="optimize the default barrier design",
        description="Size the default barrier with barrierjax.design.optimize_default "
        "and print its report.",
    )
    optimize.add_argument(
        "--json", action="store_true", help="print the report as one JSON object"
    )
    optimize.set_defaults(handler=_optimize)
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
    _enable_x64()
    from .scene_file import SceneFileError

    try:
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


if __name__ == "__main__":
    sys.exit(main())
