"""`barrierjax run cantilever-N`: the report's cantilever examples (4.3), in its
inch-pound-second units (`barrierjax.beam.report_example`)."""

from __future__ import annotations

import math
import re

from .output import EXIT_FAILED, CommandError, as_float, print_result, progress, progress_after

__all__ = [
    "CANTILEVER",
    "CANTILEVER_OPTIONS",
    "NEWTON_WARNING",
    "cantilever_dict",
    "cantilever_number",
    "format_cantilever_summary",
    "run_cantilever",
]

CANTILEVER = re.compile(r"cantilever-(\d+)")
CANTILEVER_OPTIONS = ("rate_independent", "scheme", "dt", "t_end", "elements")
NEWTON_WARNING = 1e-6  # relative residual above which a step is reported unconverged


def cantilever_dict(n: int, result, *, rate_dependent: bool, scheme: str) -> dict:
    """Example `n`'s data and its run `result` (a `CantileverResult`) as a flat JSON-ready
    dict in the report's units (keys carry them: `_in`, `_s`, `_rad`, `_lb_in`)."""
    from ..beam.examples import (
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
        "end_time_s": as_float(times[-1]),
        "plastic_moment_lb_in": as_float(plastic_moment(n)),
        "tip_rest_time_s": rest.time if at_rest else None,
        "tip_rest_displacement_in": rest.tip_displacement.tolist() if at_rest else None,
        "root_rotation_at_rest_rad": rest.root_rotation if at_rest else None,
        "final_tip_displacement_in": [as_float(x) for x in result.tip_displacement[-1]],
        "final_tip_rotation_rad": as_float(result.tip_rotation[-1]),
        "final_root_rotation_rad": as_float(result.root_rotation[-1]),
        "peak_root_moment_lb_in": as_float(abs(result.root_moment).max()),
        "max_newton_residual": as_float(result.residual.max()),
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


def run_cantilever(args, n: int) -> int:
    """`barrierjax run cantilever-N` with N = `n`: run Example `n` of 4.3 with the options
    in `args`, write its plots and print its summary (or JSON); returns the exit status."""
    import jax

    from ..beam import report_example
    from ..beam.examples import plastic_moment
    from ..beam.plots import write_cantilever_plots

    _check_cantilever_options(args)
    rate_dependent = not args.rate_independent
    scheme = args.scheme or "damped-newmark"
    try:
        with progress_after(f"compiling and solving Example {n} of report 4.3..."):
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
            progress=lambda p: progress(f"writing {p}"),
        )
    return print_result(args, data, plots, format_cantilever_summary)


def cantilever_number(args) -> int | None:
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
