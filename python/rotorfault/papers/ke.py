"""Ke et al.'s uniform passive FTC (IEEE TIE), reproduced: the named scenarios of Sections II-B
and IV-B, Table II's printed numbers and the report behind ``rotorfault ftc-report``. The
controller and its design are in :mod:`rotorfault.control.ke`; the verdict on each flight (the
metrics of Section V, judged over the last window) is the flight's own,
:mod:`rotorfault.flight.outcomes` (re-exported here for the report).

Failures are applied one after the other from hover: the first rotor, then the next once the spin
has built up (Remark 3: simultaneous failures from r = 0 are not recoverable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._typing import KeLaw
from .._util.tables import Records
from ..analysis.airframe import Airframe
from ..control.ke import FtcPreset, UniformPassiveFtc, preset, stability_check
from ..flight import RotorFault, Sensing, State, Trajectory
from ..flight.outcomes import (
    CIRCLING_TURN_RAD,
    HOLD_BAND_M,
    HOLD_SPEED_M_S,
    OUTCOME_LABELS,
    WINDOW_S,
    FlightMetrics,
    effective_fault_times,
    flight_metrics,
)
from ..flight.scenarios import HOVER_M, FlightScenario
from ..plotting.paths import plot_primary_axis
from ._numbers import PaperNumber

if TYPE_CHECKING:
    from ._report import ReportSection, ReportTable

if TYPE_CHECKING:
    from matplotlib.figure import Figure

# -- scenarios ----------------------------------------------------------------------------------

HOVER = HOVER_M


@dataclass(frozen=True)
class KeScenario(FlightScenario):
    """One of Ke's flights (a :class:`~rotorfault.flight.scenarios.FlightScenario`: faults applied
    in order from hover, setpoints). ``efficiency`` is the rotor efficiencies after the last fault
    (Ke's health matrix is ``diag(efficiency)``)."""

    #: What Ke predicts: True (stabilised), False (Fig. 7: not stabilisable).
    ke_stabilizable: bool = True


def _sequential(
    efficiency: tuple[float, ...], order: tuple[int, ...], first_s: float = 2.0, gap_s: float = 8.0
) -> tuple[RotorFault, ...]:
    return tuple(RotorFault(rotor, first_s + k * gap_s, efficiency[rotor - 1]) for k, rotor in enumerate(order))


def _both_orders(
    name: str, description: str, efficiency: tuple[float, ...], order: tuple[int, int], ke_stabilizable: bool = True
) -> tuple[KeScenario, KeScenario]:
    """A two-failure scenario and ``<name>-reversed``, the same pair failing in the other order
    (the mirror image: the same outcome with the spin reversed)."""
    first, second = order
    return (
        KeScenario(name, description, efficiency, _sequential(efficiency, order), ke_stabilizable=ke_stabilizable),
        KeScenario(
            f"{name}-reversed",
            f"diag({', '.join(f'{h:g}' for h in efficiency)}) in the other order: rotor {second} first, then rotor "
            f"{first} (the mirror image)",
            efficiency,
            _sequential(efficiency, (second, first)),
            ke_stabilizable=ke_stabilizable,
        ),
    )


def scenarios() -> list[KeScenario]:
    """Ke Section II-B's health matrices (``diag(efficiency)``) as sequential faults from hover,
    position tracking after a failure, and both adjacent pairs (Figs. 7 and 9) in both orders.

    Ke's numbering (the preset's): 1 front right, 2 rear right, 3 rear left, 4 front left, rotors
    1 and 3 anticlockwise. So ``diag(0, 0, 1, 1)`` is two *adjacent* failures (the right pair, Ke's
    experiment; the left pair remains) and ``diag(0, 1, 0, 1)`` two *opposite*. The front (or rear)
    pair failing, ``diag(0, 1, 1, 0)``, is Fig. 7's case: not stabilisable."""
    return [
        KeScenario("fault-free", "diag(1, 1, 1, 1): hover, no fault", (1, 1, 1, 1), (), 20.0),
        KeScenario("partial-0.5", "diag(0.5, 1, 1, 1): rotor 1 at half efficiency", (0.5, 1, 1, 1), _sequential((0.5, 1, 1, 1), (1,))),
        KeScenario("one-failure", "diag(0, 1, 1, 1): rotor 1 fails", (0, 1, 1, 1), _sequential((0, 1, 1, 1), (1,))),
        KeScenario(
            "one-failure-partial-rest",
            "diag(0, 0.7, 0.6, 0.8): rotor 1 fails, then the others degrade",
            (0, 0.7, 0.6, 0.8),
            (RotorFault(1, 2.0, 0.0), RotorFault(2, 10.0, 0.7), RotorFault(3, 10.0, 0.6), RotorFault(4, 10.0, 0.8)),
        ),
        *_both_orders(
            "two-adjacent",
            "diag(0, 0, 1, 1): rotor 1 (front right) fails, then rotor 2 (rear right); the left pair remains "
            "(Ke's experiment, Fig. 9: stabilisable)",
            (0, 0, 1, 1),
            (1, 2),
        ),
        KeScenario("two-opposite", "diag(0, 1, 0, 1): rotor 1 fails, then the opposite rotor 3", (0, 1, 0, 1), _sequential((0, 1, 0, 1), (1, 3))),
        *_both_orders(
            "two-adjacent-front",
            "diag(0, 1, 1, 0): rotor 1 (front right) fails, then rotor 4 (front left); the rear pair "
            "remains (Ke Fig. 7: not stabilisable)",
            (0, 1, 1, 0),
            (1, 4),
            ke_stabilizable=False,
        ),
        KeScenario("three-failures", "diag(0, 0, 0, 1): rotors 1, 2, 3 fail one after another", (0, 0, 0, 1), _sequential((0, 0, 0, 1), (1, 2, 3)), 50.0),
        KeScenario(
            "tracking-one-failure",
            "rotor 1 fails in hover; at 20 s the setpoint moves 10 m east, across the drift the failure "
            "caused (position control, Fig. 17)",
            (0, 1, 1, 1),
            (RotorFault(1, 2.0, 0.0),),
            80.0,
            ((0.0, HOVER), (20.0, (0.0, 10.0, -10.0))),
        ),
    ]


def scenario(name: str) -> KeScenario:
    for s in scenarios():
        if s.name == name:
            return s
    raise ValueError(f"scenario: unknown {name!r}; available: {', '.join(s.name for s in scenarios())}")


@dataclass
class ScenarioRun:
    scenario: KeScenario
    law: KeLaw
    trajectory: Trajectory
    metrics: FlightMetrics = field(init=False)

    def __post_init__(self) -> None:
        self.metrics = flight_metrics(self.trajectory, self.scenario)

    @property
    def title(self) -> str:
        """What the run is: scenario, law and setpoint (for figures)."""
        return f"{self.scenario.name}, law {self.law}: {self.scenario.description}\nsetpoint {_setpoint_text(self.scenario)}"

    def plot(self, path: str | None = None) -> Figure:
        """The time history (:meth:`rotorfault.Trajectory.plot`) titled with the scenario, law
        and setpoint, the setpoint drawn; saved to ``path`` if given."""
        return self.trajectory.plot(path, title=self.title, setpoints=self.scenario.setpoints)


def _setpoint_text(scenario_: KeScenario) -> str:
    def one(p: tuple[float, float, float]) -> str:
        return f"N {p[0]:g}, E {p[1]:g}, alt {-p[2]:g} m"

    first = one(scenario_.setpoints[0][1])
    rest = "; ".join(f"from {t:g} s {one(p)}" for t, p in scenario_.setpoints[1:])
    return first + (f"; {rest}" if rest else "")


def run_scenario(
    scenario_: KeScenario | str,
    *,
    law: KeLaw = "feedforward",
    controller_preset: FtcPreset | str = "ke-hil",
    record_every: int = 4,
    sensing: Sensing | None = None,
) -> ScenarioRun:
    """Flies one scenario with the uniform passive FTC (or ``law="baseline"``), on the truth or
    on ``sensing`` (sensors and the estimator; the run records the estimate beside the truth)."""
    if not isinstance(scenario_, (str, KeScenario)):
        raise TypeError(f"scenario: expected a KeScenario or a scenario name, got {type(scenario_).__name__}")
    if not isinstance(controller_preset, (str, FtcPreset)):
        raise TypeError(f"controller_preset: expected an FtcPreset or a preset name, got {type(controller_preset).__name__}")
    sc = scenario(scenario_) if isinstance(scenario_, str) else scenario_
    pre = preset(controller_preset) if isinstance(controller_preset, str) else controller_preset
    sim = pre.simulator(sensing=sensing)
    controller = UniformPassiveFtc(pre.airframe, gains=pre.gains, law=law, setpoints=sc.setpoints)
    start = State(position=sc.setpoints[0][1])
    trajectory = sim.run(start, sc.duration_s, controller=controller, faults=sc.faults, record_every=record_every)
    return ScenarioRun(sc, law, trajectory)


# -- report (rotorfault ftc-report) --------------------------------------------------------------


def _efficiency_text(values: Any) -> str:
    return " ".join(f"{float(h):g}" for h in values)


#: The columns of :func:`report_rows` and their types (one name per column everywhere: the CSV,
#: the terminal table, ``to_arrow()``).
REPORT_COLUMNS: tuple[tuple[str, str], ...] = (
    ("scenario", "string"), ("law", "string"), ("efficiency", "string"), ("planned_efficiency", "string"),
    ("faults_not_reached", "string"), ("ke_stabilizable", "bool"), ("outcome", "string"), ("outcome_label", "string"),
    ("lost_at_s", "float64"), ("end_s", "float64"), ("window_s", "float64"), ("r_rad_s", "float64"), ("n3z", "float64"),
    ("rotation_axis", "string"), ("spin_settle_s", "float64"), ("max_altitude_loss_m", "float64"),
    ("max_horizontal_error_m", "float64"), ("final_horizontal_error_m", "float64"), ("final_altitude_error_m", "float64"),
    ("window_horizontal_error_m", "float64"), ("window_altitude_error_m", "float64"), ("window_speed_m_s", "float64"),
)


def report_rows(runs: list[ScenarioRun]) -> Records:
    """One record per run (:data:`REPORT_COLUMNS`; a sequence of dicts with ``to_arrow()`` and
    ``to_pandas()``). ``efficiency`` is what the run reached (a lost run never had the
    faults after its loss), ``planned_efficiency`` the scenario's; ``None``: not settled (steady
    values) or lost (position values, see ``lost_at_s``)."""
    rows = []
    for run in runs:
        m = run.metrics
        tr = run.trajectory
        rows.append(
            {
                "scenario": run.scenario.name,
                "law": run.law,
                "efficiency": _efficiency_text(tr.efficiency[-1]),
                "planned_efficiency": _efficiency_text(run.scenario.efficiency),
                "faults_not_reached": "; ".join(
                    f"rotor {f.rotor} -> {f.efficiency:g} at {f.time:g} s" for f in tr.faults if f.time > tr.t[-1]
                ),
                "ke_stabilizable": run.scenario.ke_stabilizable,
                "outcome": m.outcome,
                "outcome_label": m.outcome_label,
                "lost_at_s": m.lost_at_s,
                "end_s": float(tr.t[-1]),
                "window_s": m.window_s,
                "r_rad_s": m.r_rad_s,
                "n3z": m.n3z,
                "rotation_axis": None if m.rotation_axis is None else " ".join(f"{v:+.3f}" for v in m.rotation_axis),
                "spin_settle_s": m.spin_settle_s,
                "max_altitude_loss_m": m.max_altitude_loss_m,
                "max_horizontal_error_m": m.max_horizontal_error_m,
                "final_horizontal_error_m": m.final_horizontal_error_m,
                "final_altitude_error_m": m.final_altitude_error_m,
                "window_horizontal_error_m": m.window_horizontal_error_m,
                "window_altitude_error_m": m.window_altitude_error_m,
                "window_speed_m_s": m.window_speed_m_s,
            }
        )
    return Records(rows, REPORT_COLUMNS, title="Ke et al.: flights", kind="ke-flights")


#: Columns that hold a steady value (blank -> "not settled") and a position value over the run
#: (blank -> "lost at t").
STEADY_COLUMNS = ("r_rad_s", "n3z", "rotation_axis", "spin_settle_s")
POSITION_COLUMNS = (
    "max_altitude_loss_m",
    "max_horizontal_error_m",
    "final_horizontal_error_m",
    "final_altitude_error_m",
    "window_horizontal_error_m",
    "window_altitude_error_m",
    "window_speed_m_s",
)


def cell(row: dict[str, Any], column: str, digits: int = 3) -> str:
    """A report cell as text: numbers with ``digits`` decimals; a missing value says why
    (``"lost at 2.41 s"`` for a lost run, ``"not settled"`` for a steady value of a run that did
    not settle)."""
    value = row[column]
    if value is None:
        if row["lost_at_s"] is not None and (column in STEADY_COLUMNS or column in POSITION_COLUMNS):
            return f"lost at {row['lost_at_s']:.2f} s"
        if column in STEADY_COLUMNS:
            return "not settled"
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{round(value, digits) + 0.0:.{digits}f}"  # + 0.0: no "-0.0"
    return str(value)


def write_report(
    runs: list[ScenarioRun],
    out_dir: str | Path,
    *,
    figures: bool = True,
    force: bool = False,
    command: str | None = None,
) -> Path:
    """Writes the report directory ``out_dir``: ``ftc-report.md`` and ``ftc-report.csv`` (one
    row per run), with ``figures`` the time history of every run of the first law
    (``<scenario>.png``) and the primary-axis paths (``primary-axis.png``), and
    ``manifest.json`` (the files, ``command``, the rotorfault version). The directory is built
    beside ``out_dir`` and swapped in only when complete: an interrupted report leaves the
    previous one as it was. An existing report is replaced only with ``force``; a non-empty
    directory that is not a report never. Returns the Markdown file's path."""
    from ._report import check_report_directory, csv_text, report_directory

    out = check_report_directory("out_dir", out_dir, force=force)
    if not runs:
        raise ValueError("runs: nothing to report (give at least one law and scenario)")
    rows = report_rows(runs)
    table_csv = csv_text(rows, lambda r, column: cell(r, column, 6))
    lines = [
        "# Uniform passive FTC (Ke et al.): scenario report",
        "",
        f"Outcomes are judged over the last {runs[0].metrics.window_s:g} s of each run: 'holds position' keeps",
        f"within {HOLD_BAND_M[0]:g} m horizontally and {HOLD_BAND_M[1]:g} m vertically of the setpoint and below "
        f"{HOLD_SPEED_M_S:g} m/s throughout;",
        f"'circling' moves faster than {HOLD_SPEED_M_S:g} m/s on average while its direction of travel turns by at "
        f"least {math.degrees(CIRCLING_TURN_RAD):g} degrees",
        "(a steady circle or oscillation); 'off station' is neither; a divergence kind ('tilt', ...) means the",
        "vehicle was lost, and its position columns say when ('lost at t'): the track stops there.",
        "Steady values (r, n3z, rotation axis) are means over the same window, reported only for runs that",
        "settled: r within 5 % (0.2 rad/s) and n3z within 0.02 of them from the spin-settle time (counted from",
        "the last fault that changed an efficiency) to the end, at least one window before the end.",
        "'efficiency reached' is the rotor efficiency at the end of the run (a lost run never had the faults",
        "planned after its loss).",
        "",
        "| scenario | law | Ke: stabilisable | outcome | efficiency reached | r (rad/s) | n3z | rotation axis (body) "
        "| spin settle (s) | max alt. loss (m) | max horiz. (m) | final horiz. (m) | final alt. err. (m) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scenario']} | {r['law']} | {cell(r, 'ke_stabilizable')} | {r['outcome_label']} | {r['efficiency']} "
            f"| {cell(r, 'r_rad_s', 1)} | {cell(r, 'n3z', 3)} | {cell(r, 'rotation_axis')} "
            f"| {cell(r, 'spin_settle_s', 1)} | {cell(r, 'max_altitude_loss_m', 2)} | {cell(r, 'max_horizontal_error_m', 2)} "
            f"| {cell(r, 'final_horizontal_error_m', 2)} | {cell(r, 'final_altitude_error_m', 2)} |"
        )
    lines += ["", "Stability checks of Section III-D (Table II health matrices, k_rotor = 2):", ""]
    lines += ["| diag(efficiency) | eig(N) | Re eig(I + k N) > 0 (25) | Re eig(N) > 0 (32) |", "|---|---|---|---|"]
    frame = Airframe.preset("ke-quadcopter")
    for efficiency in TABLE_II_EFFICIENCY:
        check = stability_check(frame, efficiency)
        eig = ", ".join(f"{v.real:.4f}" for v in check.eigenvalues)
        lines.append(
            f"| diag({', '.join(f'{h:g}' for h in efficiency)}) | {eig} | {check.thrust_feedback} | {check.full_compensation} |"
        )
    first_law = runs[0].law
    if figures:
        lines += ["", f"Figures ({first_law}): `primary-axis.png`, and one time history per scenario (`<scenario>.png`)."]
    else:
        lines += ["", "No figures (written with --no-figures)."]
    with report_directory(
        out, generator="rotorfault ftc-report (rotorfault.papers.ke.write_report)", command=command,
        default_command="rotorfault.papers.ke.write_report", laws=sorted({run.law for run in runs}),
        scenarios=sorted({run.scenario.name for run in runs}),
    ) as tmp:
        (tmp / "ftc-report.csv").write_text(table_csv, encoding="utf-8")
        (tmp / "ftc-report.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
        if figures:
            chosen = [run for run in runs if run.law == first_law]
            for run in chosen:
                run.plot(str(tmp / f"{run.scenario.name}.png"))
            plot_primary_axis(chosen, str(tmp / "primary-axis.png"))
    return out / "ftc-report.md"


#: The health matrices of Ke Table II, as their diagonals (rotor efficiencies).
TABLE_II_EFFICIENCY = (
    (0.5, 1, 1, 1),
    (0, 1, 1, 1),
    (0, 0.7, 0.6, 0.8),
    (0, 0.1, 0.1, 0.1),
    (0, 1, 0, 1),
    (0, 0.5, 0, 0.5),
    (1, 0, 1, 0),
    (0, 0, 1, 1),
    (1, 1, 0, 0),
    (0, 0, 0, 1),
    (0, 0, 1, 0),
)


#: Ke Table II: the eigenvalues of ``N = (E1 M) Lambda (E1 M)^+`` it prints (four decimals) for
#: each health matrix of :data:`TABLE_II_EFFICIENCY`, in the paper's order.
TABLE_II_EIGENVALUES = (
    (1, 0.625, 1),
    (1, 0.25, 1),
    (0.1718, 0.644, 0.7592),
    (0.1, 0.025, 0.1),
    (1, 0, 0.5),
    (0.5, 0, 0.25),
    (0.5, 0, 1),
    (1, 0, 0.5),
    (1, 0, 0.5),
    (0.75, 0, 0),
    (0.75, 0, 0),
)
PAPER = "Ke et al. (IEEE TIE)"
#: Table II prints up to four decimals: agreement to half a unit in the last place.
TABLE_II_TOL = 0.5e-4


def printed_numbers(airframe: Airframe | None = None) -> list[PaperNumber]:
    """Every eigenvalue Ke Table II prints beside ours (:func:`rotorfault.control.ke.n_eigenvalues`
    on the ``ke-quadcopter`` preset), both sorted ascending per row; a complex eigenvalue of ours
    (none is expected) is reported as ``nan`` and so "differs"."""
    from ..control.ke import n_eigenvalues

    frame = Airframe.preset("ke-quadcopter") if airframe is None else airframe
    rows = []
    for efficiency, printed in zip(TABLE_II_EFFICIENCY, TABLE_II_EIGENVALUES, strict=True):
        ours = n_eigenvalues(frame, efficiency)
        case = f"diag({', '.join(f'{h:g}' for h in efficiency)})"
        for k, (value, mine) in enumerate(zip(sorted(printed), ours, strict=True), start=1):
            real_part = float(mine.real) if abs(mine.imag) <= 1e-12 else math.nan
            rows.append(PaperNumber(PAPER, "Table II", f"eig {k} of N, {case}", float(value), real_part, TABLE_II_TOL))
    return rows


def sensing_table(truth: list[ScenarioRun], sensed: list[ScenarioRun]) -> ReportTable:
    """The same scenarios flown on the truth and on sensors, side by side: each verdict, the
    window's horizontal error, and the estimate's error (position and attitude RMS over the run)."""
    from ._report import ReportTable

    rows = []
    for a, b, row_a, row_b in zip(truth, sensed, report_rows(truth), report_rows(sensed), strict=True):
        tr = b.trajectory
        finite = np.isfinite(tr.estimate_position_error_m)
        position_mm = 1e3 * float(np.sqrt(np.mean(tr.estimate_position_error_m[finite] ** 2)))
        attitude_deg = float(np.degrees(np.sqrt(np.mean(tr.estimate_attitude_error_rad[finite] ** 2))))
        counts = tr.estimate.counts if tr.estimate is not None else None
        clamped = "" if counts is None else f"{counts.gyro_saturated_samples / max(counts.imu_samples, 1):.0%}"
        rows.append((
            a.scenario.name, a.metrics.outcome_label, b.metrics.outcome_label,
            "same" if a.metrics.outcome == b.metrics.outcome else "differs",
            f"{cell(row_a, 'window_horizontal_error_m', 3)} / {cell(row_b, 'window_horizontal_error_m', 3)}",
            f"{position_mm:.3f}", f"{attitude_deg:.4f}", clamped,
        ))
    return ReportTable(
        f"With sensors: the same flights on the truth and on {sensed[0].trajectory.sensed} (rotorfault.Sensing: the "
        "suite's IMU and position source, the error-state Kalman filter), side by side; the estimate's error over the "
        "whole run (a lost run's tumble included) and the share of IMU samples with the gyro clamped at 2000 deg/s",
        ("scenario", "truth: outcome", "sensors: outcome", "verdict", "window horiz. (m) truth / sensors",
         "estimate position RMS (mm)", "estimate attitude RMS (deg)", "gyro clamped"),
        tuple(rows),
    )


#: Scenarios flown for the reproduce-all report in --quick mode (the full mode flies all).
QUICK_SCENARIOS = ("fault-free", "one-failure", "two-adjacent", "two-opposite", "two-adjacent-front", "three-failures")


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Ke's part of ``rotorfault reproduce``: Table II beside ours, the stability checks, and the
    scenario flights (the same :func:`run_scenario`, :func:`report_rows` and figures as
    ``rotorfault ftc-report``) written into ``out``: every scenario with the default law
    (``--quick``: :data:`QUICK_SCENARIOS`) plus the printed law and the baseline on one failure."""
    import time

    from ..control.ke import stability_check as check_
    from ._report import ReportFigure, ReportSection, ReportTable

    start = time.perf_counter()
    section = ReportSection("ke", "Ke et al.: uniform passive fault-tolerant control", source="rotorfault.papers.ke (rotorfault ftc-report)")
    section.numbers = printed_numbers()
    frame = Airframe.preset("ke-quadcopter")
    checks = []
    for efficiency in TABLE_II_EFFICIENCY:
        c = check_(frame, efficiency)
        checks.append((f"diag({', '.join(f'{h:g}' for h in efficiency)})", "yes" if c.thrust_feedback else "no",
                       "yes" if c.full_compensation else "no"))
    section.tables.append(ReportTable(
        "Stability checks of Section III-D (k_rotor = 2): (25) the uniform controller, (32) Remark 5's full "
        "compensation (fails with two or three failures, as Ke says)",
        ("diag(efficiency)", "Re eig(I + k N) > 0 (25)", "Re eig(N) > 0 (32)"), tuple(checks)))
    chosen = [scenario(name) for name in QUICK_SCENARIOS] if quick else scenarios()
    runs = [run_scenario(sc) for sc in chosen]
    extra = [run_scenario("one-failure", law=law) for law in ("literal", "baseline")]
    rows = report_rows(runs + extra)
    section.tables.append(ReportTable(
        f"Flights ({'--quick: ' + str(len(chosen)) + ' scenarios' if quick else 'every scenario'}; preset ke-hil, "
        f"outcomes judged over the last {WINDOW_S:g} s; Ke's experiment spins: about 23, 38 and 42 rad/s for one, two "
        "adjacent and two opposite failures)",
        ("scenario", "law", "Ke: stabilisable", "outcome", "efficiency reached", "r (rad/s)", "n3z", "max alt. loss (m)",
         "max / final horiz. (m)"),
        tuple(
            (r["scenario"], r["law"], cell(r, "ke_stabilizable"), r["outcome_label"], r["efficiency"], cell(r, "r_rad_s", 1),
             cell(r, "n3z", 3), cell(r, "max_altitude_loss_m", 2),
             cell(r, "max_horizontal_error_m", 2) if r["max_horizontal_error_m"] is None
             else f"{cell(r, 'max_horizontal_error_m', 2)} / {cell(r, 'final_horizontal_error_m', 2)}")
            for r in rows
        ),
    ))
    sensed = [run_scenario(sc, sensing=Sensing()) for sc in chosen]
    section.tables.append(sensing_table(runs, sensed))
    plot_primary_axis(runs, str(out / "ke-primary-axis.png"))
    section.figures.append(ReportFigure("ke-primary-axis.png", "The primary axis n3 on the unit sphere for every flight (Ke Fig. 16 style)."))
    for run in runs + extra:
        name = f"ke-{run.scenario.name}-{run.law}.png"
        run.plot(str(out / name))
        section.figures.append(ReportFigure(name, f"{run.scenario.name}, law {run.law}: {run.scenario.description}", small=True))
    for run in sensed:
        name = f"ke-{run.scenario.name}-{run.law}-mocap.png"
        run.plot(str(out / name))
        section.figures.append(ReportFigure(
            name, f"{run.scenario.name}, law {run.law}, on mocap sensors: truth, the estimate (dotted) and its error", small=True))
    section.run_time_s = time.perf_counter() - start
    return section


__all__ = [
    "CIRCLING_TURN_RAD",
    "HOLD_BAND_M",
    "HOLD_SPEED_M_S",
    "OUTCOME_LABELS",
    "POSITION_COLUMNS",
    "STEADY_COLUMNS",
    "WINDOW_S",
    "TABLE_II_EFFICIENCY",
    "TABLE_II_EIGENVALUES",
    "TABLE_II_TOL",
    "PAPER",
    "QUICK_SCENARIOS",
    "printed_numbers",
    "report_section",
    "FlightMetrics",
    "KeScenario",
    "ScenarioRun",
    "cell",
    "effective_fault_times",
    "flight_metrics",
    "plot_primary_axis",
    "report_rows",
    "run_scenario",
    "sensing_table",
    "scenario",
    "scenarios",
    "write_report",
]
