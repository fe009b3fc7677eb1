"""Ke et al.'s uniform passive FTC (IEEE TIE), reproduced: the named scenarios of Sections II-B
and IV-B, the metrics of Section V and the report behind ``rotorfault ftc-report``. The controller
and its design are in :mod:`rotorfault.control.ke`.

Failures are applied one after the other from hover: the first rotor, then the next once the spin
has built up (Remark 3: simultaneous failures from r = 0 are not recoverable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._convert import FloatArray, real
from .._typing import KeLaw, KeOutcome
from ..airframe import Airframe
from ..control.ke import FtcPreset, UniformPassiveFtc, preset, stability_check
from ..simulation import RotorFault, State, Trajectory
from ._numbers import PaperNumber

if TYPE_CHECKING:
    from ._report import ReportSection

if TYPE_CHECKING:
    from matplotlib.figure import Figure

# -- scenarios ----------------------------------------------------------------------------------

HOVER = (0.0, 0.0, -10.0)


@dataclass(frozen=True)
class KeScenario:
    """A named flight: faults applied in order from hover, setpoints (time, NED position).
    ``efficiency`` is the rotor efficiencies after the last fault (Ke's health matrix is
    ``diag(efficiency)``)."""

    name: str
    description: str
    efficiency: tuple[float, ...]
    faults: tuple[RotorFault, ...]
    duration_s: float = 40.0
    setpoints: tuple[tuple[float, tuple[float, float, float]], ...] = ((0.0, HOVER),)
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


# -- metrics (Section V) -----------------------------------------------------------------------


#: "holds position": over the last ``window_s`` seconds the horizontal error stays within 2 m
#: and the altitude error within 1 m of the setpoint (m).
HOLD_BAND_M = (2.0, 1.0)
#: ... and the speed stays below this (m/s): passing through the setpoint is not holding it.
HOLD_SPEED_M_S = 0.5
#: "circling": not holding, the mean horizontal speed over the window above
#: :data:`HOLD_SPEED_M_S` and the direction of travel turning by at least this much (rad) within
#: the window: a steady circle, or an oscillation (which reverses, a turn of pi).
CIRCLING_TURN_RAD = math.pi / 2
#: Length of the judging window at the end of a run (s): outcome, steady values, settling.
WINDOW_S = 5.0


@dataclass(frozen=True)
class FlightMetrics:
    """What Ke reports per flight, judged over the last ``window_s`` seconds of the run (not its
    last sample). Outcome codes (:data:`OUTCOME_LABELS` gives the table text):

    - ``"holds-position"``: no divergence, and throughout the window the horizontal error is
      within ``HOLD_BAND_M[0]`` (2 m), the altitude error within ``HOLD_BAND_M[1]`` (1 m) and
      the speed below :data:`HOLD_SPEED_M_S` (0.5 m/s);
    - ``"circling"``: no divergence, not holding, moving (mean horizontal speed above 0.5 m/s)
      with the direction of travel turning by at least :data:`CIRCLING_TURN_RAD` (90 degrees)
      within the window: a steady circle or oscillation around or near the setpoint;
    - ``"off-station"``: no divergence, neither of the above (e.g. drifting back slowly, or
      parked away from the setpoint);
    - a divergence kind (``"tilt"``, ``"altitude-loss"``, ...): the vehicle was lost at
      ``lost_at_s``.

    Window values (``None`` for a lost run): ``window_horizontal_error_m`` and
    ``window_altitude_error_m`` the largest errors, ``window_speed_m_s`` the largest speed,
    ``window_mean_horizontal_speed_m_s``.

    Steady values, ``None`` unless the run settled: ``r_rad_s`` mean body yaw rate; ``n3z``
    mean vertical component of the primary axis ``n3 = R_eb b_3`` (Fig. 14); ``rotation_axis``
    the mean of ``R_eb^T [0, 0, 1]``, the world vertical in body axes (Section V-B: the axis a
    steady spin turns about). ``spin_settle_s``: time from the last fault that changed an
    efficiency (or from the start) until ``r`` stays within 5 % (at least 0.2 rad/s) and ``n3z``
    within 0.02 of those means to the end of the run; the run counts as settled only if that
    happens no later than ``window_s`` before its end (Ke's "enter into a steady state").

    Position values over the whole run (``None`` for a lost run, whose track stops at the loss:
    tables show "lost at t"): ``max_altitude_loss_m`` the largest drop below the start,
    ``max_horizontal_error_m``, ``final_horizontal_error_m``, ``final_altitude_error_m``
    against the setpoint."""

    outcome: KeOutcome
    r_rad_s: float | None
    n3z: float | None
    rotation_axis: tuple[float, float, float] | None
    spin_settle_s: float | None
    max_altitude_loss_m: float | None
    max_horizontal_error_m: float | None
    final_horizontal_error_m: float | None
    final_altitude_error_m: float | None
    window_s: float = WINDOW_S
    window_horizontal_error_m: float | None = None
    window_altitude_error_m: float | None = None
    window_speed_m_s: float | None = None
    window_mean_horizontal_speed_m_s: float | None = None
    lost_at_s: float | None = None

    @property
    def outcome_label(self) -> str:
        """The outcome in words, for tables (``"holds position"``, ``"circling"``, ``"off
        station"``, ``"tilt"``, ...)."""
        return OUTCOME_LABELS.get(self.outcome, self.outcome)

    @property
    def settled(self) -> bool:
        return self.spin_settle_s is not None


#: Table text of the outcome codes.
OUTCOME_LABELS: dict[str, str] = {
    "holds-position": "holds position",
    "circling": "circling",
    "off-station": "off station",
    "crashed": "crashed",
    "non-finite-state": "non-finite state",
    "non-finite-command": "non-finite command",
    "tilt": "tilt",
    "altitude-loss": "altitude loss",
    "speed": "speed",
    "body-rate": "body rate",
}


def effective_fault_times(trajectory: Trajectory) -> list[float]:
    """Times of the trajectory's own faults that changed a rotor's efficiency within the run (a
    no-op entry, which sets the efficiency a rotor already has, is not an event; nor is a fault
    the run never reached because it ended first)."""
    if not len(trajectory.t):
        return []
    current = np.array(trajectory.efficiency[0], dtype=np.float64)
    times = []
    for f in sorted(trajectory.faults, key=lambda f: f.time):
        if f.time > trajectory.t[-1]:
            break
        if current[f.rotor - 1] != f.efficiency:
            times.append(float(f.time))
            current[f.rotor - 1] = f.efficiency
    return times


def flight_metrics(trajectory: Trajectory, scenario_: KeScenario, *, window_s: float = WINDOW_S) -> FlightMetrics:
    """Scores ``trajectory`` against ``scenario_``'s setpoints. Fault times come from the
    trajectory's own faults (what it was flown with), not from the scenario."""
    window_s = real("window_s", window_s)
    if not window_s > 0:
        raise ValueError(f"window_s: must be > 0, got {window_s}")
    t = trajectory.t
    if len(t) < 2:
        raise ValueError(f"trajectory: needs at least 2 samples to be scored, got {len(t)}")
    if trajectory.diverged:
        event = trajectory.events[0]
        return FlightMetrics(event.kind, None, None, None, None, None, None, None, None, window_s, lost_at_s=float(event.time))
    setpoint = _setpoint_track(scenario_, t)
    error = trajectory.position - setpoint
    horizontal = np.hypot(error[:, 0], error[:, 1])
    vertical = np.abs(error[:, 2])
    start_alt = -trajectory.position[0, 2]
    position_errors = (
        float(np.max(start_alt - (-trajectory.position[:, 2]))),
        float(np.max(horizontal)),
        float(horizontal[-1]),
        float(vertical[-1]),
    )
    last = t >= t[-1] - window_s
    speed = np.linalg.norm(trajectory.velocity, axis=1)
    h_speed = np.hypot(trajectory.velocity[:, 0], trajectory.velocity[:, 1])
    window = (
        float(np.max(horizontal[last])),
        float(np.max(vertical[last])),
        float(np.max(speed[last])),
        float(np.mean(h_speed[last])),
    )
    held = window[0] <= HOLD_BAND_M[0] and window[1] <= HOLD_BAND_M[1] and window[2] <= HOLD_SPEED_M_S
    if held:
        outcome: KeOutcome = "holds-position"
    elif window[3] > HOLD_SPEED_M_S and _turn_rad(trajectory.velocity[last], HOLD_SPEED_M_S / 4) >= CIRCLING_TURN_RAD:
        outcome = "circling"
    else:
        outcome = "off-station"
    r = float(np.mean(trajectory.omega[last, 2]))
    n3z = float(np.mean(trajectory.primary_axis[last, 2]))
    # R_eb^T e_z: the world vertical seen from the body (the rotation axis of a steady spin).
    axis = np.einsum("nji,j->ni", trajectory.rotation[last], np.array([0.0, 0.0, 1.0])).mean(axis=0)
    axis = axis / np.linalg.norm(axis)
    last_fault = max([0.0, *effective_fault_times(trajectory)])
    unsettled = (np.abs(trajectory.omega[:, 2] - r) > max(0.05 * abs(r), 0.2)) | (
        np.abs(trajectory.primary_axis[:, 2] - n3z) > 0.02
    )
    idx = np.nonzero(unsettled & (t >= last_fault))[0]
    settled_from = last_fault if idx.size == 0 else (float(t[idx[-1] + 1]) if idx[-1] + 1 < len(t) else math.inf)
    if settled_from > t[-1] - window_s + 1e-9:
        # Still moving at (or within the window before) the end: no settle time, no steady values.
        return FlightMetrics(outcome, None, None, None, None, *position_errors, window_s, *window)
    return FlightMetrics(
        outcome,
        r,
        n3z,
        (float(axis[0]), float(axis[1]), float(axis[2])),
        settled_from - last_fault,
        *position_errors,
        window_s,
        *window,
    )


def _turn_rad(velocity: FloatArray, min_speed: float) -> float:
    """How far the horizontal direction of travel turns (range of the unwrapped heading, rad),
    over the samples moving faster than ``min_speed``; a reversal counts as pi."""
    moving = np.hypot(velocity[:, 0], velocity[:, 1]) > min_speed
    if moving.sum() < 2:
        return 0.0
    heading = np.unwrap(np.arctan2(velocity[moving, 1], velocity[moving, 0]))
    return float(np.max(heading) - np.min(heading))


def _setpoint_track(scenario_: KeScenario, t: FloatArray) -> FloatArray:
    times = np.array([s for s, _ in scenario_.setpoints])
    points = np.array([p for _, p in scenario_.setpoints])
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    out: FloatArray = points[k]
    return out


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
) -> ScenarioRun:
    """Flies one scenario with the uniform passive FTC (or ``law="baseline"``)."""
    if not isinstance(scenario_, (str, KeScenario)):
        raise TypeError(f"scenario: expected a KeScenario or a scenario name, got {type(scenario_).__name__}")
    if not isinstance(controller_preset, (str, FtcPreset)):
        raise TypeError(f"controller_preset: expected an FtcPreset or a preset name, got {type(controller_preset).__name__}")
    sc = scenario(scenario_) if isinstance(scenario_, str) else scenario_
    pre = preset(controller_preset) if isinstance(controller_preset, str) else controller_preset
    sim = pre.simulator()
    controller = UniformPassiveFtc(pre.airframe, gains=pre.gains, law=law, setpoints=sc.setpoints)
    start = State(position=sc.setpoints[0][1])
    trajectory = sim.run(start, sc.duration_s, controller=controller, faults=sc.faults, record_every=record_every)
    return ScenarioRun(sc, law, trajectory)


# -- report (rotorfault ftc-report) --------------------------------------------------------------


def plot_primary_axis(runs: list[ScenarioRun], path: str | None = None, *, tail_s: float = 10.0) -> Figure:
    """Ke Fig. 16 style: the path of the primary axis ``n3`` (body z in the world, NED) on the
    unit sphere for each run, drawn with ``n3z`` (the world-down component: 1 is level) upward
    and viewed obliquely from above that pole; the whole path thin and dashed, the last
    ``tail_s`` seconds solid and bold, the start a circle, the loss (if any) a cross. Returns the
    figure (not registered with pyplot), saved to ``path`` if given."""
    from .._output import MIN_FONT_PT, new_figure, save_figure

    if not runs:
        raise ValueError("runs: give at least one run to plot")
    count = len(runs)
    cols = min(count, 4)
    rows_ = -(-count // cols)
    fig = new_figure(figsize=(4.4 * cols, 4.6 * rows_ + 0.9), layout="constrained")
    u, v = np.mgrid[0 : 2 * np.pi : 30j, 0 : np.pi : 24j]
    handles: dict[str, Any] = {}
    for k, run in enumerate(runs):
        ax = fig.add_subplot(rows_, cols, k + 1, projection="3d")
        n3 = run.trajectory.primary_axis
        t = run.trajectory.t
        below = bool(np.nanmin(n3[:, 2]) < 0)
        uu, vv = (u, v) if below else (u[:, :13], v[:, :13])
        ax.plot_wireframe(np.cos(uu) * np.sin(vv), np.sin(uu) * np.sin(vv), np.cos(vv), color="0.85", lw=0.4)
        late = t >= t[-1] - tail_s
        whole = ax.plot(n3[:, 0], n3[:, 1], n3[:, 2], color="0.45", lw=0.7, linestyle="--", label="whole flight")
        tail = ax.plot(n3[late, 0], n3[late, 1], n3[late, 2], color="black", lw=1.8, label=f"last {tail_s:g} s")
        start = ax.scatter([n3[0, 0]], [n3[0, 1]], [n3[0, 2]], color="black", marker="o", s=28, label="start")
        handles.update({"whole flight": whole[0], f"last {tail_s:g} s": tail[0], "start": start})
        if run.trajectory.diverged:
            handles["lost"] = ax.scatter([n3[-1, 0]], [n3[-1, 1]], [n3[-1, 2]], color="black", marker="x", s=60, label="lost")
        ax.set_xlim(-1, 1)
        ax.set_ylim(-1, 1)
        ax.set_zlim(-1 if below else 0, 1)
        ax.set_box_aspect((1, 1, 1 if below else 0.5), zoom=0.82)
        ax.view_init(elev=30, azim=-60)
        ax.set_xticks([-1, 0, 1])
        ax.set_yticks([-1, 0, 1])
        ax.set_zticks([-1, 0, 1] if below else [0, 0.5, 1])
        m = run.metrics
        if m.lost_at_s is not None:
            state = f"lost at {m.lost_at_s:.2f} s ({m.outcome_label})"
        elif m.r_rad_s is not None and m.n3z is not None:
            state = f"{m.outcome_label}, r = {m.r_rad_s:.1f} rad/s, n3z = {m.n3z:.3f}"
        else:
            state = f"{m.outcome_label}, not settled"
        ax.set_title(f"{run.scenario.name} ({run.law})\n{state}", fontsize=9)
        for name, setter in (("n3x", ax.set_xlabel), ("n3y", ax.set_ylabel), ("n3z", ax.set_zlabel)):
            setter(name, fontsize=9, labelpad=2)
        ax.tick_params(labelsize=MIN_FONT_PT, pad=1)
    fig.suptitle("primary axis n3 on the unit sphere (Ke Fig. 16 style; n3z = 1 is level)", fontsize=11)
    fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncol=len(handles), fontsize=9, frameon=False)
    if path is not None:
        save_figure(fig, path)
    return fig


def _efficiency_text(values: Any) -> str:
    return " ".join(f"{float(h):g}" for h in values)


def report_rows(runs: list[ScenarioRun]) -> list[dict[str, Any]]:
    """One record per run. ``efficiency`` is what the run reached (a lost run never had the
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
    return rows


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
    import csv
    import io
    from importlib.metadata import PackageNotFoundError, version

    from .._output import check_output_directory, output_directory

    out = check_output_directory("out_dir", out_dir, force=force)
    if not runs:
        raise ValueError("runs: nothing to report (give at least one law and scenario)")
    rows = report_rows(runs)
    try:
        package_version = version("rotorfault")
    except PackageNotFoundError:  # pragma: no cover - running from a source tree
        package_version = "unknown"
    manifest = {
        "generator": "rotorfault ftc-report (rotorfault.papers.ke.write_report)",
        "command": command or "rotorfault.papers.ke.write_report",
        "version": package_version,
        "laws": sorted({run.law for run in runs}),
        "scenarios": sorted({run.scenario.name for run in runs}),
    }
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    for r in rows:
        writer.writerow({column: cell(r, column, 6) for column in r})
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
    with output_directory(out, manifest) as tmp:
        (tmp / "ftc-report.csv").write_text(buffer.getvalue(), encoding="utf-8")
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
    plot_primary_axis(runs, str(out / "ke-primary-axis.png"))
    section.figures.append(ReportFigure("ke-primary-axis.png", "The primary axis n3 on the unit sphere for every flight (Ke Fig. 16 style)."))
    for run in runs + extra:
        name = f"ke-{run.scenario.name}-{run.law}.png"
        run.plot(str(out / name))
        section.figures.append(ReportFigure(name, f"{run.scenario.name}, law {run.law}: {run.scenario.description}", small=True))
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
    "scenario",
    "scenarios",
    "write_report",
]
