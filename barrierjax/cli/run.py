"""`barrierjax run [SCENE.toml]`: solve a scene with `barrierjax.simulate`, print its
summary (`result_dict`, `format_summary`) or one JSON object, and write its plots
(`run cantilever-N` is handed to `barrierjax.cli.cantilever`)."""

from __future__ import annotations

import math
from pathlib import Path

import jax
import numpy as np

from .. import _checks
from ..hinge import SolveError
from ..hinge.oblique import ObliqueImpact
from ..hinge.response import RESULT_UNITS, kinetic_energy_balance
from .cantilever import cantilever_number, run_cantilever
from .output import EXIT_FAILED, CommandError, as_float, print_result, progress, progress_after

__all__ = [
    "STANDARD_GRAVITY",
    "format_summary",
    "occupant_risk_dict",
    "result_dict",
    "run_command",
]

STANDARD_GRAVITY = 9.80665  # m/s^2, to express decelerations in g

# The SI unit that `result_dict`'s key of each scale's field ends with.
_SI_SUFFIX = {"length": "_m", "time": "_s", "velocity": "_m_s", "energy": "_J", None: ""}


def _model_name(result) -> str:
    if isinstance(result.model, ObliqueImpact):
        return "oblique impact with convective terms (report 3.3)"
    if result.groups.axial_ratio is not None:
        return "normal impact on a beam held against axial motion (report 3.4)"
    return "normal impact, rigid-plastic vehicle, beam and backing (report 3.2)"


def result_dict(scene, result, name: str = "") -> dict:
    """The scene and its `simulate` result as a flat JSON-ready dict in SI units: every
    field of the one result vocabulary (`barrierjax.hinge.response.RESULT_UNITS`) under
    its name with its unit appended (`damage_m`, `duration_s`, `exit_speed_m_s`,
    `crush_work_J`, `exit_angle_deg`), and what the scene alone fixes
    (`peak_deceleration_g`, `kinetic_energy_J`, the energy balance's error)."""
    # (In numpy: each eager JAX operation would be an executable of its own to compile.)
    scene, result = jax.tree.map(np.asarray, (scene, result))
    barrier, vehicle, impact = scene.barrier, scene.vehicle, scene.impact
    groups, scales = result.groups, result.groups.scales
    deceleration = as_float(result.peak_deceleration)
    return {
        "scene": name,
        "model": _model_name(result),
        "inputs": {
            "plastic_moment_N_m": as_float(barrier.plastic_moment),
            "mass_per_length_kg_m": as_float(barrier.mass_per_length),
            "backing_strength_N_m": as_float(barrier.backing_strength),
            "axial_capacity_N": None
            if barrier.axial_capacity is None
            else as_float(barrier.axial_capacity),
            "vehicle_mass_kg": as_float(vehicle.mass),
            "crush_force_N": as_float(vehicle.crush_force),
            "speed_m_s": as_float(impact.speed),
            "angle_deg": as_float(impact.angle_deg),
            "friction": as_float(impact.friction),
        },
        "mass_ratio": as_float(groups.mass_ratio),
        "force_ratio": as_float(groups.force_ratio),
        "speed_dimensionless": as_float(groups.normal_speed),
        "axial_ratio": None if groups.axial_ratio is None else as_float(groups.axial_ratio),
        "length_scale_m": as_float(scales.length),
        "force_scale_N": as_float(scales.force),
        "time_scale_s": as_float(scales.time),
        **{
            name + _SI_SUFFIX[unit]: as_float(getattr(result, name))
            for name, unit in RESULT_UNITS.items()
        },
        "accelerative_phase_s": as_float(result.model.t_star * scales.time),
        "string_start_s": _string_start(result, scales),
        "peak_force_N": as_float(result.peak_force),
        "peak_deceleration_m_s2": deceleration,
        "peak_deceleration_g": deceleration / STANDARD_GRAVITY,
        "kinetic_energy_J": as_float(result.kinetic_energy),
        "exit_kinetic_energy_J": as_float(0.5 * scene.vehicle.mass * result.exit_speed**2),
        "energy_balance_error_J": as_float(
            -kinetic_energy_balance(result, scene.vehicle.mass, scene.impact.speed)
        ),
    }


_RISK_KEYS = {"t_impact": "t_impact_s", "oiv_x": "oiv_x_m_s", "oiv_y": "oiv_y_m_s",
              "ora_x": "ora_x_m_s2", "ora_y": "ora_y_m_s2", "t_head": "t_head_s",
              "thiv": "thiv_m_s", "phd": "phd_m_s2", "asi": "asi"}  # fmt: skip


def occupant_risk_dict(result) -> dict:
    """The occupant risk of a `simulate` result (`barrierjax.assess.assess`), SI, with the
    verdicts of MASH and EN 1317 (`barrierjax.assess.judge`)."""
    from ..assess import assess, judge
    from ..assess.verdict import standard_name

    risk = jax.tree.map(np.asarray, assess(result))
    data = {key: as_float(getattr(risk, name)) for name, key in _RISK_KEYS.items()}
    data["impact_within_history"] = bool(risk.impact_in_record)
    for standard in ("mash", "en1317"):
        criteria = judge(risk, standard)
        data[standard_name(standard)] = {
            "passed": all(c.passed for c in criteria),
            "criteria": {c.name: c.verdict for c in criteria},
        }
    return data


def _occupant_risk_lines(risk: dict) -> list[str]:
    g = STANDARD_GRAVITY
    after = "" if risk["impact_within_history"] else " (after the vehicle stopped)"
    mash = ", ".join(f"{k} {v}" for k, v in risk["MASH"]["criteria"].items())
    en = ", ".join(f"{k} {v}" for k, v in risk["EN 1317"]["criteria"].items())
    return [
        "",
        "Occupant risk (barrierjax.assess; the vehicle's acceleration from the history)",
        f"  occupant impact               {risk['t_impact_s'] * 1e3:10.1f} ms{after}",
        f"  OIV x, y                      {risk['oiv_x_m_s']:10.2f} {risk['oiv_y_m_s']:7.2f} m/s",
        f"  ORA x, y                      {risk['ora_x_m_s2'] / g:10.2f} {risk['ora_y_m_s2'] / g:7.2f} g",
        f"  THIV, PHD                     {risk['thiv_m_s'] * 3.6:10.1f} km/h {risk['phd_m_s2'] / g:6.2f} g",
        f"  ASI                           {risk['asi']:10.2f}",
        f"  MASH     {'pass' if risk['MASH']['passed'] else 'FAIL'}: {mash}",
        f"  EN 1317  {'pass' if risk['EN 1317']['passed'] else 'FAIL'}: {en}",
    ]


def _string_start(result, scales) -> float | None:
    """When N reached N0 and the beam became a plastic string, or None if it never did."""
    t_string = getattr(result.model, "t_string", None)
    if t_string is None or not math.isfinite(float(t_string)):
        return None
    return as_float(t_string * scales.time)


def _phases(data: dict) -> str:
    crushing = f"{data['accelerative_phase_s'] * 1e3:.1f} ms"
    string = data["string_start_s"]
    if string is None:
        if data["axial_ratio"] is not None and _crushes_to_rest(data):
            return f"vehicle crushes to rest; the axial force stopped the beam at {crushing}"
        return f"vehicle crushes for the first {crushing}"
    if string <= data["accelerative_phase_s"]:
        return f"plastic string from {string * 1e3:.1f} ms, in the crushing phase"
    return f"crushing phase {crushing}; plastic string from {string * 1e3:.1f} ms"


def _crushes_to_rest(data: dict) -> bool:
    """Whether the vehicle crushed at its crush force from impact to rest, which then took
    M v / P: with axial force, where the beam stopped first and locked (`axial_impact`).
    Where its crushing ends before, the force on it falls below P and it stops later."""
    i = data["inputs"]
    stop = i["vehicle_mass_kg"] * i["speed_m_s"] / i["crush_force_N"]
    return abs(data["duration_s"] - stop) <= 1e-6 * stop


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
        f"  hinges at rest, ahead/behind  {data['hinge_position_m']:10.3f} m"
        f" / {data['rear_hinge_position_m']:.3f} m",
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
    if "occupant_risk" in data:
        lines += _occupant_risk_lines(data["occupant_risk"])
    return "\n".join(lines)


def model_error(error: Exception) -> str:
    """The message a model raised at run time, without the traceback XLA (or equinox's
    own jit) wraps it in."""
    marker = "EquinoxRuntimeError: "
    lines = [line for line in str(error).splitlines() if marker in line]
    return lines[-1].split(marker, 1)[1].strip() if lines else " ".join(str(error).split())


def _scene_error(error: Exception) -> CommandError:
    """A library error about a scene (ValueError, NotImplementedError), worded by the
    scene-file key it concerns."""
    from ..scene_file import field_key

    message = " ".join(str(error).split())
    field = field_key(message)
    if field is not None:
        message = f"[{field.section}] {field.key}: {message}"
    return CommandError(message)


def _tolerance(rtol: float | None) -> float | None:
    try:
        return None if rtol is None else _checks.tolerance("--rtol", rtol)
    except ValueError as error:
        raise CommandError(str(error)) from None


def run_command(args) -> int:
    """`barrierjax run [SCENE.toml | cantilever-N]`: returns the exit status."""
    import jax

    from .. import plotting, scene_file
    from ..simulate import simulate

    n = cantilever_number(args)
    rtol = _tolerance(args.rtol)
    if n is not None:
        if rtol is not None:
            raise CommandError("--rtol applies to an impact scene; a cantilever steps at --dt")
        return run_cantilever(args, n)
    if args.scene is None:
        name = "default scene (barrierjax/default_scene.toml)"
        scene = scene_file.default_scene()
    else:
        name = str(args.scene)
        data = scene_file.read_toml(args.scene)
        from ..system.scene import is_system_scene, parse_system_scene

        if is_system_scene(data):  # a crash test of a barrier system
            from .system import run_system

            if rtol is not None:
                raise CommandError(
                    "--rtol applies to an impact scene (report 3.2-3.4); a barrier-system "
                    "scene steps at its own fixed time step"
                )

            return run_system(args, parse_system_scene(data), name)
        scene = scene_file.parse_scene(data)
    try:
        with progress_after("compiling and solving the impact model (report 3.2/3.3)..."):
            result = simulate(scene, rtol=rtol)
            jax.block_until_ready(result)
    except (NotImplementedError, ValueError) as error:
        raise _scene_error(error) from None
    except (SolveError, jax.errors.JaxRuntimeError) as error:  # a failed solve; a check
        raise CommandError(model_error(error), EXIT_FAILED) from None
    data = result_dict(scene, result, name)
    data["occupant_risk"] = occupant_risk_dict(result)
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
            result, args.out, title=title, progress=lambda p: progress(f"writing {p}")
        )
    return print_result(args, data, plots, format_summary)
