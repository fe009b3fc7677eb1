"""Wang, Gross, Zhao (2020), Section 4: the three flights of the VPP quadcopter with propeller 1
failed, flown in Rust by the LQR of :func:`rotorfault.vpp.lqr` on a shaped reference
(:class:`rotorfault.TrackingFeedback`), and the fixed-pitch comparison of Section 3.4.

The fixed-pitch comparison (a decision, README "Wang's fixed-pitch comparison"): no fixed-pitch
flight. Sec. 3.4's layout (``wang-fixed-pitch``: motors on one axis spin opposite ways) is not
stabilisable healthy (rank 10: yaw rate moves only with roll and pitch rate) nor with propeller 1
failed (rank 8), so no linear controller exists to fly it and none is designed (the LQR's PBH test
refuses, naming the modes). The standard layout (``wang-standard-fixed-pitch``) is stabilisable
healthy but has no hover at rest once propeller 1 fails; flying it needs a spinning controller
tuned for this vehicle and a rotational damping Wang does not give (it sets the spin rate), so
such a flight would measure our choices, not the vehicle. :func:`fixed_pitch_comparison` tabulates
both layouts beside the VPP, healthy and failed: hover at rest, rank, stabilisability with the
modes no input moves, the uncontrollable directions, the ACAI.

The scenarios are Python definitions, not ``examples/*.toml`` files: the scenario-file schema
(:mod:`rotorfault.scenario`) has no VPP actuator, no reference path and no wind profile.

Frames: Wang's ``(x, y, z)`` with z up maps to NED ``(x, y, -z)`` (his y is our east up to the
frame's sign, which mirrors the path and changes nothing else).

Paper gaps, decided here (README decisions table):

- scenario 1 gives no numbers: a circle of :data:`CIRCLE_RADIUS_M` every :data:`CIRCLE_PERIOD_S`,
  climbing at :data:`CLIMB_M_S`, yaw ``YAW_AMPLITUDE_RAD sin(2 pi t / period)`` (the gain is
  designed at yaw 0, so large yaw excursions rotate the vehicle out of its linear model);
  the reference carries the path's velocity (feedforward through the velocity error);
- scenario 3: "the desired states are all set to 0" (the paper), hold the origin with a 4 m/s
  wind in x and y from t = 1 s and 15 dB SNR noise;
- the ground: the paper prints none, and its vehicle hovers at its origin (scenario 3), so the
  origin is in the air: the simulator's ground is :data:`GROUND_Z_M` below it (the paper's
  coordinates are kept, so the paths and errors are the paper's frame);
- reference shaping: the paper feeds its steps to the LQR unshaped, and in our model that flies
  (:data:`ERROR_LIMIT_M` = inf, the default); clipping each position error (``error_limit_m``)
  trades a smaller tilt for a slower arrival and, against a steady wind, a drift (README).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._util.convert import FloatArray, real
from .._util.tables import Records
from ..control.linear import STATE_LABELS
from ..control.tracking import TrackingFeedback, circle_reference, step_reference
from ..flight import Noise, Sensing, Simulator, State, Trajectory
from ..control import vpp
from ..plotting.timeseries import plot_wang_flights as plot_flight

if TYPE_CHECKING:
    from ..control.stabilisability import PbhTest
    from ._numbers import PaperNumber
    from ._report import ReportSection

#: Scenario 1 (a decision: the paper prints no numbers).
CIRCLE_RADIUS_M = 2.0
CIRCLE_PERIOD_S = 20.0
CLIMB_M_S = 0.1
YAW_AMPLITUDE_RAD = 0.2
#: Scenario 2's waypoints (Wang's frame, z up) and the times they become the target.
WAYPOINTS = ((0.0, (0.0, 0.0, 0.0)), (2.0, (0.0, 0.0, 5.0)), (5.0, (5.0, 0.0, 5.0)), (10.0, (5.0, 5.0, 5.0)))
YAW_STEP = (1.0, 0.1)
WIND_M_S = (4.0, 4.0, 0.0)
WIND_FROM_S = 1.0
SNR_DB = 15.0
#: Reference shaping: each position error clipped to this (m); inf: the paper's unshaped steps.
ERROR_LIMIT_M = math.inf
#: Wang's operating point: omega_3 = 9000 (Sec. 3.1), the 1 kHz control period of our flights.
OMEGA3 = 9000.0
DT_S = 0.001
DURATION_S = 60.0
#: The ground plane in the paper's frame (NED z, m): 10 m below its origin (module notes).
GROUND_Z_M = 10.0

#: What the fixed-pitch comparison is (report text; module notes and README decisions).
COMPARISON_NOTE = (
    "Wang's Sec. 3.4 layout cannot be stabilised by any linear feedback, healthy or with propeller 1 failed "
    "(the LQR refuses it, naming the modes no input moves), so it is not flown; the standard layout has no "
    "hover at rest once propeller 1 fails."
)


@dataclass(frozen=True)
class WangScenario:
    """One flight: the reference table (rows of 12 NED states at ``times_s``, a repeated time is
    a jump), the wind profile, and whether the measurements carry 15 dB SNR noise."""

    number: int
    title: str
    times_s: FloatArray
    references: FloatArray
    wind_profile: tuple[tuple[float, tuple[float, float, float]], ...] | None
    noisy: bool


def scenario(number: int, *, duration_s: float = DURATION_S) -> WangScenario:
    """Scenario 1, 2 or 3 of Section 4.2 (module docs)."""
    duration = real("duration_s", duration_s)
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"duration_s: must be > 0 and finite, got {duration}")
    if number == 1:
        t, refs = circle_reference(radius_m=CIRCLE_RADIUS_M, period_s=CIRCLE_PERIOD_S, climb_m_s=CLIMB_M_S,
                                   yaw_amplitude_rad=YAW_AMPLITUDE_RAD, duration_s=duration)
        return WangScenario(1, "scenario 1: circle, climb and yaw, no noise", t, refs, None, False)
    if number in (2, 3):
        moves = WAYPOINTS if number == 2 else WAYPOINTS[:1]
        # Wang's waypoints are (x, y, z up); the reference is NED.
        times, refs = step_reference([(t_s, (x, y, -z)) for t_s, (x, y, z) in moves], [YAW_STEP])
        if number == 2:
            return WangScenario(2, "scenario 2: waypoints, yaw 0.1 rad from 1 s, 15 dB SNR noise", times, refs, None, True)
        wind = ((0.0, (0.0, 0.0, 0.0)), (WIND_FROM_S, WIND_M_S))
        return WangScenario(3, "scenario 3: hold, 4 m/s wind in x and y from 1 s, 15 dB SNR noise", times, refs, wind, True)
    raise ValueError(f"number: Wang's scenarios are 1, 2 and 3, got {number!r}")


@dataclass(frozen=True)
class WangFlight:
    """A flown scenario: the trajectory, the reference it followed (sampled at the trajectory's
    times) and the summary numbers the tests and the report print."""

    scenario: WangScenario
    vehicle: str
    trajectory: Trajectory
    reference: FloatArray
    lost_at_s: float | None
    final_error_m: float
    max_error_after_s: float
    max_tilt_rad: float

    @property
    def lost(self) -> bool:
        return self.lost_at_s is not None


def controller(vehicle: vpp.VppVehicle, s: WangScenario, *, error_limit_m: float = ERROR_LIMIT_M) -> TrackingFeedback:
    """The LQR of :func:`rotorfault.vpp.lqr` at Wang's trim (propeller 1 failed, omega_3 = 9000),
    checked at the flights' control period :data:`DT_S`, on ``s``'s reference."""
    feedback = vpp.lqr(vehicle, vpp.trim(vehicle, failed=(1,), speeds={3: OMEGA3}), dt_s=DT_S)
    limit = np.full(12, math.inf)
    limit[:3] = real("error_limit_m", error_limit_m)
    return TrackingFeedback.from_feedback(feedback, times_s=s.times_s, references=s.references, error_limit=limit)


def fly(
    number: int,
    *,
    duration_s: float = DURATION_S,
    error_limit_m: float = ERROR_LIMIT_M,
    seed: int = 0,
    settle_s: float = 15.0,
    sensing: Sensing | None = None,
) -> WangFlight:
    """Scenario ``number`` with propeller 1 failed from t = 0 on the VPP quadcopter (the
    fixed-pitch quadcopter is not flown: module notes). ``max_error_after_s``: the largest
    position error after ``settle_s`` (the last waypoint at 10 s plus 5 s). With ``sensing`` the
    controller flies on sensors and the estimator instead of the paper's 15 dB noise."""
    s = scenario(number, duration_s=duration_s)
    vehicle = vpp.preset("wang")
    law = controller(vehicle, s, error_limit_m=error_limit_m)
    base = vehicle.simulator(failed=(1,), wind_profile=list(s.wind_profile) if s.wind_profile else None)
    sim = Simulator(
        base.airframe, actuator=vehicle.actuator, drag=vehicle.drag, dt_s=DT_S,
        wind_profile=list(s.wind_profile) if s.wind_profile else None,
        noise=Noise(snr_db=SNR_DB, seed=seed) if s.noisy and sensing is None else None, ground_z_m=GROUND_Z_M,
        sensing=sensing,
    )
    run = sim.run(State(), duration_s=duration_s, controller=law)
    reference = np.array([law.reference(t) for t in run.t])
    error = np.linalg.norm(run.position - reference[:, :3], axis=1)
    late = run.t >= settle_s
    lost = run.events[0].time if run.events else None
    return WangFlight(
        s, "VPP", run, reference, lost,
        float(error[-1]), float(np.max(error[late])) if np.any(late) else math.nan,
        float(np.max(np.abs(run.euler[:, :2]))),
    )


#: The comparison's vehicles: (label, VPP or fixed-pitch airframe preset, None for the VPP).
LAYOUTS: tuple[tuple[str, str | None], ...] = (
    ("VPP (thrust in [-13, 13] N)", None),
    ("fixed pitch, Sec. 3.4 layout (1 cw, 2 ccw, 3 ccw, 4 cw)", "wang-fixed-pitch"),
    ("fixed pitch, standard layout (1, 3 cw; 2, 4 ccw)", "wang-standard-fixed-pitch"),
)

#: A hover is "at rest" when the trim leaves no acceleration beyond this (the trims' own
#: rounding is about 1e-13; an unbalanced yaw torque leaves about 10 rad/s^2).
REST_RESIDUAL = 1e-9


@dataclass(frozen=True)
class LayoutCase:
    """One row of the fixed-pitch comparison: a vehicle, healthy or with propeller 1 failed.

    ``residual``: the trim's ``||f(x*, u*)||`` (:data:`REST_RESIDUAL`: whether it hovers at
    rest); when it does, ``rank`` (scale-free, :func:`rotorfault.vpp.controllability`),
    ``stabilisability`` (the PBH test of :func:`rotorfault.control.stabilisability`, which the
    LQR runs first) and ``uncontrollable`` (the Kalman directions); else those are None (no
    equilibrium to linearise about). ``acai``: Du's index of the airframe's thrust box."""

    vehicle: str
    failed: tuple[int, ...]
    residual: float
    rank: int | None
    stabilisability: PbhTest | None
    uncontrollable: tuple[str, ...] | None
    acai: float

    @property
    def at_rest(self) -> bool:
        return self.residual <= REST_RESIDUAL


def fixed_pitch_comparison() -> list[LayoutCase]:
    """The VPP and the two fixed-pitch layouts, healthy and with propeller 1 failed (module
    notes): the comparison in place of a fixed-pitch flight."""
    from ..control.stabilisability import stabilisability
    from ..analysis.acai import acai

    wang = vpp.preset("wang")
    rows = []
    for label, frame in LAYOUTS:
        vehicle = wang if frame is None else vpp.fixed_pitch(wang, frame)
        for failed in ((), (1,)):
            if frame is None:
                at = vpp.trim(vehicle, failed=failed, speeds={3: OMEGA3} if failed else None)
            else:
                at = vpp.fixed_pitch_trim(vehicle, failed=failed)
            efficiency = np.ones(4)
            efficiency[[i - 1 for i in failed]] = 0.0
            index = float(acai(vehicle.airframe.with_efficiency(efficiency), formula="eq13"))
            if at.residual > REST_RESIDUAL:
                rows.append(LayoutCase(label, failed, at.residual, None, None, None, index))
                continue
            model = vpp.linearize(vehicle, at, pitch_fixed=frame is not None)
            kalman = vpp.controllability(model)
            test = stabilisability(
                model.A, model.B, state_names=vpp.STATE_NAMES, state_labels=STATE_LABELS,
            )
            rows.append(LayoutCase(
                label, failed, at.residual, kalman.rank, test,
                tuple(d.text for d in kalman.uncontrollable_directions), index,
            ))
    return rows


def comparison_table(cases: list[LayoutCase] | None = None) -> list[str]:
    """Markdown: :func:`fixed_pitch_comparison` (hover at rest, rank, stabilisable and the modes
    no input moves, the uncontrollable directions, ACAI)."""
    from ..analysis.acai import acai_label

    rows = [
        "| vehicle | propeller 1 | hover at rest | rank | stabilisable (PBH) | uncontrollable directions | "
        f"{acai_label('eq13')} |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in fixed_pitch_comparison() if cases is None else cases:
        state = "failed" if c.failed else "healthy"
        if not c.at_rest:
            rows.append(
                f"| {c.vehicle} | {state} | no (trim residual {c.residual:.3g}) | - | "
                f"no equilibrium to linearise | - | {c.acai:.4f} |"
            )
            continue
        assert c.stabilisability is not None and c.uncontrollable is not None
        verdict = "yes" if c.stabilisability.holds else f"no: {c.stabilisability.describe()}"
        rows.append(
            f"| {c.vehicle} | {state} | yes | {c.rank} | {verdict} | {'; '.join(c.uncontrollable) or 'none'} | "
            f"{c.acai:.4f} |"
        )
    return rows


def speed_sweep_table() -> list[str]:
    """Markdown: the feasible trim speeds per failed propeller (:func:`rotorfault.vpp.feasible_speeds`)."""
    wang = vpp.preset("wang")
    rows = ["| failed | fixed group, speed range | free group, speed range |", "|---|---|---|"]
    for i in range(1, 5):
        w = vpp.feasible_speeds(wang, failed=(i,))
        rows.append(
            f"| {i} | {list(w.fixed_rotors)}: [{w.fixed_speed_range[0]:.1f}, {w.fixed_speed_range[1]:.1f}] | "
            f"{list(w.free_rotors)}: [{w.free_speed_range[0]:.1f}, {w.free_speed_range[1]:.1f}] |"
        )
    return rows


def flight_rows(flights: list[WangFlight]) -> Records:
    """One record per flight (a sequence of dicts with ``to_arrow()`` and ``to_pandas()``):
    ``final_error_m`` and ``max_error_after_settle_m`` are ``None`` for a lost flight."""
    columns = [("scenario", "int64"), ("vehicle", "string"), ("lost", "bool"), ("lost_at_s", "float64"), ("final_error_m", "float64"),
               ("max_error_after_settle_m", "float64"), ("max_tilt_rad", "float64")]
    rows = [
        {
            "scenario": f.scenario.number, "vehicle": f.vehicle, "lost": f.lost, "lost_at_s": f.lost_at_s,
            "final_error_m": None if f.lost else f.final_error_m,
            "max_error_after_settle_m": None if f.lost or math.isnan(f.max_error_after_s) else f.max_error_after_s,
            "max_tilt_rad": f.max_tilt_rad,
        }
        for f in flights
    ]
    return Records(rows, columns, title="Wang et al.: Section 4's flights", kind="wang-flights")


def comparison_rows(cases: list[LayoutCase] | None = None) -> Records:
    """:func:`fixed_pitch_comparison` as records (one per vehicle and propeller state); the rank,
    stabilisability and directions are ``None`` where the vehicle has no hover at rest."""
    columns = [("vehicle", "string"), ("failed_rotors", "list<int64>"), ("trim_residual", "float64"), ("hover_at_rest", "bool"),
               ("controllability_rank", "int64"), ("stabilisable", "bool"), ("uncontrollable_directions", "list<string>"),
               ("acai_eq13", "float64")]
    rows = [
        {
            "vehicle": c.vehicle, "failed_rotors": list(c.failed), "trim_residual": c.residual, "hover_at_rest": c.at_rest,
            "controllability_rank": c.rank, "stabilisable": None if c.stabilisability is None else c.stabilisability.holds,
            "uncontrollable_directions": None if c.uncontrollable is None else list(c.uncontrollable), "acai_eq13": c.acai,
        }
        for c in (fixed_pitch_comparison() if cases is None else cases)
    ]
    return Records(rows, columns, title="Wang et al.: the fixed-pitch comparison", kind="wang-comparison")


def flights_table(flights: list[WangFlight]) -> list[str]:
    rows = ["| scenario | vehicle | outcome | final error (m) | largest error after 15 s (m) | largest tilt (rad) |",
            "|---|---|---|---|---|---|"]
    for f in flights:
        outcome = f"lost at {f.lost_at_s:.2f} s" if f.lost else "flown"
        late = "" if f.lost or math.isnan(f.max_error_after_s) else f"{f.max_error_after_s:.3f}"
        final = "" if f.lost else f"{f.final_error_m:.3f}"
        rows.append(f"| {f.scenario.number} | {f.vehicle} | {outcome} | {final} | {late} | {f.max_tilt_rad:.3f} |")
    return rows


def write_report(out_dir: str, *, quick: bool = False, force: bool = False, command: str | None = None) -> str:
    """Writes ``out_dir`` atomically (replaced only with ``force``): ``vpp-report.md`` (the
    fixed-pitch comparison table, the speed sweep, the flights), one figure per scenario
    (``scenario-<n>.png``) and ``manifest.json``.
    ``quick``: 20 s flights instead of the paper's 60 s."""
    from .._util.output import check_output_directory, output_directory, write_text

    check_output_directory("out_dir", out_dir, force=force)
    duration = 20.0 if quick else DURATION_S
    flights = []
    pages = []
    for n in (1, 2, 3):
        v = fly(n, duration_s=duration)
        flights.append(v)
        pages.append((n, [v]))
    lines = [
        "# Variable-pitch quadcopters that lose a propeller (Wang et al.): report", "",
        "## The fixed-pitch comparison: hover, controllability, ACAI", "", COMPARISON_NOTE, "",
        *comparison_table(), "",
        "## Feasible trim speeds per failed propeller", "", *speed_sweep_table(), "",
        f"## Section 4's flights ({duration:g} s, VPP, propeller 1 failed from t = 0)", "",
        *flights_table(flights), "",
    ]
    manifest = {"generator": "rotorfault vpp-report (rotorfault.papers.wang.write_report)",
                "command": command or "rotorfault.papers.wang.write_report", "quick": quick}
    with output_directory(out_dir, manifest) as tmp:
        write_text(tmp / "vpp-report.md", "\n".join(lines))
        for n, pair in pages:
            plot_flight(pair, str(tmp / f"scenario-{n}.png"))
    return out_dir


__all__ = ["COMPARISON_NOTE", "LAYOUTS", "PAPER", "REST_RESIDUAL", "LayoutCase", "WangFlight", "WangScenario", "comparison_rows", "comparison_table", "fixed_pitch_comparison", "flight_rows", "printed_numbers", "report_section", "controller", "flights_table", "fly", "plot_flight",
           "scenario", "speed_sweep_table", "write_report"]


# -- the reproduce-all report ---------------------------------------------------------------------

PAPER = "Wang et al. (2020)"


def printed_numbers() -> list[PaperNumber]:
    """The numbers Sections 3.1, 3.3 and 3.4 print, beside ours (propeller 1 failed): the trim at
    omega3 = 9000, the feasible speed ranges, the range of r(omega2), and the controllability
    ranks. Printed values carry their own rounding: half a unit in the last printed place."""
    from ._numbers import PaperNumber

    wang = vpp.preset("wang")
    trim = vpp.trim(wang, failed=(1,), speeds={3: OMEGA3})
    window = vpp.feasible_speeds(wang, failed=(1,))
    fixed = vpp.fixed_pitch(wang)
    fixed_model = vpp.controllability(vpp.linearize(fixed, vpp.fixed_pitch_trim(fixed, failed=(1,)), pitch_fixed=True))
    ranks = (vpp.controllability(vpp.linearize(wang, trim)).rank, fixed_model.rank)
    (lo2, hi2), (lo3, hi3) = window.free_speed_range, window.fixed_speed_range
    r_lo, r_hi = window.free_torque_range_nm
    return [
        PaperNumber(PAPER, "Sec. 3.1", "omega2* at omega3 = 9000", 6355, trim.speed(2), 0.5),
        PaperNumber(PAPER, "Sec. 3.1", "alpha2* at omega3 = 9000 (rad)", 0.2476, trim.pitch(2), 0.5e-4),
        PaperNumber(PAPER, "Sec. 3.1", "lowest feasible omega2 (pitch bound)", 6201, lo2, 1.0,
                    "the paper truncates 6201.7 to 6201"),
        PaperNumber(PAPER, "Sec. 3.1", "highest feasible omega2 (r = 1)", 7067, hi2, 0.5,
                    "7067 is not a root of r = 1 (r(7067) = 1.0008); the root is 7064.2 (README decisions)"),
        PaperNumber(PAPER, "Sec. 3.1", "lowest feasible omega3", 8782, lo3, 0.5,
                    "the paper evaluates r at the rounded 6201 (0.7714) and truncates sqrt(0.7714 / k2) = 8782.9"),
        PaperNumber(PAPER, "Sec. 3.1", "highest feasible omega3 (speed bound)", 10000, hi3, 0.5),
        PaperNumber(PAPER, "Sec. 3.1", "lowest r(omega2)", 0.7714, r_lo, 0.5e-4,
                    "at the exact pitch-bound speed 6201.7; r(6201) = 0.7714"),
        PaperNumber(PAPER, "Sec. 3.1", "highest r(omega2)", 2, r_hi, 0.5),
        PaperNumber(PAPER, "Sec. 3.3", "controllability rank, VPP, propeller 1 failed", 12, ranks[0], 0.0),
        PaperNumber(PAPER, "Sec. 3.4", "controllability rank, fixed pitch, propeller 1 failed", 8, ranks[1], 0.0,
                    f"uncontrollable: {', '.join(fixed_model.uncontrollable_states)} (Wang: y, phi, p, v)"),
    ]


def _lost(time_s: float | None) -> str:
    return "not lost" if time_s is None else f"{time_s:.2f}"


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Wang's part of ``rotorfault reproduce``: the printed numbers beside ours, the same tables
    and flights as ``rotorfault vpp-report`` (``--quick``: 20 s flights)."""
    import time

    from ._report import ReportFigure, ReportSection, ReportTable, markdown_table

    start = time.perf_counter()
    section = ReportSection("wang", "Wang et al.: variable-pitch quadcopters that lose a propeller",
                            source="rotorfault.papers.wang (rotorfault vpp-report)")
    section.numbers = printed_numbers()
    for caption, lines in (
        (f"The fixed-pitch comparison (no fixed-pitch flight): {COMPARISON_NOTE} The 4-axis ACAI's yaw row "
         "cannot see the VPP's separate torque channel (README decisions).", comparison_table()),
        ("Feasible trim speeds per failed propeller", speed_sweep_table()),
    ):
        columns, rows = markdown_table(lines)
        section.tables.append(ReportTable(caption, columns, rows))
    duration = 20.0 if quick else DURATION_S
    flights = []
    for n in (1, 2, 3):
        flight = fly(n, duration_s=duration)
        flights.append(flight)
        name = f"wang-scenario-{n}.png"
        plot_flight([flight], str(out / name))
        section.figures.append(ReportFigure(name, f"Section 4 scenario {n}: VPP, propeller 1 failed", small=True))
    columns, rows = markdown_table(flights_table(flights))
    section.tables.append(ReportTable(f"Section 4's flights ({duration:g} s, VPP, propeller 1 failed from t = 0)", columns, rows))
    sensed = [fly(n, duration_s=duration, sensing=Sensing(imu_rate_hz=1000.0)) for n in (1, 2, 3)]
    section.tables.append(ReportTable(
        "With sensors: the same flights on the paper's sensing (scenario 1 the truth, 2 and 3 its 15 dB noise) and on "
        "mocap (rotorfault.Sensing, the IMU at the 1 kHz loop rate; the error-state Kalman filter), side by side",
        ("scenario", "paper: lost at (s)", "mocap: lost at (s)", "paper: max error after 15 s (m)",
         "mocap: max error after 15 s (m)"),
        tuple((str(n), _lost(a.lost_at_s), _lost(b.lost_at_s), f"{a.max_error_after_s:.3f}", f"{b.max_error_after_s:.3f}")
              for n, a, b in zip((1, 2, 3), flights, sensed, strict=True)),
    ))
    section.run_time_s = time.perf_counter() - start
    return section
