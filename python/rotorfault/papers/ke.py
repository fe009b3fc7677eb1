"""Ke et al.'s uniform passive FTC (IEEE TIE), reproduced: the named scenarios of Sections II-B
and IV-B, the metrics of Section V and the report behind ``rotorfault ftc-report``. The controller
and its design are in :mod:`rotorfault.control.ke`.

Failures are applied one after the other from hover: the first rotor, then the next once the spin
has built up (Remark 3: simultaneous failures from r = 0 are not recoverable).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .._convert import FloatArray
from .._typing import KeLaw, KeOutcome
from ..airframe import Airframe
from ..control.ke import FtcPreset, UniformPassiveFtc, preset, stability_check
from ..simulation import RotorFault, State, Trajectory

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


#: Position band for "holds position": horizontal and vertical error at the end of the run, m.
HOLD_BAND_M = (2.0, 1.0)


@dataclass(frozen=True)
class FlightMetrics:
    """What Ke reports per flight. "Steady" values are means over the final ``window_s`` seconds
    and are ``None`` for a run that diverged (there is no steady state to report):

    - ``outcome``: ``"holds-position"`` (no divergence, final error within :data:`HOLD_BAND_M`,
      2 m horizontally and 1 m vertically), ``"off-station"`` (no divergence, outside the band)
      or the divergence kind (``"tilt"``, ...); :attr:`outcome_label` is the text for tables;
    - ``r_rad_s`` mean body yaw rate; ``n3z`` mean vertical component of the primary axis
      ``n3 = R_eb b_3`` (Fig. 14); ``rotation_axis`` the mean of ``R_eb^T [0, 0, 1]``, the world
      vertical in body axes (Section V-B: the axis a steady spin turns about);
    - ``spin_settle_s``: time from the last fault until ``r`` stays within 5 % (or 0.2 rad/s) and
      ``n3z`` within 0.02 of their steady values (Ke's "enter into a steady state");
    - ``max_altitude_loss_m`` the largest drop below the start; ``max_horizontal_error_m``,
      ``final_horizontal_error_m`` and ``final_altitude_error_m`` against the setpoint."""

    outcome: KeOutcome
    r_rad_s: float | None
    n3z: float | None
    rotation_axis: tuple[float, float, float] | None
    spin_settle_s: float | None
    max_altitude_loss_m: float
    max_horizontal_error_m: float
    final_horizontal_error_m: float
    final_altitude_error_m: float

    @property
    def outcome_label(self) -> str:
        """The outcome in words, for tables (``"holds position"``, ``"off station"``, ``"tilt"``)."""
        return OUTCOME_LABELS.get(self.outcome, self.outcome)


#: Table text of the outcomes that are not a divergence kind.
OUTCOME_LABELS: dict[str, str] = {"holds-position": "holds position", "off-station": "off station"}


def flight_metrics(trajectory: Trajectory, scenario_: KeScenario, *, window_s: float = 5.0) -> FlightMetrics:
    t = trajectory.t
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
    if trajectory.diverged:
        return FlightMetrics(trajectory.events[0].kind, None, None, None, None, *position_errors)
    last = t >= t[-1] - window_s
    r = float(np.mean(trajectory.omega[last, 2]))
    n3z = float(np.mean(trajectory.primary_axis[last, 2]))
    # R_eb^T e_z: the world vertical seen from the body (the rotation axis of a steady spin).
    axis = np.einsum("nji,j->ni", trajectory.rotation[last], np.array([0.0, 0.0, 1.0])).mean(axis=0)
    axis = axis / np.linalg.norm(axis)
    last_fault = max([0.0] + [f.time for f in scenario_.faults])
    unsettled = (np.abs(trajectory.omega[:, 2] - r) > max(0.05 * abs(r), 0.2)) | (
        np.abs(trajectory.primary_axis[:, 2] - n3z) > 0.02
    )
    idx = np.nonzero(unsettled & (t >= last_fault))[0]
    settle = 0.0 if idx.size == 0 else float(t[min(idx[-1] + 1, len(t) - 1)] - last_fault)
    held = position_errors[2] <= HOLD_BAND_M[0] and position_errors[3] <= HOLD_BAND_M[1]
    return FlightMetrics(
        "holds-position" if held else "off-station",
        r,
        n3z,
        (float(axis[0]), float(axis[1]), float(axis[2])),
        settle,
        *position_errors,
    )


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
    """Ke Fig. 16 style: the path of the primary axis ``n3`` (body z in the world) on the unit
    sphere for each run (the last ``tail_s`` seconds bold), seen from below the vehicle's
    downward axis. Returns the matplotlib figure, saved to ``path`` if given."""
    import matplotlib

    if path is not None:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    count = len(runs)
    cols = min(count, 4)
    rows_ = -(-count // cols)
    fig = plt.figure(figsize=(4.2 * cols, 4.2 * rows_))
    u, v = np.mgrid[0 : 2 * np.pi : 30j, 0 : np.pi / 2 : 12j]
    for k, run in enumerate(runs):
        ax = fig.add_subplot(rows_, cols, k + 1, projection="3d")
        ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", lw=0.4)
        n3 = run.trajectory.primary_axis
        t = run.trajectory.t
        late = t >= t[-1] - tail_s
        ax.plot(n3[:, 0], n3[:, 1], n3[:, 2], color="tab:orange", lw=0.6)
        ax.plot(n3[late, 0], n3[late, 1], n3[late, 2], color="tab:red", lw=1.4)
        ax.scatter([n3[0, 0]], [n3[0, 1]], [n3[0, 2]], color="tab:blue", s=20)
        below = bool(np.nanmin(n3[:, 2]) < 0)
        ax.set_xlim(-1, 1)
        ax.set_ylim(-1, 1)
        ax.set_zlim(-1 if below else 0, 1)
        ax.set_box_aspect((1, 1, 1 if below else 0.5))
        m = run.metrics
        steady = "" if m.r_rad_s is None or m.n3z is None else f", r = {m.r_rad_s:.1f} rad/s, n3z = {m.n3z:.3f}"
        ax.set_title(f"{run.scenario.name} ({run.law})\n{m.outcome_label}{steady}", fontsize=8)
        ax.set_xlabel("n3x", fontsize=7)
        ax.set_ylabel("n3y", fontsize=7)
        ax.set_zlabel("n3z", fontsize=7)
        ax.tick_params(labelsize=6)
    fig.suptitle("primary axis n3 on the unit sphere (blue: start, red: last 10 s)")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def report_rows(runs: list[ScenarioRun]) -> list[dict[str, Any]]:
    rows = []
    for run in runs:
        m = run.metrics
        rows.append(
            {
                "scenario": run.scenario.name,
                "law": run.law,
                "efficiency": " ".join(f"{h:g}" for h in run.scenario.efficiency),
                "ke_stabilizable": run.scenario.ke_stabilizable,
                "outcome": m.outcome,
                "outcome_label": m.outcome_label,
                "end_s": float(run.trajectory.t[-1]),
                "r_rad_s": m.r_rad_s,
                "n3z": m.n3z,
                "rotation_axis": "" if m.rotation_axis is None else " ".join(f"{v:+.3f}" for v in m.rotation_axis),
                "spin_settle_s": m.spin_settle_s,
                "max_altitude_loss_m": m.max_altitude_loss_m,
                "max_horizontal_error_m": m.max_horizontal_error_m,
                "final_horizontal_error_m": m.final_horizontal_error_m,
                "final_altitude_error_m": m.final_altitude_error_m,
            }
        )
    return rows


def write_report(runs: list[ScenarioRun], out_dir: str | Path, *, figures: bool = True) -> Path:
    """Writes ``ftc-report.md`` and ``ftc-report.csv`` (one row per run), and with ``figures``
    the time history of every run of the first law (``<scenario>.png``) and the primary-axis
    paths (``primary-axis.png``). Returns the Markdown file's path."""
    import csv

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = report_rows(runs)
    with open(out / "ftc-report.csv", "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = [
        "# Uniform passive FTC (Ke et al.): scenario report",
        "",
        "Steady values (r, n3z, rotation axis) are means over the last 5 s, blank for runs that",
        "diverged; spin settle counts from the last fault until r and n3z stay near those values.",
        "Outcome: 'holds position' ends within 2 m horizontally and 1 m vertically of the setpoint.",
        "",
        "| scenario | law | Ke: stabilisable | outcome | end (s) | r (rad/s) | n3z | rotation axis (body) "
        "| spin settle (s) | max alt. loss (m) | max horiz. (m) | final horiz. (m) | final alt. err. (m) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]

    def number(value: float | None, digits: int) -> str:
        return "" if value is None else f"{value:.{digits}f}"

    for r in rows:
        lines.append(
            f"| {r['scenario']} | {r['law']} | {'yes' if r['ke_stabilizable'] else 'no'} | {r['outcome_label']} "
            f"| {r['end_s']:.1f} | {number(r['r_rad_s'], 1)} | {number(r['n3z'], 3)} | {r['rotation_axis']} "
            f"| {number(r['spin_settle_s'], 1)} | {r['max_altitude_loss_m']:.2f} | {r['max_horizontal_error_m']:.2f} "
            f"| {r['final_horizontal_error_m']:.2f} | {r['final_altitude_error_m']:.2f} |"
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
    if figures:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        first_law = runs[0].law
        chosen = [run for run in runs if run.law == first_law]
        for run in chosen:
            fig = run.trajectory.plot(str(out / f"{run.scenario.name}.png"))
            plt.close(fig)
        fig = plot_primary_axis(chosen, str(out / "primary-axis.png"))
        plt.close(fig)
        lines += ["", f"Figures ({first_law}): `primary-axis.png`, and one time history per scenario."]
    path = out / "ftc-report.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


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


__all__ = [
    "HOLD_BAND_M",
    "OUTCOME_LABELS",
    "TABLE_II_EFFICIENCY",
    "FlightMetrics",
    "KeScenario",
    "ScenarioRun",
    "flight_metrics",
    "plot_primary_axis",
    "report_rows",
    "run_scenario",
    "scenario",
    "scenarios",
    "write_report",
]
