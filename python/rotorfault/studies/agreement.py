"""Does ``certify`` agree with flights? (issue 30). For every single and double rotor failure of a
vehicle, certify's verdict (static hover, or by spinning: :func:`rotorfault.studies.certify.certify`
with ``spinning=True``, computed with the vehicle's own rotational damping and rotor lag) beside
short flights of our controllers through that failure, each judged by the one flight verdict
(:mod:`rotorfault.flight.outcomes`: ``holds``, ``drifts``, ``circles``, ``crashed``, ``diverged``
over the last :data:`rotorfault.flight.outcomes.WINDOW_S` seconds, thresholds stated there).

The rule: a case certify calls survivable (it hovers statically, ``hover != "no"``, or the relaxed
hover found a solution a linear feedback can hold that
:func:`rotorfault.analysis.entry_from_hover` does not exclude from hover: the complement of
:meth:`~rotorfault.studies.certify.Certificate.failing_spinning`) must be held by at least one
controller; a case certified not survivable must be held by none. A case agrees when that holds.

How each case is flown (deterministic, nominal vehicle, no wind): from rest at the set point,
the rotors of the case fail completely at :data:`FAILURE_TIME_S`, the flight ends
:data:`AFTER_FAILURE_S` later. A run that holds its place while its spin has not settled by then
(the summary's settle test: yaw rate within 5 % and n3z within 0.02 of their window means over the
whole window) is not yet a steady flight: it is flown again to :data:`SETTLE_AFTER_FAILURE_S` after
the failure and that flight's verdict stands (a quadrotor without two opposing rotors kept upright
spins up towards k_mu m g / k_r, 275 rad/s on Wang's frames, past the simulator's 200 rad/s
body-rate limit 23 s after the failure, while holding its place within micrometres at 10 s).
Every controller is told the failure (which rotors, when), designed
on the vehicle it flies (each builder gets a ``FlightCase``: the vehicle, the failed rotors,
certify's own best relaxed hover of the case, and the healthy vehicle's hover LQR, designed once
per vehicle):

- ``linear-feedback``: the hover LQR (:func:`rotorfault.control.lqr_hover`) of the failed vehicle
  (refused where its ACAI is <= 0: static hover with all four axes lost);
- ``relaxed-hover-feedback``: the healthy vehicle's hover LQR until the failure, then the LQR about
  the best relaxed hover, the one certify found (the failure-time switch of
  :class:`rotorfault.control.RelaxedHoverFeedback`);
  on a vehicle whose healthy hover no LQR holds (``wang-fixed-pitch``: no yaw control even
  healthy) there is no healthy design and the relaxed hover LQR flies from the start;
- ``indi-controller``: INDI told of the failed rotors;
- ``uniform-passive-ftc``: Ke's passive controller with the ``ke-robust`` gains (told nothing);
- ``lanzon-controller``: Lanzon's design, only on the Lanzon quadrotor with rotor 2 failed.

A controller that refuses the design (``design-refused``) or does not apply (``not-applicable``)
has not held the case. A lost flight's cell says when and why it was lost and the largest rotor
command it asked for against the rotors' limit (and how long a rotor was saturated).

Two adjacent rotors lost (measured on ``ke-quadcopter``, rotors 1-2, 1-4, 2-3, 3-4; the failure at
1 s) was the disagreement: a relaxed hover exists (20.06 rad/s on the remaining pair, its up axis
25 degrees off body z) and the relaxed hover LQR holds it when started on the periodic solution,
but no controller captures it from hover: ``relaxed-hover-feedback`` asks for 20.9 N (1-2, 3-4)
or 18.4 N (1-4, 2-3) against the 8.5 N limit and is lost to tilt (past the simulator's 90 degrees)
at 1.15 s, ``uniform-passive-ftc`` at 1.23 s, INDI and the hover LQR refuse the design. The cause
is the geometry, not the gains: the pair sits on one side of the frame, every newton rolls the
vehicle by at least 0.0884 N m while it yaws it by at most 0.0166 N m (9.89 times less in angular
acceleration); in the relaxed hover the roll is balanced by the gyroscopic moment of the
18.19 rad/s spin, which does not exist at hover. Certify now checks that entry
(:func:`rotorfault.analysis.entry_from_hover`: the tilt is at least 126 degrees before the spin is
reached, the spin at most 2.33 rad/s by 90 degrees) and says "spinning solution exists, not
reachable from hover": the four cases are certified not survivable and agree. The condition is
checked independently (``tests/studies/test_agreement.py``): on Ke's quadcopter with rotors that
yaw more than they roll (k_mu 0.08 m, arm 0.06 m, k_r 0.01 N m s) it excludes nothing and the
relaxed hover LQR does enter the spin from hover; certify without it, or with a 180-degree tilt
limit, disagrees again on the four pairs. It is an obstruction, not a promise: where it excludes
nothing the flights decide (the Wang quadrotors without two adjacent rotors, roll/yaw 5.36, and
the hexacopters without two adjacent rotors, whose remaining rotors include an opposite pair that
yaws without tilting one way, are not excluded and not held: the README's table).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from os import PathLike
from typing import Any

import numpy as np

from .. import _rfcore
from ..analysis.airframe import Airframe, rotor_labels
from ..flight import DivergenceLimits, Drag, FixedPitchActuator, RotorFault, Simulator, State
from ..flight.outcomes import verdict_of
from ..flight.scenarios import HOVER_M
from ..flight.simulator import trim_command
from ..analysis.relaxed_hover import RelaxedHoverSolution
from .certify import RelaxedHoverVerdict, certify, describe_relaxed_hover, survives
from .deciding import CampaignVehicle, vehicle

#: When the rotors fail, and how long each flight goes on after that (s); the verdict window is
#: the last :data:`rotorfault.flight.outcomes.WINDOW_S` (5 s) of the flight.
FAILURE_TIME_S = 1.0
AFTER_FAILURE_S = 10.0
#: How long after the failure a run that holds its place with its spin not settled at
#: :data:`AFTER_FAILURE_S` is flown again (s): its verdict is the case's (module notes).
SETTLE_AFTER_FAILURE_S = 60.0
#: Control period and RK4 substeps (the deciding campaign's 400 Hz).
DT_S = 1.0 / 400.0
SUBSTEPS = 2


@dataclass(frozen=True)
class CaseFlight:
    """One controller flown through one case: its ``verdict`` (a flight verdict, or
    ``design-refused`` / ``not-applicable`` with the reason in ``note``) and the largest horizontal
    and altitude errors over the verdict window (m; NaN when not flown or lost)."""

    controller: str
    verdict: str
    note: str = ""
    horizontal_error_m: float = math.nan
    altitude_error_m: float = math.nan

    @property
    def holds(self) -> bool:
        return self.verdict == "holds"


@dataclass(frozen=True)
class AgreementCase:
    """One failure case of one vehicle: certify's static verdict (``hover``) and relaxed hover
    (``spinning``), whether certify calls it survivable, and every controller's flight."""

    vehicle: str
    failed: tuple[int, ...]
    hover: str
    spinning: RelaxedHoverVerdict
    flights: tuple[CaseFlight, ...]

    @property
    def survivable(self) -> bool:
        """Certify's answer (:func:`rotorfault.studies.certify.survives`): static hover with all
        four axes, or a steady relaxed hover a linear feedback can hold that is not excluded from
        hover (:func:`rotorfault.analysis.entry_from_hover`)."""
        return survives(self.hover, self.spinning)

    @property
    def held_by(self) -> tuple[str, ...]:
        return tuple(f.controller for f in self.flights if f.holds)

    @property
    def agrees(self) -> bool:
        return self.survivable == bool(self.held_by)


@dataclass(frozen=True)
class CertifyAgreement:
    """Every case of :func:`certify_against_flights`, in vehicle and certificate order.

    Examples:

        >>> from rotorfault.studies import certify_against_flights
        >>> from rotorfault.studies.agreement import preset_vehicles
        >>> ke = [v for v in preset_vehicles() if v.name == "ke-quadcopter"]
        >>> agreement = certify_against_flights(ke, max_failed=1, controllers=["indi-controller"])
        >>> [(case.failed, case.held_by) for case in agreement.cases][:2]
        [((1,), ('indi-controller',)), ((2,), ('indi-controller',))]
    """

    cases: tuple[AgreementCase, ...]
    controllers: tuple[str, ...]

    def disagreements(self) -> list[AgreementCase]:
        return [c for c in self.cases if not c.agrees]

    def counts(self) -> dict[str, int]:
        """Cases, how many certify calls survivable, how many of those are held, how many not
        survivable are held (must be 0), and how many agree."""
        survivable = [c for c in self.cases if c.survivable]
        refused = [c for c in self.cases if not c.survivable]
        return {"cases": len(self.cases), "survivable": len(survivable), "survivable_held": sum(bool(c.held_by) for c in survivable),
                "not_survivable": len(refused), "not_survivable_held": sum(bool(c.held_by) for c in refused),
                "agree": sum(c.agrees for c in self.cases)}

    def rows(self) -> list[tuple[str, ...]]:
        """One row per case: vehicle, failed rotors, certify's static verdict, its relaxed hover,
        survivable, held by, each controller's verdict (with the window errors), agree."""
        out = []
        for c in self.cases:
            verdicts = {f.controller: f for f in c.flights}
            cells = []
            for name in self.controllers:
                f = verdicts.get(name)
                if f is None:
                    cells.append("-")
                elif math.isfinite(f.horizontal_error_m):
                    cells.append(f"{f.verdict} ({f.horizontal_error_m:.2f} / {f.altitude_error_m:.2f} m)")
                elif f.verdict in ("crashed", "diverged"):
                    cells.append(f"{f.verdict} ({f.note})")  # when, why, and the peak command against the limit
                else:
                    cells.append(f.verdict)
            out.append((c.vehicle, rotor_labels(c.failed), c.hover, describe_relaxed_hover(c.spinning),
                        "yes" if c.survivable else "no", ", ".join(c.held_by) or "none", *cells, "yes" if c.agrees else "NO"))
        return out

    def headers(self) -> tuple[str, ...]:
        return ("vehicle", "failed", "certify: static", "certify: relaxed hover", "survivable", "held by",
                *(f"{n} (horiz / alt error)" for n in self.controllers), "agree")

    def table(self) -> str:
        n = self.counts()
        lines = [
            f"certify against flights: {n['cases']} cases, {n['agree']} agree; certified survivable {n['survivable']} "
            f"(held by a controller: {n['survivable_held']}); not survivable {n['not_survivable']} (held: {n['not_survivable_held']})",
            "| " + " | ".join(self.headers()) + " |",
            "|" + "---|" * len(self.headers()),
        ]
        lines += ["| " + " | ".join(r) + " |" for r in self.rows()]
        return "\n".join(lines)


def px4_vehicle(
    path: str | PathLike[str], *, inertia_kg_m2: Any = None, rotor_time_constant_s: float = 0.0125,
    rotational_drag_n_m_s: float = 2.8e-3, linear_drag_n_s_m: float = 0.3, name: str | None = None,
) -> CampaignVehicle:
    """A vehicle imported from a PX4 parameter file (:meth:`rotorfault.Airframe.from_px4_params`;
    PX4 keeps no inertia, rotor lag or drag: ``inertia_kg_m2`` (kg m^2, default the importer's
    placeholder), the rotor time constant (s; default the Gazebo x500's), rotational damping
    (N m s) and translational drag (N s/m; default the small multirotor's of the ``ke-hil`` preset))."""
    airframe = Airframe.from_px4_params(path, inertia_kg_m2=inertia_kg_m2, name=name)
    return CampaignVehicle(airframe.name, airframe, rotor_time_constant_s, rotational_drag_n_m_s, linear_drag_n_s_m)


def preset_vehicles() -> list[CampaignVehicle]:
    """Every shipped airframe preset flown as the deciding campaign flies its vehicles (the
    ``ke-hil`` preset's rotor lag and drags where a preset has none of its own), and the PX4 x500
    imported from its parameters."""
    names = [*Airframe.presets(), "px4-x500"]
    return [vehicle(n) if n in ("ke-quadcopter", "px4-x500") else _ke_like(n) for n in names]


def _ke_like(name: str) -> CampaignVehicle:
    v = vehicle("ke-quadcopter")
    return CampaignVehicle(name, Airframe.preset(name), v.rotor_time_constant_s, v.rotational_drag_n_m_s, v.linear_drag_n_s_m)


def _drag(v: CampaignVehicle) -> Drag:
    return Drag(rotational_n_m_s=v.rotational_drag_n_m_s, linear_n_s_m=v.linear_drag_n_s_m)


def _actuator(v: CampaignVehicle) -> FixedPitchActuator:
    return FixedPitchActuator(time_constant_s=v.rotor_time_constant_s)


def _simulator(v: CampaignVehicle, airframe: Airframe) -> Simulator:
    return Simulator(airframe, dt_s=DT_S, substeps=SUBSTEPS, drag=_drag(v), actuator=_actuator(v))


@dataclass(frozen=True)
class FlightCase:
    """One failure case as a controller's builder sees it: the ``vehicle``, its ``failed`` rotors
    (1-based), ``relaxed_hover`` (certify's best relaxed hover of the failed vehicle, ``None``
    where none a linear feedback can hold) and ``healthy_lqr`` (the healthy vehicle's hover LQR,
    designed at most once per vehicle; it returns ``None`` where no LQR holds the healthy hover)."""

    vehicle: CampaignVehicle
    failed: tuple[int, ...]
    relaxed_hover: RelaxedHoverSolution | None
    healthy_lqr: Callable[[], Any]


def _healthy_lqr(v: CampaignVehicle) -> Any:
    from ..control.lqr import lqr_hover

    try:
        return lqr_hover(_simulator(v, v.airframe), position=HOVER_M)
    except ValueError:  # no healthy-vehicle design (module notes)
        return None


def _lqr(case: FlightCase) -> Any:
    from ..control.lqr import lqr_hover

    v = case.vehicle
    return lqr_hover(_simulator(v, v.airframe.with_failed_rotors(case.failed)), position=HOVER_M)


def _relaxed(case: FlightCase) -> Any:
    from ..control.relaxed_hover import RelaxedHoverFeedback

    v, best = case.vehicle, case.relaxed_hover
    if best is None:
        raise ValueError("no relaxed hover a linear feedback can hold")
    airframe = v.airframe.with_failed_rotors(case.failed)
    healthy = case.healthy_lqr()
    if healthy is None:
        return RelaxedHoverFeedback(best, airframe, position=HOVER_M, linear_drag_n_s_m=v.linear_drag_n_s_m)
    return RelaxedHoverFeedback(best, airframe, position=HOVER_M, linear_drag_n_s_m=v.linear_drag_n_s_m,
                                before_failure=healthy, failure_time_s=FAILURE_TIME_S)


def _indi(case: FlightCase) -> Any:
    from ..control import IndiController

    return IndiController(case.vehicle.airframe, failures=[RotorFault(r, FAILURE_TIME_S, 0.0) for r in case.failed], position=HOVER_M)


def _ke_robust(case: FlightCase) -> Any:
    from ..control.ke import UniformPassiveFtc, preset

    return UniformPassiveFtc(case.vehicle.airframe, gains=preset("ke-robust").gains, position=HOVER_M)


def _lanzon(case: FlightCase) -> Any:
    from .deciding import CONTROLLERS

    if case.vehicle.name != "lanzon-quadrotor" or case.failed != (2,):
        raise LookupError("Lanzon's design: the Lanzon quadrotor with rotor 2 failed only")
    return CONTROLLERS["lanzon-controller"].build(case.vehicle, [])


#: The controllers flown through every case (registry names), each built for the case's failure.
CONTROLLERS: dict[str, Callable[[FlightCase], Any]] = {
    "linear-feedback": _lqr,
    "relaxed-hover-feedback": _relaxed,
    "indi-controller": _indi,
    "uniform-passive-ftc": _ke_robust,
    "lanzon-controller": _lanzon,
}


def certify_against_flights(
    vehicles: Sequence[CampaignVehicle] | None = None, *, max_failed: int = 2, controllers: Sequence[str] | None = None,
) -> CertifyAgreement:
    """Certify's verdict on every failure of 1 to ``max_failed`` rotors of each vehicle (default
    :func:`preset_vehicles`) beside a flight of each controller (default every entry of
    :data:`CONTROLLERS`) through it (module notes); all flights in one Rust batch.

    Examples:

        >>> from rotorfault.studies import certify_against_flights
        >>> from rotorfault.studies.agreement import preset_vehicles
        >>> ke = [v for v in preset_vehicles() if v.name == "ke-quadcopter"]
        >>> certify_against_flights(ke, max_failed=1, controllers=["indi-controller"]).counts()
        {'cases': 4, 'survivable': 4, 'survivable_held': 4, 'not_survivable': 0, 'not_survivable_held': 0, 'agree': 4}
    """
    if vehicles is not None and not isinstance(vehicles, (list, tuple)):
        raise TypeError(f"vehicles: expected a list of rotorfault.studies.deciding.CampaignVehicle, got {type(vehicles).__name__}")
    if controllers is not None and not isinstance(controllers, (list, tuple)):
        raise TypeError(f"controllers: expected a list of controller names, got {type(controllers).__name__}")
    vehicles = preset_vehicles() if vehicles is None else list(vehicles)
    for i, v in enumerate(vehicles):
        if not isinstance(v, CampaignVehicle):
            raise TypeError(f"vehicles[{i}]: expected rotorfault.studies.deciding.CampaignVehicle, got {type(v).__name__}")
    if isinstance(max_failed, bool) or not isinstance(max_failed, int):
        raise TypeError(f"max_failed: expected an integer, got {type(max_failed).__name__}")
    if not 1 <= max_failed <= 2:
        raise ValueError(f"max_failed: must be 1 or 2 (single and double failures), got {max_failed!r}")
    names = tuple(CONTROLLERS) if controllers is None else tuple(controllers)
    for n in names:
        if n not in CONTROLLERS:
            raise ValueError(f"controllers: {n!r} is not one of {', '.join(CONTROLLERS)}")
    pending: list[tuple[int, str, Any, Any]] = []  # (case index, controller, batch entry, controller object)
    partial: list[tuple[CampaignVehicle, Any, dict[str, CaseFlight]]] = []
    for v in vehicles:
        cert = certify(v.airframe, max_failed=max_failed, spinning=True, drag=_drag(v), actuator=_actuator(v))
        healthy_lqr = functools.cache(functools.partial(_healthy_lqr, v))  # one design per vehicle
        for case in cert.cases:
            if not case.failed:
                continue
            assert case.relaxed_hover is not None  # spinning=True
            flights: dict[str, CaseFlight] = {}
            built = FlightCase(v, case.failed, case.relaxed_hover.solution, healthy_lqr)
            for name in names:
                try:
                    controller = CONTROLLERS[name](built)
                except LookupError as exc:
                    flights[name] = CaseFlight(name, "not-applicable", str(exc))
                    continue
                except ValueError as exc:
                    flights[name] = CaseFlight(name, "design-refused", str(exc).split("\n")[0][:200])
                    continue
                pending.append((len(partial), name, v, controller))
            partial.append((v, case, flights))
    _fly(pending, partial)
    cases = tuple(
        AgreementCase(v.name, case.failed, case.hover, case.relaxed_hover, tuple(flights[n] for n in names if n in flights))
        for v, case, flights in partial
    )
    return CertifyAgreement(cases, names)


def _batch(pending: list[tuple[int, str, Any, Any]], partial: list[tuple[CampaignVehicle, Any, dict[str, CaseFlight]]],
           after_failure_s: float) -> Any:
    limits = DivergenceLimits()
    duration = FAILURE_TIME_S + after_failure_s
    args: list[list[Any]] = [[] for _ in range(8)]
    for index, _name, v, controller in pending:
        failed = partial[index][1].failed
        trim = trim_command(controller)
        config = _rfcore.SimulationConfig(dt_s=DT_S, substeps=SUBSTEPS, duration_s=duration, limits=limits, wind_m_s=(0.0, 0.0, 0.0))
        for k, value in enumerate((
            v.airframe._core, _actuator(v), _drag(v), controller.core(DT_S), State(position=HOVER_M)._packed(),
            [RotorFault(r, FAILURE_TIME_S, 0.0)._packed() for r in failed], None if trim is None else [float(u) for u in trim], config,
        )):
            args[k].append(value)
    return _rfcore.simulate_summaries(args[0], args[1], args[2], args[3], args[4], args[5], args[6], args[7],
                                      [HOVER_M] * len(pending), _rfcore.VerdictCriteria())


def _fly(pending: list[tuple[int, str, Any, Any]], partial: list[tuple[CampaignVehicle, Any, dict[str, CaseFlight]]]) -> None:
    if not pending:
        return
    batch = _batch(pending, partial, AFTER_FAILURE_S)
    verdicts = [verdict_of(o) for o in batch.outcome]
    steady = np.asarray(batch.steady_spin_rad_s)
    # A run that holds its place while its spin has not settled is not yet a steady flight (a
    # quadrotor without two opposing rotors, upright, spins up towards k_r-limited rates with the
    # yaw time constant J_z / k_r, 18 s on Wang's frame): flown again for SETTLE_AFTER_FAILURE_S,
    # whose verdict stands.
    again = [j for j, verdict in enumerate(verdicts) if verdict == "holds" and math.isnan(steady[j])]
    longer = _batch([pending[j] for j in again], partial, SETTLE_AFTER_FAILURE_S) if again else None
    for j, (index, name, v, _c) in enumerate(pending):
        source, row, note = batch, j, ""
        if longer is not None and j in again:
            source, row = longer, again.index(j)
            note = (f"spin not settled {AFTER_FAILURE_S:g} s after the failure: flown for {SETTLE_AFTER_FAILURE_S:g} s; ")
        verdict = verdict_of(source.outcome[row])
        lost = verdict in ("crashed", "diverged")
        if lost:
            note += f"lost at {float(source.lost_at_s[row]):.2f} s"
            cause = source.cause[row]
            note += f" ({cause})" if cause else ""
            # What the controller asked of the rotors on the way (module notes: the entry into a
            # relaxed hover, which certify's entry condition bounds).
            note += (f", peak command {float(source.peak_command[row]):.1f} N against the {max(v.airframe.max_thrust_n):g} N limit"
                     f" (saturated {float(source.saturated_s[row]):.2f} s)")
        partial[index][2][name] = CaseFlight(
            name, verdict, note.rstrip("; "),
            math.nan if lost else float(np.asarray(source.window_horizontal_error_m)[row]),
            math.nan if lost else float(np.asarray(source.window_altitude_error_m)[row]))


__all__ = ["AFTER_FAILURE_S", "SETTLE_AFTER_FAILURE_S", "CONTROLLERS", "FAILURE_TIME_S", "AgreementCase", "CaseFlight", "CertifyAgreement",
           "certify_against_flights", "preset_vehicles", "px4_vehicle"]
