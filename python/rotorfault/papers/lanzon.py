"""Lanzon, Freddi and Longhi (JGCD 2014), reproduced: the paper's two 60 s flights (Scenario A,
Table 2, inner loop only; Scenario B, Table 3, inner and outer loop to the setpoint) flown three
ways, the Monte Carlo robustness study, and the report behind ``rotorfault lanzon-report``. The
controller and its design are in :mod:`rotorfault.control.lanzon`.

The three ways (:func:`design_cases`):

- ``a``: the paper's design (about 100 rad/s crossover) on the model **without** actuator limits
  (the model the design assumes; thrusts may go negative);
- ``b``: the same design **with** the paper's own limits (thrust in [0, 5] N, 50 N/s);
- ``c``: our design for the limits: 30 rad/s crossover, the same loop shape otherwise.

Each is flown with Table 1's printed ``I_zz = 1.16e-3`` and with the probable ``1.16e-2``
(:data:`IZZ_VALUES`): the gyroscopic moment of the rotors and the sign of ``I_xx - I_zz`` change
what works.
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._util.convert import FloatArray, count, real
from .._util.tables import Column, Records, Tabular
from .._typing import FlightVerdict
from ..control.ke import UniformPassiveFtc
from ..control.lanzon import LanzonController, LanzonDesign, LanzonVehicle, OuterLoopGains, design
from ..flight import Noise, RotorFault, Sensing, State, Trajectory, simulate_batch
from ..plotting.paths import plot_lanzon_paths as plot_paths
from ..plotting.timeseries import plot_lanzon_flight as plot_flight
from ..plotting.verdicts import plot_verdict_sweep
from ..studies.engine import run_chunks
from ..studies.storage import pyarrow_module
from ..flight.outcomes import HOLD_BAND_M, HOLD_SPEED_M_S, WINDOW_S, FlightMetrics, flight_metrics, outcome_text, scoring_window, verdict_of
from ..flight.outcomes import OUTCOME_LABELS as OUTCOME_TEXT  # noqa: F401  (the one table of outcome words)
from ..flight.scenarios import FlightScenario as KeScenario  # a generic flight scenario (no paper imports another)
from ._report import markdown_lines

if TYPE_CHECKING:
    from ._numbers import PaperClaim
    from ._report import ReportFile, ReportSection, ReportTable
    from matplotlib.figure import Figure

# -- scenarios ----------------------------------------------------------------------------------

#: Table 1's printed yaw inertia and the probable intended value (kg m^2): both are flown.
IZZ_PRINTED = 1.16e-3
IZZ_PROBABLE = 1.16e-2
IZZ_VALUES = (IZZ_PRINTED, IZZ_PROBABLE)
#: Scenario B's setpoint (Section IV.B: x = y = 0, z = 1 m up), world NED; the paper's z is the
#: height above the ground (its "recovery base at the origin"), where the simulator's ground is.
SETPOINT_NED = (0.0, 0.0, -1.0)
#: Scenario A's initial height above the ground, m: Table 2 prints no position and Section IV.A
#: holds "an arbitrary constant altitude" (a decision: 10 m, clear of the ground).
SCENARIO_A_HEIGHT_M = 10.0
#: "level" in Scenario A: tilt below this (deg) throughout the judging window.
LEVEL_TILT_DEG = 1.0
#: ... and the spin within this fraction of its set point (m g d / k_r).
LEVEL_SPIN_FRACTION = 0.1


@dataclass(frozen=True)
class LanzonScenario:
    """One of the paper's flights: the initial state in the paper's frame (12-vector (12):
    ``[phi, theta, psi, p, q, r, x, y, z, x', y', z']``, z up) and, for the outer loop, the
    ``position`` setpoint (world NED, m; ``None``: inner loop only)."""

    name: str
    description: str
    paper_state: tuple[float, ...]
    position: tuple[float, float, float] | None
    duration_s: float = 60.0

    def initial_state(self) -> State:
        return State.from_vector(LanzonVehicle.simulator_state(self.paper_state))


def scenarios() -> list[LanzonScenario]:
    """Scenario A (Table 2) and Scenario B (Table 3)."""
    q = math.pi / 4
    return [
        LanzonScenario("A", f"inner loop only from Table 2 (roll -45 deg, pitch 45 deg), {SCENARIO_A_HEIGHT_M:g} m up",
                       (-q, q, q, -0.5, 0.5, 2.7, 0.0, 0.0, SCENARIO_A_HEIGHT_M, 0.0, 0.0, 0.0), None),
        LanzonScenario("B", "inner and outer loop from Table 3 (x = y = z = 5 m) to x = y = 0, z = 1 m",
                       (0.075, 0.025, 0.1, 0.03, 0.02, 2.7, 5.0, 5.0, 5.0, 0.0, 0.0, 0.0), SETPOINT_NED),
    ]


def scenario(name: str) -> LanzonScenario:
    """Scenario ``"A"`` or ``"B"`` of :func:`scenarios`; ``ValueError`` otherwise."""
    for s in scenarios():
        if s.name == name:
            return s
    raise ValueError(f"scenario: unknown {name!r}; available: A, B")


@dataclass(frozen=True)
class DesignCase:
    """One way of flying: the loop shape of :func:`~rotorfault.control.lanzon.design`, whether the
    simulator has the paper's actuator limits, and the outer-loop gains."""

    label: str
    description: str
    crossover_rad_s: float
    limits: bool
    channel_gain: tuple[float, float, float] = (1.0, 1.0, 1.0)
    outer_loop: OuterLoopGains = field(default_factory=OuterLoopGains)

    def __post_init__(self) -> None:
        crossover = real("crossover_rad_s", self.crossover_rad_s)
        if not (math.isfinite(crossover) and crossover > 0):
            raise ValueError(f"crossover_rad_s: must be finite and > 0, got {crossover}")
        gains = np.asarray(self.channel_gain, dtype=np.float64)
        if gains.shape != (3,) or not np.all(np.isfinite(gains)) or np.any(gains <= 0):
            raise ValueError(f"channel_gain: expected 3 finite numbers > 0 (phi, theta, r), got {self.channel_gain}")
        if not isinstance(self.limits, bool):
            raise TypeError(f"limits: expected True or False, got {type(self.limits).__name__}")
        if not isinstance(self.outer_loop, OuterLoopGains):
            raise TypeError(f"outer_loop: expected OuterLoopGains, got {type(self.outer_loop).__name__}")

    def design(self, vehicle: LanzonVehicle) -> LanzonDesign:
        return design(vehicle, crossover_rad_s=self.crossover_rad_s, channel_gain=self.channel_gain)


def design_cases() -> list[DesignCase]:
    """(a) the paper's design without limits, (b) with the paper's limits, (c) ours with them."""
    return [
        DesignCase("a", "paper's design (100 rad/s), no actuator limits", 100.0, False),
        DesignCase("b", "paper's design (100 rad/s), paper's limits", 100.0, True),
        DesignCase("c", "our design (30 rad/s), paper's limits", 30.0, True),
    ]


def design_case(label: str) -> DesignCase:
    """Design case ``"a"``, ``"b"`` or ``"c"`` of :func:`design_cases`; ``ValueError`` otherwise."""
    for c in design_cases():
        if c.label == label:
            return c
    raise ValueError(f"case: unknown {label!r}; available: a, b, c")


# -- metrics ------------------------------------------------------------------------------------

AttitudeOutcome = Literal["level", "not-level"]


@dataclass(frozen=True)
class AttitudeMetrics:
    """What Scenario A asks (roll and pitch to zero, spin to ``m g d / k_r``), judged like Ke's
    flights over the last ``window_s`` seconds: ``"level"`` when the tilt (angle between body and
    world vertical) stays below :data:`LEVEL_TILT_DEG` and the spin within
    :data:`LEVEL_SPIN_FRACTION` of its set point throughout the window, ``"not-level"`` otherwise,
    or the divergence kind (``lost_at_s``). ``level_after_s``: from when the tilt stays below
    :data:`LEVEL_TILT_DEG` to the end (``None``: not level at the end, or lost). Whole-run values:
    ``max_altitude_loss_m`` the largest drop below the start; ``window_*`` the largest tilt and
    the mean spin (paper frame, rad/s) over the window."""

    outcome: str
    level_after_s: float | None
    final_tilt_deg: float | None
    window_tilt_deg: float | None
    window_spin_rad_s: float | None
    max_altitude_loss_m: float | None
    lost_at_s: float | None = None
    window_s: float = WINDOW_S


def tilt_deg(trajectory: Trajectory) -> FloatArray:
    """The angle between the body z axis and the world vertical (deg)."""
    out: FloatArray = np.degrees(np.arccos(np.clip(trajectory.primary_axis[:, 2], -1.0, 1.0)))
    return out


def attitude_metrics(trajectory: Trajectory, spin_setpoint_rad_s: float, *, window_s: float = WINDOW_S) -> AttitudeMetrics:
    """Scores Scenario A's question on ``trajectory`` (see :class:`AttitudeMetrics`)."""
    window_s, t = scoring_window(trajectory, window_s)
    if trajectory.diverged:
        e = trajectory.events[0]
        return AttitudeMetrics(e.kind, None, None, None, None, None, float(e.time_s), window_s)
    tilt = tilt_deg(trajectory)
    spin = -trajectory.omega[:, 2]  # paper frame r (z up)
    last = t >= t[-1] - window_s
    window_tilt = float(np.max(tilt[last]))
    window_spin = float(np.mean(spin[last]))
    level = window_tilt < LEVEL_TILT_DEG and bool(
        np.all(np.abs(spin[last] - spin_setpoint_rad_s) <= LEVEL_SPIN_FRACTION * spin_setpoint_rad_s))
    above = np.nonzero(tilt >= LEVEL_TILT_DEG)[0]
    if above.size == 0:
        level_after: float | None = 0.0
    elif above[-1] + 1 < len(t):
        level_after = float(t[above[-1] + 1])
    else:
        level_after = None
    alt = -trajectory.position[:, 2]
    return AttitudeMetrics("level" if level else "not-level", level_after, float(tilt[-1]), window_tilt, window_spin,
                           float(np.max(alt[0] - alt)), None, window_s)


# -- flights ------------------------------------------------------------------------------------


@dataclass
class LanzonRun:
    """One flight: scenario, design case, vehicle, the design flown and the trajectory, with the
    attitude metrics (both scenarios) and, for Scenario B, Ke's position metrics."""

    scenario: LanzonScenario
    case: DesignCase
    vehicle: LanzonVehicle
    design: LanzonDesign
    trajectory: Trajectory
    attitude: AttitudeMetrics = field(init=False)
    position: FlightMetrics | None = field(init=False)

    def __post_init__(self) -> None:
        self.attitude = attitude_metrics(self.trajectory, self.vehicle.spin_rate_rad_s)
        self.position = None if self.scenario.position is None else flight_metrics(
            self.trajectory, _as_ke_scenario(self.scenario))

    @property
    def outcome(self) -> str:
        """Scenario A: the attitude outcome; B: the position outcome (Ke's verdicts)."""
        return self.attitude.outcome if self.position is None else self.position.outcome

    @property
    def lost_at_s(self) -> float | None:
        return self.attitude.lost_at_s

    @property
    def final_error_m(self) -> float | None:
        """Scenario B: distance from the setpoint at the end (``None``: A, or lost)."""
        if self.scenario.position is None or self.trajectory.diverged:
            return None
        return float(np.linalg.norm(self.trajectory.position[-1] - np.asarray(self.scenario.position)))

    @property
    def title(self) -> str:
        return (f"Lanzon scenario {self.scenario.name}, case ({self.case.label}) {self.case.description}, "
                f"I_zz = {self.vehicle.inertia_zz_kg_m2:g} kg m^2, gamma = {self.design.gamma:.3f}")

    def plot(self, path: str | None = None) -> Figure:
        """Lanzon Figs. 6-9 style: roll and pitch, spin, position (paper frame, z up) and rotor
        thrusts against time. Saved to ``path`` if given."""
        return plot_flight(self, path)


def _as_ke_scenario(s: LanzonScenario) -> KeScenario:
    assert s.position is not None
    return KeScenario(f"lanzon-{s.name}", s.description, (1.0, 0.0, 1.0, 1.0), (), s.duration_s, ((0.0, s.position),))


def fly(
    scenario_: LanzonScenario | str,
    case: DesignCase | str,
    *,
    vehicle: LanzonVehicle | None = None,
    duration_s: float | None = None,
    record_every: int = 10,
    designed: LanzonDesign | None = None,
    sensing: Sensing | None = None,
) -> LanzonRun:
    """Flies one scenario with one design case on ``vehicle`` (default: Table 1 with the printed
    ``I_zz``), rotor 2 dead from the start. ``designed`` reuses a design of that case. The
    controller flies on the truth, or on ``sensing`` (sensors and the estimator)."""
    sc = scenario(scenario_) if isinstance(scenario_, str) else scenario_
    cs = design_case(case) if isinstance(case, str) else case
    if not isinstance(sc, LanzonScenario):
        raise TypeError(f"scenario: expected a LanzonScenario or 'A'/'B', got {type(scenario_).__name__}")
    if not isinstance(cs, DesignCase):
        raise TypeError(f"case: expected a DesignCase or 'a'/'b'/'c', got {type(case).__name__}")
    v = LanzonVehicle() if vehicle is None else vehicle
    d = cs.design(v) if designed is None else designed
    controller = LanzonController(d, position=sc.position, outer_loop=cs.outer_loop)
    duration = sc.duration_s if duration_s is None else real("duration_s", duration_s)
    sim = v.simulator(limits=cs.limits, sensing=sensing)
    trajectory = sim.run(sc.initial_state(), duration, controller=controller, faults=[RotorFault(2, 0.0)],
                         record_every=record_every)
    return LanzonRun(replace(sc, duration_s=duration), cs, v, d, trajectory)


def three_way(
    *, izz_values: tuple[float, ...] = IZZ_VALUES, duration_s: float | None = None, record_every: int = 10,
    cases: list[DesignCase] | None = None,
) -> list[LanzonRun]:
    """Both scenarios, each design case, each ``I_zz``: the runs of the three-way table. The 12
    flights go to two threads (the core releases the GIL)."""
    jobs = []
    for izz in izz_values:
        v = LanzonVehicle(inertia_zz_kg_m2=real("izz", izz))
        made: dict[tuple[float, tuple[float, float, float]], LanzonDesign] = {}  # (a) and (b) fly one design
        for cs in cases if cases is not None else design_cases():
            key = (cs.crossover_rad_s, cs.channel_gain)
            d = made[key] = made[key] if key in made else cs.design(v)
            for sc in scenarios():
                jobs.append((sc, cs, v, d))
    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        return list(pool.map(lambda j: fly(j[0], j[1], vehicle=j[2], designed=j[3], duration_s=duration_s,
                                           record_every=record_every), jobs))


# -- verdicts and the paper's claims ---------------------------------------------------------------

#: The one verdict of a whole flight (issue 28: holds / drifts / circles / crashed / diverged)
#: from the outcome codes: Scenario B's are Ke's windowed verdicts (``holds-position`` within 2 m
#: horizontally, 1 m vertically and below 0.5 m/s over the last 5 s; ``circling`` moving above
#: 0.5 m/s and turning; ``off-station`` neither), Scenario A's the attitude verdict (``level``:
#: tilt below 1 deg and spin within 10 % of m g d / k_r over the last 5 s); ``crashed`` is ground
#: contact; every other loss (tilt, speed, ...) is ``diverged``.
#: Scenario A's own question (level and spinning): its two attitude outcomes as verdicts; every
#: other outcome is a flight's, judged by ``flight.outcomes.verdict_of`` (the one table).
_VERDICT_OF_ATTITUDE: dict[str, FlightVerdict] = {"level": "holds", "not-level": "drifts"}


def flight_verdict(run: LanzonRun) -> FlightVerdict:
    """The whole flight's verdict (``holds``, ``drifts``, ``circles``, ``crashed``,
    ``diverged``): Scenario A's ``level`` holds and ``not-level`` drifts; a position outcome or
    a divergence kind by :func:`~rotorfault.flight.outcomes.verdict_of`."""
    return _VERDICT_OF_ATTITUDE.get(run.outcome) or verdict_of(run.outcome)


def _measurement(run: LanzonRun) -> str:
    """What the flight did, in numbers (the evidence of its verdict)."""
    e = run.trajectory.events[0] if run.trajectory.diverged else None
    if e is not None:
        speed = float(np.linalg.norm(run.trajectory.velocity[-1])) if len(run.trajectory.t) else math.nan
        where = "hit the ground" if e.kind == "crashed" else f"lost ({e.kind})"
        return f"{where} at {float(e.time_s):.2f} s ({speed:.1f} m/s)"
    a, p = run.attitude, run.position
    if p is None:
        return (f"over the last {a.window_s:g} s: tilt <= {a.window_tilt_deg:.2f} deg, mean spin {a.window_spin_rad_s:.2f} rad/s "
                f"(set point {run.vehicle.spin_rate_rad_s:.2f}); altitude lost {a.max_altitude_loss_m:.1f} m")
    return (f"over the last {p.window_s:g} s: horizontal error <= {p.window_horizontal_error_m:.2f} m, altitude error <= "
            f"{p.window_altitude_error_m:.2f} m, speed <= {p.window_speed_m_s:.2f} m/s; {run.final_error_m:.3f} m off at the end")


_REASONS = {
    "holds": "the whole-flight verdict is holds: the claim is met in our model",
    "circles": "still circling the set point at the end (moving above {speed:g} m/s and turning): not a hover",
    "drifts": "flies to the end but outside the hold band (or, in A, not level)",
    "crashed": "ground contact ends the run: a crash is never a success",
    "diverged": "lost in flight before the end",
}


@dataclass(frozen=True)
class LanzonClaim:
    """A claim the paper makes about a flight beside what we measure: ``claim`` (``where`` in
    the paper), the flight we flew (``design``, ``inertia_zz_kg_m2``, ``rotor_inertia_kg_m2``,
    ``duration_s``), ``measurement``, the whole-flight ``verdict``, ``status`` (``confirmed``
    only when the verdict is ``holds``) and ``reason``. The fields ``paper, where, claim,
    measurement, verdict, status, reason`` are those of the scoreboard's claim rows."""

    paper: str
    where: str
    claim: str
    design: str
    inertia_zz_kg_m2: float
    rotor_inertia_kg_m2: float
    duration_s: float
    measurement: str
    verdict: str
    status: str
    reason: str


#: The paper's two flight claims (Section IV), each for the paper's design with its limits.
CLAIMS = {
    "A": ("Section IV.A, Figs. 6-7", "inner loop only, limits [0, 5] N and 50 N/s: roll and pitch reach 0 and the spin "
          "m g d / k_r ('the states reach their desired values at steady state')"),
    "B": ("Section IV.B, Figs. 8-10", "inner and outer loop, the same limits: from (5, 5, 5) m to hover at x = y = 0, z = 1 m"),
}


def flight_claims(runs: list[LanzonRun]) -> list[LanzonClaim]:
    """The paper's claims (:data:`CLAIMS`) scored on ``runs``: one per run of the paper's design
    with its limits (case ``b``), each scenario and ``I_zz``."""
    out = []
    for run in runs:
        if run.case.label != "b":
            continue
        where, claim = CLAIMS[run.scenario.name]
        verdict = flight_verdict(run)
        out.append(LanzonClaim(
            "Lanzon et al. (JGCD 2014)", where, claim, f"({run.case.label}) {run.case.description}", run.vehicle.inertia_zz_kg_m2,
            run.vehicle.rotor_inertia_kg_m2, run.scenario.duration_s, _measurement(run), verdict,
            "confirmed" if verdict == "holds" else "not confirmed", _REASONS[verdict].format(speed=HOLD_SPEED_M_S)))
    return out


def paper_claim(claim: LanzonClaim) -> PaperClaim:
    """The scoreboard's claim row of ``claim``: the flight flown (design, I_zz, I_R, duration)
    named in the claim's text."""
    from ._numbers import PaperClaim

    flown = (f" [flown: {claim.design}, I_zz {claim.inertia_zz_kg_m2:g} kg m^2, I_R {claim.rotor_inertia_kg_m2:g} kg m^2, "
             f"{claim.duration_s:g} s]")
    return PaperClaim(claim.paper, claim.where, claim.claim + flown, claim.measurement, claim.verdict,  # type: ignore[arg-type]
                      claim.status, claim.reason)  # type: ignore[arg-type]


def claims_table(claims: list[LanzonClaim]) -> list[str]:
    """The claims as Markdown lines (claim, flight, measurement, verdict, status, reason)."""
    return markdown_lines(
        ("where", "claim", "flight", "measurement", "verdict", "status", "reason"),
        [(c.where, c.claim, f"{c.design}, I_zz = {c.inertia_zz_kg_m2:g}, I_R = {c.rotor_inertia_kg_m2:g}, {c.duration_s:g} s",
          c.measurement, c.verdict, c.status, c.reason) for c in claims],
    )


# -- the rotor inertia the paper does not print -----------------------------------------------------

#: Rotor inertias of the sweep (kg m^2): the paper prints none; ours is 3e-5.
ROTOR_INERTIAS_FULL = (0.0, 5e-6, 1e-5, 1.5e-5, 2e-5, 3e-5, 5e-5, 7e-5, 1e-4)
ROTOR_INERTIAS_QUICK = (0.0, 1e-5, 2e-5, 3e-5, 5e-5, 1e-4)


@dataclass(frozen=True)
class SweepPoint:
    """One flight of the rotor-inertia sweep (Scenario B) and its verdict."""

    inertia_zz_kg_m2: float
    case: str
    rotor_inertia_kg_m2: float
    verdict: str
    measurement: str


def rotor_inertia_sweep(
    rotor_inertias: tuple[float, ...] = ROTOR_INERTIAS_FULL, *, izz_values: tuple[float, ...] = IZZ_VALUES,
    cases: tuple[str, ...] = ("b", "c"), duration_s: float | None = None,
    designs: dict[tuple[float, str], LanzonDesign] | None = None,
) -> list[SweepPoint]:
    """Scenario B flown with each design case at each ``I_zz`` and rotor inertia ``I_R`` (the
    design does not depend on ``I_R``: the RFL model (24) has no gyroscopic term, so one design
    per ``I_zz`` and case is flown on every ``I_R``; ``designs`` may hold them already, keyed by
    ``(I_zz, case)``). Two threads (the core releases the GIL)."""
    jobs = []
    for izz in izz_values:
        base = LanzonVehicle(inertia_zz_kg_m2=real("izz", izz))
        for label in cases:
            cs = design_case(label)
            known = None if designs is None else designs.get((base.inertia_zz_kg_m2, label))
            d = cs.design(base) if known is None else known
            for ir in rotor_inertias:
                ir = real("rotor_inertia_kg_m2", ir)
                jobs.append((cs, base.replace(rotor_inertia_kg_m2=ir), d))
    sc = scenario("B")
    with ThreadPoolExecutor(max_workers=min(2, os.cpu_count() or 1)) as pool:
        runs = list(pool.map(lambda j: fly(sc, j[0], vehicle=j[1], designed=j[2], duration_s=duration_s, record_every=20), jobs))
    return [SweepPoint(r.vehicle.inertia_zz_kg_m2, r.case.label, r.vehicle.rotor_inertia_kg_m2, flight_verdict(r), _measurement(r))
            for r in runs]


def verdict_changes(points: list[SweepPoint]) -> list[str]:
    """Where the verdict changes along ``I_R``, one sentence per ``I_zz`` and case."""
    out = []
    keys = list(dict.fromkeys((p.inertia_zz_kg_m2, p.case) for p in points))
    for izz, case in keys:
        row = sorted((p.rotor_inertia_kg_m2, p.verdict) for p in points if (p.inertia_zz_kg_m2, p.case) == (izz, case))
        steps = [f"{a[1]} at I_R = {a[0]:g} -> {b[1]} at {b[0]:g}" for a, b in zip(row, row[1:]) if a[1] != b[1]]
        what = "; ".join(steps) if steps else f"{row[0][1]} at every I_R from {row[0][0]:g} to {row[-1][0]:g}"
        out.append(f"I_zz = {izz:g}, case ({case}): {what}")
    return out


def sweep_table(points: list[SweepPoint]) -> list[str]:
    """The sweep as Markdown lines: one row per ``I_zz`` and case, one column per ``I_R``."""
    return markdown_lines(*_sweep_cells(points))


def _sweep_cells(points: list[SweepPoint]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    irs = sorted({p.rotor_inertia_kg_m2 for p in points})
    rows = []
    for izz, case in dict.fromkeys((p.inertia_zz_kg_m2, p.case) for p in points):
        cells = {p.rotor_inertia_kg_m2: p.verdict for p in points if (p.inertia_zz_kg_m2, p.case) == (izz, case)}
        rows.append((f"{izz:g}", f"({case}) {design_case(case).description}", *(cells.get(ir, "-") for ir in irs)))
    return ("I_zz (kg m^2)", "case", *(f"I_R = {ir:g}" for ir in irs)), tuple(rows)


# -- robustness (Monte Carlo) -------------------------------------------------------------------

MonteCarloController = Literal["lanzon", "ke"]


@dataclass(frozen=True)
class MonteCarloResult(Tabular):
    """A Monte Carlo batch: ``runs`` perturbed vehicles (mass, ``I_xx = I_yy``, ``I_zz``,
    ``k_r``, ``I_R`` each scaled by a factor drawn uniformly from ``[1 - spread, 1 + spread]``)
    with sensor noise at ``snr_db``, flown from Scenario B's start to its setpoint for
    ``duration_s``. ``outcomes`` holds Ke's windowed verdict per run, ``final_error_m`` the
    distance from the setpoint at the end (NaN: lost), ``factors`` the draws (runs x 5).
    ``to_arrow()`` / ``to_pandas()``: one row per run (its draws, outcome and final error)."""

    controller: str
    runs: int
    spread: float
    snr_db: float | None
    duration_s: float
    inertia_zz_kg_m2: float
    outcomes: tuple[str, ...]
    final_error_m: FloatArray
    factors: FloatArray

    @property
    def held_fraction(self) -> float:
        """The fraction of runs that reach and hold the setpoint (``holds-position``)."""
        return sum(o == "holds-position" for o in self.outcomes) / self.runs

    @property
    def lost_fraction(self) -> float:
        return sum(o not in ("holds-position", "off-station", "circling") for o in self.outcomes) / self.runs

    @property
    def worst_final_error_m(self) -> float:
        """The largest final distance from the setpoint among the runs not lost (inf: all lost)."""
        finite = self.final_error_m[np.isfinite(self.final_error_m)]
        return float(np.max(finite)) if finite.size else math.inf

    @property
    def median_final_error_m(self) -> float:
        finite = self.final_error_m[np.isfinite(self.final_error_m)]
        return float(np.median(finite)) if finite.size else math.inf

    def _table_columns(self) -> list[Column]:
        draws = ("mass_scale", "inertia_xx_scale", "inertia_zz_scale", "rotational_drag_scale", "rotor_inertia_scale")
        columns: list[Column] = [("run", "int64", np.arange(self.runs, dtype=np.int64))]
        columns += [(name, "float64", self.factors[:, k]) for k, name in enumerate(draws)]
        return columns + [("outcome", "string", list(self.outcomes)), ("final_error_m", "float64", self.final_error_m)]

    def _table_title(self) -> str:
        return f"Monte Carlo: {self.runs} runs of {self.controller}, spread {self.spread:g}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "lanzon-monte-carlo", "controller": self.controller, "spread": self.spread, "snr_db": self.snr_db,
                "duration_s": self.duration_s, "inertia_zz_kg_m2": self.inertia_zz_kg_m2}

    def counts(self) -> dict[str, int]:
        out: dict[str, int] = {}
        for o in self.outcomes:
            out[o] = out.get(o, 0) + 1
        return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def monte_carlo(
    controller: MonteCarloController = "lanzon",
    *,
    runs: int = 1000,
    spread: float = 0.2,
    snr_db: float | None = 15.0,
    duration_s: float = 60.0,
    inertia_zz_kg_m2: float = IZZ_PRINTED,
    case: DesignCase | str = "c",
    seed: int = 0,
    progress: bool | None = None,
) -> MonteCarloResult:
    """Robustness of ``controller`` with rotor 2 dead: ``"lanzon"`` (design ``case``, designed
    once on the nominal vehicle) or ``"ke"`` (Ke's :class:`~rotorfault.UniformPassiveFtc`,
    ``ke-hil`` gains, on the same vehicle with the same limits). Each run's vehicle differs, so
    each goes to :func:`~rotorfault.simulate_batch` with its own simulator; the runs go through
    the study engine (:func:`rotorfault.studies.engine.run_chunks`, the local backend: two chunks
    at a time on threads, the core releases the GIL); run ``i`` uses noise seed ``seed + i``."""
    if controller not in ("lanzon", "ke"):
        raise ValueError(f"controller: expected 'lanzon' or 'ke', got {controller!r}")
    n = count("runs", runs)
    if n < 1:
        raise ValueError(f"runs: must be >= 1, got {n}")
    spread = real("spread", spread)
    if not 0 <= spread < 1:
        raise ValueError(f"spread: must lie in [0, 1), got {spread}")
    nominal = LanzonVehicle(inertia_zz_kg_m2=real("inertia_zz_kg_m2", inertia_zz_kg_m2))
    cs = design_case(case) if isinstance(case, str) else case
    if not isinstance(cs, DesignCase):
        raise TypeError(f"case: expected a DesignCase or 'a'/'b'/'c', got {type(case).__name__}")
    seed = count("seed", seed)
    duration = real("duration_s", duration_s)
    # The draws: one generator for the whole batch, row i for run i (as since the study was
    # written; the campaigns' per-run generators would draw other numbers).
    factors = np.random.default_rng(seed).uniform(1 - spread, 1 + spread, size=(n, 5))
    task = _MonteCarloTask(controller, nominal, cs, cs.design(nominal) if controller == "lanzon" else None, factors, snr_db,
                           seed, duration)
    # Two runs at a time (the core releases the GIL): two chunks in flight, each at most half the runs.
    chunk_rows = max(1, min(max(8, n // 50), -(-n // 2)))
    result = run_chunks(
        task, total_rows=n, chunk_rows=chunk_rows, schema=_monte_carlo_schema(), kind="lanzon-monte-carlo",
        arguments={"controller": controller, "runs": n, "spread": spread, "snr_db": None if snr_db is None else real("snr_db", snr_db),
                   "duration_s": duration,
                   "inertia_zz_kg_m2": float(inertia_zz_kg_m2), "case": cs.label, "seed": seed},
        progress=progress, description=f"{n:,} {controller} runs",
    )
    assert result.table is not None  # gathered in memory (no ``out``)
    columns = result.table.to_pydict()
    return MonteCarloResult(controller, n, spread, snr_db, duration, float(inertia_zz_kg_m2),
                            tuple(columns["outcome"]), np.array(columns["final_error_m"], dtype=np.float64), factors)


def _monte_carlo_schema() -> Any:
    """The rows of one Monte Carlo chunk: the run, Ke's windowed verdict code, the final distance
    from the setpoint (m; NaN: lost)."""
    pa = pyarrow_module()

    return pa.schema([pa.field("run", pa.int64()), pa.field("outcome", pa.string()), pa.field("final_error_m", pa.float64())])


@dataclass(frozen=True)
class _MonteCarloTask:
    """The runs of one chunk of :func:`monte_carlo` (the study engine's task): run ``i`` flies the
    nominal vehicle scaled by ``factors[i]`` (mass, ``I_xx = I_yy``, ``I_zz``, ``k_r``, ``I_R``)
    with noise seed ``seed + i``, rotor 2 dead, from Scenario B's start to its setpoint."""

    controller: str
    nominal: LanzonVehicle
    case: DesignCase
    designed: LanzonDesign | None
    factors: FloatArray
    snr_db: float | None
    seed: int
    duration_s: float

    def __call__(self, spec: Any) -> Any:
        pa = pyarrow_module()

        runs = [self.run(i) for i in range(spec.start, spec.stop)]
        return pa.Table.from_arrays(
            [pa.array(range(spec.start, spec.stop), pa.int64()), pa.array([o for o, _ in runs], pa.string()),
             pa.array([e for _, e in runs], pa.float64())], schema=_monte_carlo_schema())

    def run(self, i: int) -> tuple[str, float]:
        """Run ``i``: Ke's windowed verdict code and the final distance from the setpoint (NaN: lost)."""
        sc = scenario("B")
        assert sc.position is not None
        nominal, f = self.nominal, self.factors[i]
        v = nominal.replace(mass_kg=nominal.mass_kg * f[0], inertia_xx_kg_m2=nominal.inertia_xx_kg_m2 * f[1],
                            inertia_zz_kg_m2=nominal.inertia_zz_kg_m2 * f[2],
                            rotational_drag_n_m_s=nominal.rotational_drag_n_m_s * f[3],
                            rotor_inertia_kg_m2=nominal.rotor_inertia_kg_m2 * f[4])
        noise = None if self.snr_db is None else Noise(snr_db=self.snr_db, seed=self.seed + i)
        sim = v.simulator(limits=self.case.limits if self.controller == "lanzon" else True, noise=noise)
        ctrl: Any
        if self.controller == "lanzon":
            assert self.designed is not None
            ctrl = LanzonController(self.designed, position=sc.position, outer_loop=self.case.outer_loop)
        else:
            ctrl = UniformPassiveFtc(sim.airframe, gains="ke-hil", position=sc.position)
        batch = simulate_batch(sim, [sc.initial_state()], self.duration_s, controllers=[ctrl], faults=[[RotorFault(2, 0.0)]],
                               record_every=20)
        tr = batch.trajectories[0]
        m = flight_metrics(tr, replace(_as_ke_scenario(sc), duration_s=self.duration_s))
        err = math.nan if tr.diverged else float(np.linalg.norm(tr.position[-1] - np.asarray(sc.position)))
        return m.outcome, err


# -- report (rotorfault lanzon-report) -----------------------------------------------------------


#: The columns of :func:`report_rows` and their types.
REPORT_COLUMNS: tuple[tuple[str, str], ...] = (
    ("scenario", "string"), ("case", "string"), ("case_description", "string"), ("inertia_zz_kg_m2", "float64"),
    ("crossover_rad_s", "float64"), ("limits", "bool"), ("gamma_min", "float64"), ("gamma", "float64"),
    ("achieved_norm", "float64"), ("verdict", "string"), ("outcome", "string"), ("outcome_text", "string"),
    ("lost_at_s", "float64"), ("duration_s", "float64"),
    ("level_after_s", "float64"), ("window_tilt_deg", "float64"), ("window_spin_rad_s", "float64"),
    ("max_altitude_loss_m", "float64"), ("final_error_m", "float64"), ("window_horizontal_error_m", "float64"),
    ("window_altitude_error_m", "float64"), ("min_thrust_n", "float64"), ("max_thrust_n", "float64"),
)


def report_rows(runs: list[LanzonRun]) -> Records:
    """One record per run of the three-way table (:data:`REPORT_COLUMNS`; a sequence of dicts with
    ``to_arrow()`` and ``to_pandas()``)."""
    rows = []
    for run in runs:
        a, p = run.attitude, run.position
        rows.append({
            "scenario": run.scenario.name,
            "case": run.case.label,
            "case_description": run.case.description,
            "inertia_zz_kg_m2": run.vehicle.inertia_zz_kg_m2,
            "crossover_rad_s": run.case.crossover_rad_s,
            "limits": run.case.limits,
            "gamma_min": run.design.gamma_min,
            "gamma": run.design.gamma,
            "achieved_norm": run.design.evidence.achieved_norm,
            "verdict": flight_verdict(run),
            "outcome": run.outcome,
            "outcome_text": outcome_text(run.outcome, run.lost_at_s),
            "lost_at_s": run.lost_at_s,
            "duration_s": run.scenario.duration_s,
            "level_after_s": a.level_after_s,
            "window_tilt_deg": a.window_tilt_deg,
            "window_spin_rad_s": a.window_spin_rad_s,
            "max_altitude_loss_m": a.max_altitude_loss_m,
            "final_error_m": run.final_error_m,
            "window_horizontal_error_m": None if p is None else p.window_horizontal_error_m,
            "window_altitude_error_m": None if p is None else p.window_altitude_error_m,
            "min_thrust_n": float(np.nanmin(run.trajectory.rotor_thrust[:, [0, 2, 3]])),
            "max_thrust_n": float(np.nanmax(run.trajectory.rotor_thrust)),
        })
    return Records(rows, REPORT_COLUMNS, title="Lanzon et al.: three-way flights", kind="lanzon-flights")


def _num(value: Any, digits: int) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if not math.isfinite(value):
            return str(value)
        return f"{round(value, digits) + 0.0:.{digits}f}"
    return str(value)


def three_way_table(runs: list[LanzonRun]) -> list[str]:
    """The three-way table as Markdown lines: one row per ``I_zz`` and case, scenarios A and B side
    by side (A: outcome, tilt below 1 deg after, altitude lost; B: outcome, final error)."""
    return markdown_lines(*_three_way_cells(runs))


def _three_way_cells(runs: list[LanzonRun]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    by_key: dict[tuple[float, str], dict[str, LanzonRun]] = {}
    for run in runs:
        by_key.setdefault((run.vehicle.inertia_zz_kg_m2, run.case.label), {})[run.scenario.name] = run
    columns = ("I_zz (kg m^2)", "case", "gamma", "A: outcome", "A: tilt < 1 deg after (s)", "A: altitude lost (m)",
               "B: outcome", "B: final error (m)", "B: altitude lost (m)")
    rows = []
    for (izz, label), pair in by_key.items():
        a, b = pair.get("A"), pair.get("B")
        any_run = a or b
        assert any_run is not None
        cells = [f"{izz:g}", f"({label}) {any_run.case.description}", f"{any_run.design.gamma:.3f}"]
        if a is not None:
            cells += [outcome_text(a.outcome, a.lost_at_s), _num(a.attitude.level_after_s, 1),
                      _num(a.attitude.max_altitude_loss_m, 1)]
        else:
            cells += ["-", "-", "-"]
        if b is not None:
            cells += [outcome_text(b.outcome, b.lost_at_s), _num(b.final_error_m, 3), _num(b.attitude.max_altitude_loss_m, 1)]
        else:
            cells += ["-", "-", "-"]
        rows.append(tuple(cells))
    return columns, tuple(rows)


def monte_carlo_table(results: list[MonteCarloResult]) -> list[str]:
    """The robustness comparison as Markdown lines."""
    return markdown_lines(*_monte_carlo_cells(results))


def _monte_carlo_cells(results: list[MonteCarloResult]) -> tuple[tuple[str, ...], tuple[tuple[str, ...], ...]]:
    names = {"lanzon": "Lanzon RFL + H-infinity, design (c)", "ke": "Ke uniform passive FTC (ke-hil)"}
    rows = []
    for r in results:
        outcomes = ", ".join(f"{outcome_text(k)} {v}" for k, v in r.counts().items())
        rows.append((names.get(r.controller, r.controller), str(r.runs), f"{r.inertia_zz_kg_m2:g}", f"{100 * r.held_fraction:.1f} %",
                     f"{100 * r.lost_fraction:.1f} %", _num(r.median_final_error_m, 3), _num(r.worst_final_error_m, 3), outcomes))
    return ("controller", "runs", "I_zz (kg m^2)", "holds position", "lost", "median final error (m)", "worst final error (m)",
            "outcomes"), tuple(rows)


def write_report(
    runs: list[LanzonRun],
    out_dir: str | Path,
    *,
    monte_carlo_results: list[MonteCarloResult] | None = None,
    figures: bool = True,
    force: bool = False,
    command: str | None = None,
) -> Path:
    """Writes the report directory ``out_dir``: ``lanzon-report.md`` (the three-way table and
    the Monte Carlo comparison), ``lanzon-report.csv`` (one row per flight), ``monte-carlo.csv``
    (one row per Monte Carlo run), with ``figures`` one time history per flight
    (``<scenario>-<case>-izz-<value>.png``), the Scenario B paths (``paths-3d.png``) and the loop
    shapes of the paper's and our design (``loop-shape-<case>.png``); and ``manifest.json``.
    Written beside ``out_dir`` and swapped in when complete (the one report writer,
    :func:`rotorfault.papers._report.write_report_files`); an existing report is replaced only
    with ``force``."""
    from ._report import write_report_files

    def content(tmp: Path) -> list[ReportFile]:
        if not runs:
            raise ValueError("runs: nothing to report (fly at least one scenario)")
        if figures:
            _draw_report_figures(runs, tmp)
        return _report_files(runs, monte_carlo_results or [], figures=figures)

    out = write_report_files(
        out_dir, content, field_name="out_dir", force=force,
        generator="rotorfault lanzon-report (rotorfault.papers.lanzon.write_report)", command=command,
        default_command="rotorfault.papers.lanzon.write_report",
    )
    return out / "lanzon-report.md"


def _draw_report_figures(runs: list[LanzonRun], directory: Path) -> None:
    """The figures of ``rotorfault lanzon-report`` (:func:`write_report`) drawn into ``directory``."""
    for run in runs:
        run.plot(str(directory / f"{run.scenario.name}-{run.case.label}-izz-{run.vehicle.inertia_zz_kg_m2:g}.png"))
    b_runs = [run for run in runs if run.scenario.name == "B"]
    if b_runs:
        plot_paths(b_runs, str(directory / "paths-3d.png"))
    seen: set[str] = set()
    for run in runs:
        if run.case.label in ("b", "c") and run.case.label not in seen:
            seen.add(run.case.label)
            fig = run.design.plot_loop_shape(str(directory / f"loop-shape-{run.case.label}.png"))
            del fig


#: The columns of ``monte-carlo.csv``: one row per Monte Carlo run, its five factors, verdict and error.
MONTE_CARLO_CSV_COLUMNS = ("controller", "run", "mass_factor", "inertia_xx_factor", "inertia_zz_factor", "rotational_drag_factor",
                           "rotor_inertia_factor", "outcome", "final_error_m")


def _report_files(runs: list[LanzonRun], mc: list[MonteCarloResult], *, figures: bool) -> list[ReportFile]:
    """The text files of ``rotorfault lanzon-report``: ``lanzon-report.csv`` (:func:`report_rows`),
    ``lanzon-report.md`` and, with Monte Carlo results, ``monte-carlo.csv``."""
    from ._report import CsvTable, MarkdownText

    lines = [
        "# Flying a quadrotor on three rotors (Lanzon et al.): report",
        "",
        "Rotor 2 dead from the start. Scenario A (Table 2): inner loop only, from roll -45 deg, pitch 45 deg;",
        f"'level' keeps the tilt below {LEVEL_TILT_DEG:g} deg and the spin within {100 * LEVEL_SPIN_FRACTION:g} % of "
        f"m g d / k_r over the last {WINDOW_S:g} s.",
        "Scenario B (Table 3): inner and outer loop from (5, 5, 5) m to (0, 0, 1) m (z up); 'holds position'",
        f"keeps within {HOLD_BAND_M[0]:g} m horizontally, {HOLD_BAND_M[1]:g} m vertically and below "
        f"{HOLD_SPEED_M_S:g} m/s over the last {WINDOW_S:g} s (Ke's verdicts).",
        "Cases: (a) the paper's design (100 rad/s crossover) without actuator limits, (b) the same with the",
        "paper's limits (thrust in [0, 5] N, 50 N/s), (c) our 30 rad/s design with the limits. I_zz: Table 1's",
        f"printed {IZZ_PRINTED:g} and the probable {IZZ_PROBABLE:g} kg m^2.",
        "",
        *three_way_table(runs),
    ]
    claims = flight_claims(runs)
    if claims:
        lines += ["", "The paper's flight claims (the paper's design with its limits), each with the whole flight's verdict:", "",
                  *claims_table(claims)]
    if mc:
        r0 = mc[0]
        lines += [
            "",
            f"Robustness: {r0.runs} runs per controller, mass, I_xx = I_yy, I_zz, k_r and I_R each scaled by a",
            f"factor uniform in [{1 - r0.spread:g}, {1 + r0.spread:g}], sensor noise "
            f"{'none' if r0.snr_db is None else f'{r0.snr_db:g} dB SNR'}, Scenario B's start and setpoint, "
            f"{r0.duration_s:g} s, the paper's limits.",
            "",
            *monte_carlo_table(mc),
        ]
    if figures:
        lines += ["", "Figures: `<scenario>-<case>-izz-<I_zz>.png` (one per flight), `paths-3d.png`, "
                  "`loop-shape-b.png` (the paper's design), `loop-shape-c.png` (ours)."]
    files: list[ReportFile] = [CsvTable.from_records("lanzon-report.csv", report_rows(runs)), MarkdownText("lanzon-report.md", tuple(lines))]
    if mc:
        files.append(CsvTable("monte-carlo.csv", MONTE_CARLO_CSV_COLUMNS, tuple(
            (result.controller, i, *(f"{x:.6f}" for x in result.factors[i]), result.outcomes[i],
             f"{float(result.final_error_m[i]):.6f}" if math.isfinite(float(result.final_error_m[i])) else "")
            for result in mc for i in range(result.runs))))
    return files


__all__ = [
    "CLAIMS",
    "ROTOR_INERTIAS_FULL",
    "ROTOR_INERTIAS_QUICK",
    "LanzonClaim",
    "SweepPoint",
    "claims_table",
    "paper_claim",
    "flight_claims",
    "flight_verdict",
    "rotor_inertia_sweep",
    "sweep_table",
    "verdict_changes",
    "report_section",
    "IZZ_PRINTED",
    "IZZ_PROBABLE",
    "IZZ_VALUES",
    "LEVEL_SPIN_FRACTION",
    "LEVEL_TILT_DEG",
    "SETPOINT_NED",
    "AttitudeMetrics",
    "DesignCase",
    "LanzonRun",
    "LanzonScenario",
    "MonteCarloResult",
    "attitude_metrics",
    "design_case",
    "design_cases",
    "fly",
    "monte_carlo",
    "monte_carlo_table",
    "outcome_text",
    "plot_flight",
    "plot_paths",
    "report_rows",
    "scenario",
    "scenarios",
    "three_way",
    "three_way_table",
    "tilt_deg",
    "write_report",
]


#: The mocap suite with the IMU at Lanzon's 1 kHz loop rate (an ICM-42688-P output data rate;
#: at 500 Hz, under the 1 kHz loop, Scenario A with design (a) is lost by tilt).
MOCAP_AT_LOOP_RATE = Sensing(imu_rate_hz=1000.0)


def sensing_table(truth: list[LanzonRun], sensed: list[LanzonRun]) -> ReportTable:
    """The flights of ``sensed`` beside the same scenario, case and vehicle in ``truth``: outcome
    and final error on each."""
    from ._report import ReportTable

    def key(r: LanzonRun) -> tuple[str, str, float]:
        return (r.scenario.name, r.case.label, r.vehicle.inertia_zz_kg_m2)

    by_key = {key(r): r for r in truth}
    rows = []
    for b in sensed:
        a = by_key[key(b)]
        rows.append((b.scenario.name, b.case.label, f"{b.vehicle.inertia_zz_kg_m2:g}", a.outcome, b.outcome,
                     "same" if a.outcome == b.outcome else "differs", _num(a.final_error_m, 3), _num(b.final_error_m, 3)))
    return ReportTable(
        f"With sensors: the same flights on the truth and on {sensed[0].trajectory.sensed if sensed else 'sensors'} "
        "(rotorfault.Sensing, the IMU at the 1 kHz loop rate; the error-state Kalman filter), side by side",
        ("scenario", "case", "I_zz (kg m^2)", "truth: outcome", "sensors: outcome", "verdict",
         "final error truth (m)", "final error sensors (m)"),
        tuple(rows),
    )


def report_section(out: Path, *, quick: bool = False) -> ReportSection:
    """Lanzon's flights for ``rotorfault reproduce``: the three-way table (the paper's design
    without and with its limits, ours with them; both ``I_zz`` values) from :func:`three_way`, the
    3-D paths and the flight figures of Scenario B, and, in the full mode, a 200-run Monte Carlo
    of design (c) beside Ke's controller (``rotorfault lanzon-report`` runs 1,000); the paper's
    flight claims scored (:func:`flight_claims`), the 3-D paths of each scenario in its own figure
    and Scenario B's verdict against the rotor inertia (:func:`rotor_inertia_sweep`). Every flight
    is the paper's 60 s; ``--quick`` skips the Monte Carlo and sweeps 6 rotor inertias instead of 9."""
    import time

    from ._report import ReportFigure, ReportSection, ReportTable

    start = time.perf_counter()
    section = ReportSection("lanzon-flights", "Lanzon's flights (Scenarios A and B, Figs. 6-10)",
                            source="rotorfault.papers.lanzon (rotorfault lanzon-report)")
    # The paper's 60 s flights in both modes: a verdict is the whole flight's (a 20 s flight of the
    # paper's design still circles where the 60 s one holds), and they cost about 2.5 s in all.
    runs = three_way()
    columns, rows = _three_way_cells(runs)
    section.tables.append(ReportTable(
        "Three ways, rotor 2 dead (60 s flights)"
        + ": (a) the paper's 100 rad/s design without actuator limits, (b) the same design with the paper's "
        "[0, 5] N and 50 N/s, (c) our 30 rad/s design with those limits; for the printed I_zz and for the likely "
        "misprint 1.16e-2", columns, rows))
    section.tables.append(sensing_table(
        runs, [fly(r.scenario, r.case, vehicle=r.vehicle, designed=r.design, duration_s=r.scenario.duration_s,
                   sensing=MOCAP_AT_LOOP_RATE) for r in runs if r.vehicle.inertia_zz_kg_m2 == IZZ_VALUES[0]]))
    # The paper's flight claims on the scoreboard (a claim is confirmed only when the whole-flight
    # verdict is holds: B within 2 m horizontally, 1 m vertically and below 0.5 m/s over the last
    # 5 s, A tilt below 1 deg and spin within 10 % over the last 5 s; ground contact is crashed).
    section.claims = [paper_claim(c) for c in flight_claims(runs)]
    for name in ("A", "B"):
        mine = [run for run in runs if run.scenario.name == name]
        plot_paths(mine, str(out / f"lanzon-paths-{name}.png"))
        section.figures.append(ReportFigure(f"lanzon-paths-{name}.png", f"3-D paths of Scenario {name}'s runs (Lanzon Fig. 8 style)."))
    # 60 s flights in both modes (a 20 s flight still circling is not the verdict of the paper's
    # 60 s flight; most runs at large I_R are lost within seconds): --quick takes fewer I_R.
    points = rotor_inertia_sweep(ROTOR_INERTIAS_QUICK if quick else ROTOR_INERTIAS_FULL,
                                 designs={(r.vehicle.inertia_zz_kg_m2, r.case.label): r.design for r in runs})
    columns, rows = _sweep_cells(points)
    section.tables.append(ReportTable(
        "Scenario B's verdict against the rotor inertia I_R (the paper prints none; ours is 3e-5 kg m^2), both I_zz, "
        "the paper's design (b) and ours (c) with the paper's limits, 60 s flights"
        + (f" (--quick: {len(ROTOR_INERTIAS_QUICK)} values; the full report {len(ROTOR_INERTIAS_FULL)})" if quick else ""),
        columns, rows))
    section.notes += ["Where the verdict changes with I_R: " + s for s in verdict_changes(points)]
    names = {"b": "(b) paper's design, 100 rad/s", "c": "(c) ours, 30 rad/s"}
    plot_verdict_sweep([{"I_zz (kg m^2)": p.inertia_zz_kg_m2, "design": names.get(p.case, p.case), "I_R": p.rotor_inertia_kg_m2,
                         "verdict": p.verdict} for p in points], str(out / "lanzon-rotor-inertia.png"), parameter="I_R",
                       parameter_label="rotor inertia I_R (kg m^2)", series="design", panel="I_zz (kg m^2)",
                       title="Lanzon scenario B, the paper's limits, 60 s: whole-flight verdict against the rotor inertia I_R",
                       mark=(LanzonVehicle().rotor_inertia_kg_m2, "our I_R"))
    section.figures.append(ReportFigure("lanzon-rotor-inertia.png", "Scenario B's verdict against I_R, per I_zz and design."))
    for run in runs:
        if run.scenario.name == "B" and run.vehicle.inertia_zz_kg_m2 == IZZ_VALUES[0]:
            name = f"lanzon-B-{run.case.label}.png"
            run.plot(str(out / name))
            section.figures.append(ReportFigure(name, run.title, small=True))
    if not quick:
        results = [monte_carlo(c, runs=200, duration_s=60.0) for c in ("lanzon", "ke")]
        columns, rows = _monte_carlo_cells(results)
        section.tables.append(ReportTable(
            "Robustness, 200 runs each: mass, inertias, k_r, I_R +-20 %, 15 dB sensor noise, Scenario B", columns, rows))
    else:
        section.notes.append("--quick: no Monte Carlo (rotorfault lanzon-report runs 1,000 runs per controller).")
    section.run_time_s = time.perf_counter() - start
    return section
