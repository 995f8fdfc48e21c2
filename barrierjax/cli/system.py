"""`barrierjax run SYSTEM.toml`: a crash test of a barrier system (`barrierjax.system`):
the summary with the verdict of each criterion, or one JSON object in SI, and the plots
(plan view, histories, the plan view animated)."""

from __future__ import annotations

import math
from pathlib import Path

from .output import EXIT_FAILED, CommandError, print_result, progress, progress_after

G = 9.80665

# The verdicts that the summary and the JSON give, against the test's standard (MASH's
# criteria where the scene names no test).
_CRITERIA = ("OIV", "ORA", "THIV", "ASI", "PHD")


def system_dict(scene, result, name: str) -> dict:
    """The run's crash-test numbers (SI), its energy audit, and the verdicts."""
    import jax
    import numpy as np

    from ..assess import judge
    from ..assess.verdict import standard_name
    from ..system.assessment import summary, system_exit_box, system_occupant_risk

    risk = system_occupant_risk(result)
    numbers = {k: v.item() for k, v in jax.tree.map(np.asarray, summary(result, risk)).items()}
    numbers["contained"] = bool(numbers["contained"])
    standard = "en1317" if scene.test and scene.test.startswith("EN") else "mash"
    criteria = judge(risk, standard)
    energies = {k: float(v) for k, v in result.energies.items()}
    box = system_exit_box(result, scene.vehicle, "MASH" if standard == "mash" else "CEN car")
    exit_box = None
    if box is not None:
        exit_box = {"passed": bool(box.passed), "largest_offset_m": float(box.largest_offset),
                    "margin_m": float(box.margin)}  # fmt: skip
    failed = np.asarray(result.failed_posts)
    return {
        "scene": name,
        "test": scene.test,
        "vehicle": scene.vehicle_name,
        "barrier": scene.barrier_name,
        "inputs": {
            "speed_m_s": scene.speed,
            "angle_deg": scene.angle_deg,
            "impact_point_m": scene.impact_point,
            "duration_s": scene.duration,
            "friction": scene.friction,
        },
        **numbers,
        "redirected": bool(numbers["contained"] and numbers["exit_angle"] < 0.0),
        "failed_posts": int(failed.sum()),
        "rail_tension_peak": float(np.max(np.asarray(result.history.rail_tension), initial=0.0)),
        "post_force_peak": float(
            np.max(np.abs(np.asarray(result.history.post_force)), initial=0.0)
        ),
        "kinetic_energy_J": float(result.kinetic_energy),
        "energies_J": energies,
        "energy_audit_error": float(np.max(np.abs(np.asarray(result.history.energy_error)))),
        "standard": standard_name(standard),
        "verdicts": {c.name: c.verdict for c in criteria},
        "exit_box": exit_box,
        "passed": bool(numbers["contained"])
        and all(c.passed for c in criteria)
        and (exit_box is None or exit_box["passed"]),
    }


def format_system_summary(data: dict) -> str:
    e, kinetic = data["energies_J"], data["kinetic_energy_J"]

    def share(joules):
        return f"{joules / 1e3:9.1f} kJ  {100 * joules / kinetic:5.1f} %"

    verdicts = ", ".join(f"{k} {v}" for k, v in data["verdicts"].items())
    inputs = data["inputs"]
    return "\n".join(
        [
            f"Scene: {data['scene']}" + (f"  ({data['test']})" if data["test"] else ""),
            (
                f"  vehicle {data['vehicle']} at {inputs['speed_m_s'] * 3.6:.1f} km/h and "
                f"{inputs['angle_deg']:.1f} deg into the {data['barrier']}, "
                f"{inputs['impact_point_m']:.2f} m along it"
            ),
            "",
            "Results (barrierjax.system; planar, after BARRIER VII)",
            f"  contained and redirected      {'yes' if data['redirected'] else 'NO'}",
            (
                f"  exit speed and angle          {data['exit_speed'] * 3.6:10.1f} km/h at "
                f"{data['exit_angle']:.1f} deg"
            ),
            f"  dynamic deflection            {data['dynamic_deflection']:10.3f} m",
            f"  working width (from the face) {data['working_width']:10.3f} m",
            f"  failed posts                  {data['failed_posts']:10d}",
            (
                f"  peak rail tension, post force {data['rail_tension_peak'] / 1e3:10.1f} kN "
                f"{data['post_force_peak'] / 1e3:7.1f} kN"
            ),
            f"  OIV x, y                      {data['oiv_x']:10.2f} {data['oiv_y']:7.2f} m/s",
            f"  ORA x, y                      {data['ora_x'] / G:10.2f} {data['ora_y'] / G:7.2f} g",
            (
                f"  THIV, PHD                     {data['thiv'] * 3.6:10.1f} km/h "
                f"{data['phd'] / G:6.2f} g"
            ),
            f"  ASI                           {data['asi']:10.2f}",
            f"  exit box                      {_exit_box_line(data['exit_box'])}",
            f"  {data['standard']}: {'pass' if data['passed'] else 'FAIL'} ({verdicts})",
            "",
            f"Energy audit (vehicle kinetic energy {kinetic / 1e3:.1f} kJ)",
            f"  rail (elastic and plastic)  {share(e['rail'])}",
            f"  posts                       {share(e['posts'])}",
            f"  anchors                     {share(e['anchors'])}",
            (
                f"  crush and rail friction     {share(e['contact'])}"
                f"   (friction {e['contact_friction'] / 1e3:.1f} kJ)"
            ),
            f"  tyres                       {share(e['tyres'])}",
            f"  kinetic at the end          {share(e['kinetic'])}",
            f"  largest remainder           {data['energy_audit_error']:.1e} of the initial",
        ]
    )


def _exit_box_line(box) -> str:
    if box is None:
        return "undetermined (still in contact at the end of the run)"
    verdict = "pass" if box["passed"] else "FAIL"
    return f"{verdict} (largest offset {box['largest_offset_m']:.2f} m, margin {box['margin_m']:.2f} m)"


def run_system(args, scene, name: str) -> int:
    """Run a `SystemScene`, print its summary or JSON, write its plots."""
    import jax

    from ..system import system_impact
    from ..system.plots import animate_plan_view, histories_figure, plan_view_figure

    try:
        with progress_after("compiling and solving the barrier system..."):
            result = system_impact(scene.vehicle, scene.barrier, speed=scene.speed,
                                   angle_deg=scene.angle_deg, impact_point=scene.impact_point,
                                   duration=scene.duration, friction=scene.friction)  # fmt: skip
            jax.block_until_ready(result)
    except ValueError as error:
        raise CommandError(" ".join(str(error).split())) from None
    data = system_dict(scene, result, name)
    bad = [k for k, v in data.items() if isinstance(v, float) and not math.isfinite(v)]
    if bad:
        raise CommandError(f"the solution is not finite ({', '.join(bad)})", EXIT_FAILED)
    plots = []
    if not args.no_plots:
        title = f"{Path(name).stem}: {data['vehicle']} into the {data['barrier']}"
        out = Path(args.out)
        figures = {"plan_view.png": lambda: plan_view_figure(result, scene.vehicle,
                                                            scene.barrier, title=title),
                   "histories.png": lambda: histories_figure(result, title=title)}  # fmt: skip
        for file, make in figures.items():
            progress(f"writing {out / file}")
            out.mkdir(parents=True, exist_ok=True)
            make().savefig(out / file, dpi=110)
            plots.append(out / file)
        progress(f"writing {out / 'plan_view.gif'}")
        plots.append(animate_plan_view(result, scene.vehicle, scene.barrier,
                                       out / "plan_view.gif", title=title))  # fmt: skip
    return print_result(args, data, plots, format_system_summary)
