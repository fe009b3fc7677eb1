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
    VERDICT_MEANINGS,
    VERDICTS,
    verdict_count_text,
    WINDOW_S,
    FlightMetrics,
    effective_fault_times,
    flight_metrics,
)
from ..flight.scenarios import HOVER_M, FlightScenario
from ..plotting.paths import plot_primary_axis
from ._numbers import PaperClaim, PaperNumber

if TYPE_CHECKING:
    from ._report import ReportFile, ReportSection, ReportTable

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
    """The scenario of :func:`scenarios` called ``name``; ``ValueError`` listing the names otherwise."""
    for s in scenarios():
        if s.name == name:
            return s
    raise ValueError(f"scenario: unknown {name!r}; available: {', '.join(s.name for s in scenarios())}")


@dataclass
class ScenarioRun:
    """One flight of a :class:`KeScenario` with a control ``law``: its trajectory and the
    verdict on the whole flight (``metrics``, :func:`flight_metrics`)."""

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
    ("faults_not_reached", "string"), ("ke_stabilizable", "bool"), ("verdict", "string"), ("cause", "string"),
    ("verdict_label", "string"), ("outcome", "string"), ("outcome_label", "string"),
    ("lost_at_s", "float64"), ("end_s", "float64"), ("window_s", "float64"), ("r_rad_s", "float64"), ("n3z", "float64"),
    ("rotation_axis", "string"), ("spin_settle_s", "float64"), ("max_altitude_loss_m", "float64"),
    ("max_horizontal_error_m", "float64"), ("final_horizontal_error_m", "float64"), ("final_altitude_error_m", "float64"),
    ("window_horizontal_error_m", "float64"), ("window_altitude_error_m", "float64"), ("window_speed_m_s", "float64"),
)


def report_rows(runs: list[ScenarioRun]) -> Records:
    """One record per run (:data:`REPORT_COLUMNS`; a sequence of dicts with ``to_arrow()`` and
    ``to_pandas()``). ``verdict`` is the flight's one verdict (``holds``, ``drifts``,
    ``circles``, ``crashed``, ``diverged``; ``cause`` how a lost run was lost; ``outcome`` the code
    before issue 28, kept for one release). ``efficiency`` is what the run reached (a lost run
    never had the faults after its loss), ``planned_efficiency`` the scenario's; ``None``: not
    settled (steady values) or lost (position values, see ``lost_at_s``)."""
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
                "verdict": m.verdict,
                "cause": m.cause,
                "verdict_label": m.verdict_label,
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
    beside ``out_dir`` and swapped in only when complete (the one report writer,
    :func:`rotorfault.papers._report.write_report_files`): an interrupted report leaves the
    previous one as it was. An existing report is replaced only with ``force``; a non-empty
    directory that is not a report never. Returns the Markdown file's path."""
    from ._report import write_report_files

    def content(tmp: Path) -> list[ReportFile]:
        if not runs:
            raise ValueError("runs: nothing to report (give at least one law and scenario)")
        first_law = runs[0].law
        if figures:
            chosen = [run for run in runs if run.law == first_law]
            for run in chosen:
                run.plot(str(tmp / f"{run.scenario.name}.png"))
            plot_primary_axis(chosen, str(tmp / "primary-axis.png"))
        return _report_files(runs, figures=figures)

    out = write_report_files(
        out_dir, content, field_name="out_dir", force=force, generator="rotorfault ftc-report (rotorfault.papers.ke.write_report)",
        command=command, default_command="rotorfault.papers.ke.write_report", laws=sorted({run.law for run in runs}),
        scenarios=sorted({run.scenario.name for run in runs}),
    )
    return out / "ftc-report.md"


#: The flights table of ``ftc-report.md``: (column, the report row's column, decimals; None: as text).
_MARKDOWN_COLUMNS: tuple[tuple[str, str, int | None], ...] = (
    ("scenario", "scenario", None), ("law", "law", None), ("Ke: stabilisable", "ke_stabilizable", 3),
    ("verdict", "verdict_label", None), ("efficiency reached", "efficiency", None), ("r (rad/s)", "r_rad_s", 1),
    ("n3z", "n3z", 3), ("rotation axis (body)", "rotation_axis", 3), ("spin settle (s)", "spin_settle_s", 1),
    ("max alt. loss (m)", "max_altitude_loss_m", 2), ("max horiz. (m)", "max_horizontal_error_m", 2),
    ("final horiz. (m)", "final_horizontal_error_m", 2), ("final alt. err. (m)", "final_altitude_error_m", 2),
)


def _report_files(runs: list[ScenarioRun], *, figures: bool = True) -> list[ReportFile]:
    """The text files of ``rotorfault ftc-report`` for ``runs``: ``ftc-report.csv`` (every
    column of :func:`report_rows`, six decimals) and ``ftc-report.md`` (the verdicts, the flights
    table, the stability checks of Table II's health matrices; ``figures``: whether the figures
    are listed)."""
    from ._report import CsvTable, MarkdownText, markdown_lines

    rows = report_rows(runs)
    flights = markdown_lines(
        [name for name, _, _ in _MARKDOWN_COLUMNS],
        [[r[column] if digits is None else cell(r, column, digits) for _, column, digits in _MARKDOWN_COLUMNS] for r in rows],
    )
    lines = [
        "# Uniform passive FTC (Ke et al.): scenario report",
        "",
        f"Every flight gets one verdict, judged over the last {runs[0].metrics.window_s:g} s of the run:",
        *(f"- {v}: {VERDICT_MEANINGS[v]};" for v in VERDICTS),
        "a lost run's position columns say when ('lost at t'): the track stops there.",
        "Steady values (r, n3z, rotation axis) are means over the same window, reported only for runs that",
        "settled: r within 5 % (0.2 rad/s) and n3z within 0.02 of them from the spin-settle time (counted from",
        "the last fault that changed an efficiency) to the end, at least one window before the end.",
        "'efficiency reached' is the rotor efficiency at the end of the run (a lost run never had the faults",
        "planned after its loss).",
        "",
        *flights,
    ]
    lines += ["", f"Verdicts counted ({len(rows)} flights): {verdict_count_text(r['verdict'] for r in rows)}."]
    lines += ["", "Stability checks of Section III-D (Table II health matrices, k_rotor = 2):", ""]
    frame = Airframe.preset("ke-quadcopter")
    checks = []
    for efficiency in TABLE_II_EFFICIENCY:
        check = stability_check(frame, efficiency)
        checks.append([f"diag({', '.join(f'{h:g}' for h in efficiency)})", ", ".join(f"{v.real:.4f}" for v in check.eigenvalues),
                       str(check.thrust_feedback), str(check.full_compensation)])
    lines += markdown_lines(["diag(efficiency)", "eig(N)", "Re eig(I + k N) > 0 (25)", "Re eig(N) > 0 (32)"], checks)
    if figures:
        lines += ["", f"Figures ({runs[0].law}): `primary-axis.png`, and one time history per scenario (`<scenario>.png`)."]
    else:
        lines += ["", "No figures (written with --no-figures)."]
    return [CsvTable.from_records("ftc-report.csv", rows, lambda r, column: cell(r, column, 6)), MarkdownText("ftc-report.md", tuple(lines))]


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


def printed_numbers(airframe: Airframe | None = None, *, health: Any = None) -> list[PaperNumber]:
    """Every eigenvalue Ke Table II prints beside ours (:func:`rotorfault.control.ke.n_eigenvalues`
    on the ``ke-quadcopter`` preset), both sorted ascending per row; a complex eigenvalue of ours
    (none is expected) is reported as ``nan`` and so "differs". Each is *reproduced*: computed
    from the vehicle's geometry (Table III, Fig. 8's numbering) and the health matrix, never from
    the printed value. ``airframe`` and ``health`` (a function from Table II's efficiencies to
    the health matrix's diagonal used, default the identity) let a test break what a row measures
    (``tests/papers/test_scoreboard.py``)."""
    from ..control.ke import n_eigenvalues

    frame = Airframe.preset("ke-quadcopter") if airframe is None else airframe
    rows = []
    for efficiency, printed in zip(TABLE_II_EFFICIENCY, TABLE_II_EIGENVALUES, strict=True):
        ours = n_eigenvalues(frame, efficiency if health is None else health(efficiency))
        case = f"diag({', '.join(f'{h:g}' for h in efficiency)})"
        for k, (value, mine) in enumerate(zip(sorted(printed), ours, strict=True), start=1):
            real_part = float(mine.real) if abs(mine.imag) <= 1e-12 else math.nan
            rows.append(PaperNumber(PAPER, "Table II", f"eig {k} of N, {case}", float(value), real_part, TABLE_II_TOL,
                                    kind="reproduced"))
    return rows


#: Ke's claims about its hovering flights, each scored against our flight of the same scenario
#: (:func:`flight_claims`): (scenario, where, the claim, the steady spin Ke reports (rad/s) or
#: None, whether Ke says the vehicle is stabilised). Ke's spins come from a real vehicle whose
#: rotational damping Ke does not give (README decisions): compared in words, not scored.
KE_CLAIMS: tuple[tuple[str, str, str, float | None, bool], ...] = (
    ("one-failure", "Sec. V-C, Fig. 16", "rotor 1 fails in hover: the vehicle recovers into a steady spin (about 23 rad/s)", 23.0, True),
    ("two-adjacent", "Sec. V-C, Figs. 9 and 16", "rotors 1 then 2 (adjacent, the right pair) fail: stabilised, spinning at about 38 rad/s", 38.0, True),
    ("two-opposite", "Sec. V-C, Fig. 16", "rotors 1 then 3 (opposite) fail: stabilised, spinning at about 42 rad/s", 42.0, True),
    ("three-failures", "Sec. V-C, Fig. 16", "rotors 1, 2 and 3 fail: stabilised, spinning at about 42 rad/s", 42.0, True),
    ("two-adjacent-front", "Sec. IV-B, Fig. 7", "rotors 1 then 4 (the front pair) fail: the uniform passive FTC cannot stabilise it", None, False),
)
#: Ke Sec. V-C 3): "while one rotor stops working, the quadcopter has an overshoot of less than
#: 10 meters in the horizontal position".
KE_OVERSHOOT_M = 10.0


def flight_claims(runs: list[ScenarioRun]) -> list[PaperClaim]:
    """Ke's flight claims (:data:`KE_CLAIMS`, the horizontal overshoot) beside our flights of the
    same scenarios with the default law (the runs given; a claim whose scenario was not flown is
    left out). A stabilisation claim is confirmed when the flight is not lost and its spin and
    tilt settle (``spin_settle_s``); Fig. 7's when the flight is lost or never settles."""
    from ._numbers import PaperClaim

    flown = {run.scenario.name: run for run in runs if run.law == "feedforward"}
    claims = []
    for name, where, claim, spin, stabilised in KE_CLAIMS:
        run = flown.get(name)
        if run is None:
            continue
        m = run.metrics
        settled = m.lost_at_s is None and m.settled
        if m.lost_at_s is not None:
            measured = m.verdict_label
        elif m.settled and m.r_rad_s is not None:
            measured = (f"steady spin {abs(m.r_rad_s):.1f} rad/s, n3z {m.n3z:.3f} after {m.spin_settle_s:.1f} s; final altitude error "
                        f"{m.final_altitude_error_m:.2f} m, {m.final_horizontal_error_m:.1f} m from the setpoint")
        else:
            measured = f"not settled; final altitude error {m.final_altitude_error_m:.2f} m"
        if stabilised:
            confirmed = settled
            reason = (f"the spin settles, {abs(m.r_rad_s or 0.0):.1f} rad/s against Ke's about {spin:g} (a real vehicle; our rotational "
                      "damping is a decision, README)" if confirmed else "the flight does not settle into a steady spin")
            if confirmed and m.verdict != "holds" and m.window_errors is not None:
                horizontal, vertical, speed = m.window_errors
                reason += (f"; it does not hold its setpoint (verdict {m.verdict}: over the last {m.window_s:g} s up to "
                           f"{horizontal:.1f} m off horizontally, {vertical:.1f} m in altitude, {speed:.2f} m/s; Table IV's "
                           "outer loop, k_v = 0.1 1/s and 0.15 m/s^2, brings it back slowly)")
        else:
            confirmed = not settled
            reason = ("the spin collapses and the vehicle is lost, as Fig. 7 predicts" if m.lost_at_s is not None
                      else "the flight does not settle, as Fig. 7 predicts" if confirmed else "it settles: Fig. 7 says it should not")
        claims.append(PaperClaim(PAPER, where, claim, measured, m.verdict, "confirmed" if confirmed else "not confirmed", reason))
    one = flown.get("one-failure")
    if one is not None:
        m = one.metrics
        worst = m.max_horizontal_error_m
        confirmed = worst is not None and worst < KE_OVERSHOOT_M
        claims.append(PaperClaim(
            PAPER, "Sec. V-C 3)", f"after one rotor failure the horizontal overshoot is less than {KE_OVERSHOOT_M:g} m",
            m.verdict_label if worst is None else f"largest horizontal error {worst:.1f} m (final {m.final_horizontal_error_m:.1f} m)",
            m.verdict, "confirmed" if confirmed else "not confirmed",
            "within the bound" if confirmed else
            "the vehicle tips to n3z = 0.45 in the half second before the spin builds up and picks up about 6 m/s; "
            "Table IV's outer loop (k_v = 0.1 1/s, 0.15 m/s^2) then brings it back slowly (README findings)",
        ))
    return claims


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
            a.scenario.name, a.metrics.verdict_label, b.metrics.verdict_label,
            "same" if a.metrics.verdict == b.metrics.verdict else "differs",
            f"{cell(row_a, 'window_horizontal_error_m', 3)} / {cell(row_b, 'window_horizontal_error_m', 3)}",
            f"{position_mm:.3f}", f"{attitude_deg:.4f}", clamped,
        ))
    return ReportTable(
        f"With sensors: the same flights on the truth and on {sensed[0].trajectory.sensed} (rotorfault.Sensing: the "
        "suite's IMU and position source, the error-state Kalman filter), side by side; the estimate's error over the "
        "whole run (a lost run's tumble included) and the share of IMU samples with the gyro clamped at 2000 deg/s",
        ("scenario", "truth: verdict", "sensors: verdict", "same verdict", "window horiz. (m) truth / sensors",
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
    section.claims = flight_claims(runs)
    section.tables.append(ReportTable(
        f"Flights ({'--quick: ' + str(len(chosen)) + ' scenarios' if quick else 'every scenario'}; preset ke-hil, "
        f"verdicts judged over the last {WINDOW_S:g} s (window errors: largest horizontal and altitude error and speed), "
        f"counted: {verdict_count_text(r['verdict'] for r in rows)}; Ke's experiment spins: about 23, 38 and 42 rad/s for one, two "
        "adjacent and two opposite failures)",
        ("scenario", "law", "Ke: stabilisable", "verdict", "efficiency reached", "r (rad/s)", "n3z", "max alt. loss (m)",
         "max / final horiz. (m)"),
        tuple(
            (r["scenario"], r["law"], cell(r, "ke_stabilizable"), r["verdict_label"], r["efficiency"], cell(r, "r_rad_s", 1),
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
    "KE_CLAIMS",
    "KE_OVERSHOOT_M",
    "flight_claims",
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
