"""Uniform passive fault-tolerant control of a quadcopter (Ke, Cai, Quan; IEEE TIE).

One controller and one set of gains fly the vehicle fault-free and through one, two and three
rotor failures, without fault detection or switching: the controller never sees rotor health. The
controller itself runs in Rust (:class:`rotorfault.controllers.UniformPassiveFTC`); this module
holds its gain presets, the stability analysis of Ke's Section III-D (the N matrix, Table II),
the named scenarios of Sections II-B and IV-B, the metrics of Section V and the report behind
``rotorfault ftc-report``.

Decisions on the paper's gaps (also in the README):

- the control command (18) as printed leaves a steady virtual-control deficit
  (``u_1 = k/(k+1) u_d1`` without a fault, eq. (43)); the default ``law="feedforward"`` adds the
  filtered desired virtual control, which removes the deficit, keeps the partial compensation of
  a fault and leaves the stability matrix ``I + k_rotor N`` of (25) unchanged. ``law="literal"``
  is (18) as printed, ``"full-compensation"`` Remark 5's (29), ``"baseline"`` a conventional
  cascade into the pseudo-inverse;
- Ke gives no aerodynamic rotational damping, which sets the spin rate: the presets carry a linear
  damping ``rotational_drag_n_m_s`` chosen so the steady spins land in the range of Ke's
  experiments;
- failures are applied one after the other from hover: the first rotor, then the next once the
  spin has built up (Remark 3: simultaneous failures from r = 0 are not recoverable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from . import _rfcore
from ._convert import FloatArray, float_array, real
from .airframe import Airframe
from .simulation import DivergenceLimits, Drag, FixedPitchActuator, RotorFault, Simulator, State, Trajectory

#: Rows of the virtual control Ke's N matrix uses: thrust, roll, pitch (E_1).
E1_ROWS = (0, 1, 2)


@dataclass(frozen=True)
class KeGains:
    """Ke Table IV (HIL column by default) plus ``k_cp`` of Remark 4 and the remedy's altitude
    integral ``k_iz`` (not in the paper; equal to the ``ke-hil`` preset). Validated in Rust when a
    controller is built: ``epsilon_s``, ``k_rotor``, ``k_rotor_z``, ``k_p``, ``k_v``, ``k_n3``,
    ``accel_limit_m_s2`` > 0, ``k_vz`` and ``k_omega`` > 0.5 (Theorem 1)."""

    k_p: float = 0.3
    k_v: float = 0.1
    k_vz: float = 1.0
    accel_limit_m_s2: float = 0.15
    k_n3: float = 3.0
    k_omega: float = 14.0
    k_r: float = 4.2
    k_cp: float = 0.6
    epsilon_s: float = 0.06
    k_rotor: float = 2.0
    k_rotor_z: float = 0.1
    weights: tuple[float, float, float, float] = (1.0, 20.0, 20.0, 0.01)
    #: Altitude integral of the remedy (``law="feedforward"`` only), 1/s^2; not in the paper (the
    #: ``ke-hil`` preset's value).
    k_iz: float = 0.1

    def _packed(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "weights":
                w = float_array("gains.weights", value, 1)
                if w.shape != (4,):
                    raise ValueError(f"gains.weights: expected 4 entries (w_f, w_p, w_q, w_r), got {w.shape[0]}")
                out["weights"] = [float(v) for v in w]
            else:
                out[f.name] = real(f"gains.{f.name}", value)
        return out


@dataclass(frozen=True)
class FtcPreset:
    """A controller preset file (``presets/ftc/*.toml``): gains and the vehicle values that go with
    them (rotor lag from Ke Table III, the rotational damping Ke does not give)."""

    name: str
    description: str
    source: str
    airframe_name: str
    gains: KeGains
    rotor_time_constant_s: float
    rotational_drag_n_m_s: float
    linear_drag_n_s_m: float

    @property
    def airframe(self) -> Airframe:
        return Airframe.preset(self.airframe_name)

    def simulator(self, dt: float = 1 / 400, substeps: int = 4, limits: DivergenceLimits | None = None) -> Simulator:
        """The preset's vehicle at Ke's 400 Hz control rate: rotor lag and rotational damping."""
        return Simulator(
            self.airframe,
            dt=dt,
            substeps=substeps,
            actuator=FixedPitchActuator(time_constant_s=self.rotor_time_constant_s),
            drag=Drag(rotational_n_m_s=self.rotational_drag_n_m_s, linear_n_s_m=self.linear_drag_n_s_m),
            limits=limits,
        )


def _ftc_dir() -> Path:
    return Path(str(resources.files("rotorfault") / "presets" / "ftc"))


def presets() -> list[str]:
    """Names of the shipped controller presets (``ke-hil``, ``ke-experiment``)."""
    return sorted(p.stem for p in _ftc_dir().glob("*.toml"))


def preset(name: str = "ke-hil") -> FtcPreset:
    """A shipped controller preset by name."""
    if not isinstance(name, str):
        raise TypeError(f"preset: expected a preset name (str), got {type(name).__name__}")
    if name not in presets():
        raise ValueError(f"preset: unknown controller preset {name!r}; available: {', '.join(presets())}")
    raw = _rfcore.ftc_preset_from_toml((_ftc_dir() / f"{name}.toml").read_text(encoding="utf-8"), name)
    gains = dict(raw["gains"])
    gains["weights"] = tuple(gains["weights"])
    return FtcPreset(
        raw["name"],
        raw["description"],
        raw["source"],
        raw["airframe"],
        KeGains(**gains),
        raw["vehicle"]["rotor_time_constant_s"],
        raw["vehicle"]["rotational_drag_n_m_s"],
        raw["vehicle"]["linear_drag_n_s_m"],
    )


# -- Section III-D: stability analysis --------------------------------------------------------


def n_matrix(airframe: Airframe, health: Any) -> FloatArray:
    """Ke's ``N = (E_1 M) Lambda (E_1 M)^+`` (3 x 3) with ``M`` the airframe's nominal
    effectiveness matrix and ``Lambda = diag(health)``: how the rotors turn a commanded
    thrust/roll/pitch into what the vehicle receives under pseudo-inverse allocation (24)."""
    if not isinstance(airframe, Airframe):
        raise TypeError(f"airframe: expected an Airframe, got {type(airframe).__name__}")
    lam = float_array("health", health, 1)
    nominal = airframe.with_efficiency(np.ones(airframe.rotor_count))
    frame = nominal.with_efficiency(lam)  # validates health: one per rotor, in [0, 1]
    e1m = nominal.effectiveness_matrix()[list(E1_ROWS)]
    e1m_lambda = frame.effectiveness_matrix()[list(E1_ROWS)]
    out: FloatArray = e1m_lambda @ np.linalg.pinv(e1m)
    return out


ComplexArray = npt.NDArray[np.complex128]


def n_eigenvalues(airframe: Airframe, health: Any) -> ComplexArray:
    """Eigenvalues of :func:`n_matrix` (Table II), sorted by real part then imaginary part."""
    values = np.linalg.eigvals(n_matrix(airframe, health)).astype(np.complex128)
    order = np.lexsort((values.imag, values.real))
    out: ComplexArray = values[order]
    return out


@dataclass(frozen=True)
class StabilityCheck:
    """Ke's linear checks for one health matrix: ``thrust_feedback`` is (25),
    ``Re eig(I + k_rotor N) > 0`` (the uniform controller); ``full_compensation`` is (32),
    ``Re eig(N) > 0`` (Remark 5's controller, which fails with two or three failures)."""

    health: tuple[float, ...]
    eigenvalues: ComplexArray
    k_rotor: float
    thrust_feedback: bool
    full_compensation: bool


def stability_check(airframe: Airframe, health: Any, k_rotor: float = 2.0) -> StabilityCheck:
    k = real("k_rotor", k_rotor)
    if not (math.isfinite(k) and k > 0):
        raise ValueError(f"k_rotor: must be > 0 and finite, got {k}")
    eig = n_eigenvalues(airframe, health)
    tol = 1e-12
    return StabilityCheck(
        tuple(float(v) for v in float_array("health", health, 1)),
        eig,
        k,
        bool(np.all((1.0 + k * eig).real > tol)),
        bool(np.all(eig.real > tol)),
    )


# -- scenarios ----------------------------------------------------------------------------------

HOVER = (0.0, 0.0, -10.0)


@dataclass(frozen=True)
class Scenario:
    """A named flight: faults applied in order from hover, setpoints (time, NED position)."""

    name: str
    description: str
    health: tuple[float, ...]
    faults: tuple[RotorFault, ...]
    t_final: float = 40.0
    setpoints: tuple[tuple[float, tuple[float, float, float]], ...] = ((0.0, HOVER),)
    #: What Ke predicts: True (stabilised), False (Fig. 7: not stabilisable).
    ke_stabilizable: bool = True


def _sequential(health: tuple[float, ...], order: tuple[int, ...], first_s: float = 2.0, gap_s: float = 8.0) -> tuple[RotorFault, ...]:
    return tuple(RotorFault(rotor, first_s + k * gap_s, health[rotor - 1]) for k, rotor in enumerate(order))


def _both_orders(
    name: str, description: str, health: tuple[float, ...], order: tuple[int, int], ke_stabilizable: bool = True
) -> tuple[Scenario, Scenario]:
    """A two-failure scenario and ``<name>-reversed``, the same pair failing in the other order
    (the mirror image: the same outcome with the spin reversed)."""
    first, second = order
    return (
        Scenario(name, description, health, _sequential(health, order), ke_stabilizable=ke_stabilizable),
        Scenario(
            f"{name}-reversed",
            f"diag({', '.join(f'{h:g}' for h in health)}) in the other order: rotor {second} first, then rotor "
            f"{first} (the mirror image)",
            health,
            _sequential(health, (second, first)),
            ke_stabilizable=ke_stabilizable,
        ),
    )


def scenarios() -> list[Scenario]:
    """Ke Section II-B's health matrices as sequential faults from hover, position tracking after a
    failure, and both adjacent pairs (Figs. 7 and 9) in both orders.

    Ke's numbering (the preset's): 1 front right, 2 rear right, 3 rear left, 4 front left, rotors
    1 and 3 anticlockwise. So ``diag(0, 0, 1, 1)`` is two *adjacent* failures (the right pair, Ke's
    experiment; the left pair remains) and ``diag(0, 1, 0, 1)`` two *opposite*. The front (or rear)
    pair failing, ``diag(0, 1, 1, 0)``, is Fig. 7's case: not stabilisable."""
    return [
        Scenario("fault-free", "diag(1, 1, 1, 1): hover, no fault", (1, 1, 1, 1), (), 20.0),
        Scenario("partial-0.5", "diag(0.5, 1, 1, 1): rotor 1 at half efficiency", (0.5, 1, 1, 1), _sequential((0.5, 1, 1, 1), (1,))),
        Scenario("one-failure", "diag(0, 1, 1, 1): rotor 1 fails", (0, 1, 1, 1), _sequential((0, 1, 1, 1), (1,))),
        Scenario(
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
        Scenario("two-opposite", "diag(0, 1, 0, 1): rotor 1 fails, then the opposite rotor 3", (0, 1, 0, 1), _sequential((0, 1, 0, 1), (1, 3))),
        *_both_orders(
            "two-adjacent-front",
            "diag(0, 1, 1, 0): rotor 1 (front right) fails, then rotor 4 (front left); the rear pair "
            "remains (Ke Fig. 7: not stabilisable)",
            (0, 1, 1, 0),
            (1, 4),
            ke_stabilizable=False,
        ),
        Scenario("three-failures", "diag(0, 0, 0, 1): rotors 1, 2, 3 fail one after another", (0, 0, 0, 1), _sequential((0, 0, 0, 1), (1, 2, 3)), 50.0),
        Scenario(
            "tracking-one-failure",
            "rotor 1 fails in hover; at 20 s the setpoint moves 10 m east, across the drift the failure "
            "caused (position control, Fig. 17)",
            (0, 1, 1, 1),
            (RotorFault(1, 2.0, 0.0),),
            80.0,
            ((0.0, HOVER), (20.0, (0.0, 10.0, -10.0))),
        ),
    ]


def scenario(name: str) -> Scenario:
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

    - ``outcome``: ``"holds position"`` (no divergence, final error within :data:`HOLD_BAND_M`,
      2 m horizontally and 1 m vertically), ``"off station"`` (no divergence, outside the band)
      or the divergence reason (``"tilt"``, ...);
    - ``r_rad_s`` mean body yaw rate; ``n3z`` mean vertical component of the primary axis
      ``n3 = R_eb b_3`` (Fig. 14); ``rotation_axis`` the mean of ``R_eb^T [0, 0, 1]``, the world
      vertical in body axes (Section V-B: the axis a steady spin turns about);
    - ``spin_settle_s``: time from the last fault until ``r`` stays within 5 % (or 0.2 rad/s) and
      ``n3z`` within 0.02 of their steady values (Ke's "enter into a steady state");
    - ``max_altitude_loss_m`` the largest drop below the start; ``max_horizontal_error_m``,
      ``final_horizontal_error_m`` and ``final_altitude_error_m`` against the setpoint."""

    outcome: str
    r_rad_s: float | None
    n3z: float | None
    rotation_axis: tuple[float, float, float] | None
    spin_settle_s: float | None
    max_altitude_loss_m: float
    max_horizontal_error_m: float
    final_horizontal_error_m: float
    final_altitude_error_m: float


def flight_metrics(trajectory: Trajectory, scenario_: Scenario, window_s: float = 5.0) -> FlightMetrics:
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
        "holds position" if held else "off station",
        r,
        n3z,
        (float(axis[0]), float(axis[1]), float(axis[2])),
        settle,
        *position_errors,
    )


def _setpoint_track(scenario_: Scenario, t: FloatArray) -> FloatArray:
    times = np.array([s for s, _ in scenario_.setpoints])
    points = np.array([p for _, p in scenario_.setpoints])
    k = np.clip(np.searchsorted(times, t, side="right") - 1, 0, len(times) - 1)
    out: FloatArray = points[k]
    return out


@dataclass
class ScenarioRun:
    scenario: Scenario
    law: str
    trajectory: Trajectory
    metrics: FlightMetrics = field(init=False)

    def __post_init__(self) -> None:
        self.metrics = flight_metrics(self.trajectory, self.scenario)


def run_scenario(
    scenario_: Scenario | str,
    law: str = "feedforward",
    controller_preset: FtcPreset | str = "ke-hil",
    record_every: int = 4,
) -> ScenarioRun:
    """Flies one scenario with the uniform passive FTC (or ``law="baseline"``)."""
    from .controllers import UniformPassiveFTC

    if not isinstance(scenario_, (str, Scenario)):
        raise TypeError(f"scenario: expected a Scenario or a scenario name, got {type(scenario_).__name__}")
    if not isinstance(controller_preset, (str, FtcPreset)):
        raise TypeError(f"controller_preset: expected an FtcPreset or a preset name, got {type(controller_preset).__name__}")
    sc = scenario(scenario_) if isinstance(scenario_, str) else scenario_
    pre = preset(controller_preset) if isinstance(controller_preset, str) else controller_preset
    sim = pre.simulator()
    controller = UniformPassiveFTC(pre.airframe, gains=pre.gains, law=law, setpoints=sc.setpoints)
    start = State(position=sc.setpoints[0][1])
    trajectory = sim.run(start, sc.t_final, controller=controller, faults=sc.faults, record_every=record_every)
    return ScenarioRun(sc, law, trajectory)


# -- report (rotorfault ftc-report) --------------------------------------------------------------


def plot_primary_axis(runs: list[ScenarioRun], path: str | None = None, tail_s: float = 10.0) -> Any:
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
        ax.set_title(f"{run.scenario.name} ({run.law})\n{m.outcome}{steady}", fontsize=8)
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
                "health": " ".join(f"{h:g}" for h in run.scenario.health),
                "ke_stabilizable": run.scenario.ke_stabilizable,
                "outcome": m.outcome,
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


def write_report(runs: list[ScenarioRun], out_dir: str | Path, figures: bool = True) -> Path:
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
            f"| {r['scenario']} | {r['law']} | {'yes' if r['ke_stabilizable'] else 'no'} | {r['outcome']} "
            f"| {r['end_s']:.1f} | {number(r['r_rad_s'], 1)} | {number(r['n3z'], 3)} | {r['rotation_axis']} "
            f"| {number(r['spin_settle_s'], 1)} | {r['max_altitude_loss_m']:.2f} | {r['max_horizontal_error_m']:.2f} "
            f"| {r['final_horizontal_error_m']:.2f} | {r['final_altitude_error_m']:.2f} |"
        )
    lines += ["", "Stability checks of Section III-D (Table II health matrices, k_rotor = 2):", ""]
    lines += ["| health | eig(N) | Re eig(I + k N) > 0 (25) | Re eig(N) > 0 (32) |", "|---|---|---|---|"]
    frame = Airframe.preset("ke-quadcopter")
    for health in TABLE_II_HEALTH:
        check = stability_check(frame, health)
        eig = ", ".join(f"{v.real:.4f}" for v in check.eigenvalues)
        lines.append(f"| diag({', '.join(f'{h:g}' for h in health)}) | {eig} | {check.thrust_feedback} | {check.full_compensation} |")
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


#: The health matrices of Ke Table II.
TABLE_II_HEALTH = (
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
    "TABLE_II_HEALTH",
    "plot_primary_axis",
    "report_rows",
    "write_report",
    "FlightMetrics",
    "FtcPreset",
    "KeGains",
    "Scenario",
    "ScenarioRun",
    "StabilityCheck",
    "flight_metrics",
    "n_eigenvalues",
    "n_matrix",
    "preset",
    "presets",
    "run_scenario",
    "scenario",
    "scenarios",
    "stability_check",
]
