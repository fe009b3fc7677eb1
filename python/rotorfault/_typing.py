"""The string options of the public API, as ``Literal`` types (one kebab-case style), and the
:class:`Controller` protocol the simulator runs.

This module depends only on the extension module, so every layer can use it.
"""

from __future__ import annotations

from typing import Literal, Protocol, TypeAlias

from . import _rfcore

#: How an ACAI reads when the hover wrench lies outside the attainable set (Du eq. (13) or the
#: facet margin; see :mod:`rotorfault.analysis.acai`).
AcaiFormula: TypeAlias = Literal["eq13", "facet-margin"]
#: Where the hover wrench lies relative to the attainable set (a verdict every ACAI carries:
#: with ``formula="eq13"`` an ACAI of 0 can come with ``"outside"``, where hover is infeasible).
HoverPoint: TypeAlias = Literal["inside", "boundary", "outside", "rank-deficient"]
#: Virtual-control axes an analysis keeps: Du's four (thrust, roll, pitch, yaw), three with yaw
#: given up, or the full six-axis wrench (force and torque, body FRD) of tilted rotors.
ControlAxes: TypeAlias = Literal["thrust-roll-pitch-yaw", "thrust-roll-pitch", "wrench"]
#: Solver of :func:`rotorfault.allocate`.
AllocationMethod: TypeAlias = Literal["active-set", "clarabel", "pinv"]
#: Outcome of one allocation.
AllocationStatus: TypeAlias = Literal["optimal", "almost-optimal", "iteration-limit", "unconstrained", "failed"]
#: Which method produced an allocation's commands (``"clarabel"`` also for the active set's fallback).
SolvedBy: TypeAlias = Literal["active-set", "clarabel", "pinv"]
#: Rotor spin direction seen from above (``"clockwise"``, ``"anticlockwise"``, ``"acw"`` and
#: ``"counterclockwise"`` are accepted as well).
Spin: TypeAlias = Literal["cw", "ccw"]
#: Command law of Ke's uniform passive FTC (:class:`rotorfault.control.UniformPassiveFtc`).
KeLaw: TypeAlias = Literal["feedforward", "literal", "full-compensation", "baseline"]
#: Why a simulated run ended early (:data:`rotorfault.Divergence` ``kind``).
DivergenceKind: TypeAlias = Literal[
    "crashed", "non-finite-state", "non-finite-command", "tilt", "altitude-loss", "speed", "body-rate", "step-size"
]
#: A flight's outcome (:mod:`rotorfault.flight.outcomes`): held, circling, off station, or how it
#: diverged.
FlightOutcome: TypeAlias = Literal[
    "holds-position", "circling", "off-station", "crashed",
    "non-finite-state", "non-finite-command", "tilt", "altitude-loss", "speed", "body-rate", "step-size",
]
#: The old name of :data:`FlightOutcome` (a verdict is a property of a flight, not of Ke's paper).
KeOutcome: TypeAlias = FlightOutcome
#: The one verdict on a whole flight (:mod:`rotorfault.flight.outcomes`, judged over its last
#: window): it holds its setpoint, drifts (airborne to the end, not held, not circling), circles,
#: crashed into the ground, or diverged (lost another way: tilt, altitude loss, ...).
FlightVerdict: TypeAlias = Literal["holds", "drifts", "circles", "crashed", "diverged"]
#: What a row of a paper's scoreboard is (:class:`rotorfault.papers._numbers.PaperNumber`):
#: ``reproduced`` (our computation, independent of the printed number, agrees with it or not; the
#: only kind that is scored), ``input`` (a parameter taken from the paper, shown for reference)
#: or ``consistency`` (a check of our own code against the paper's statement).
NumberKind: TypeAlias = Literal["reproduced", "input", "consistency"]
#: Whether a paper's claim holds in our model (:class:`rotorfault.papers._numbers.PaperClaim`).
ClaimStatus: TypeAlias = Literal["confirmed", "not confirmed"]
#: Which channels a linear design of a VPP quadcopter commands (:func:`rotorfault.vpp.lqr`):
#: ``"wang"``, Wang's design (the fixed group's speeds held at the trim, the free group's speeds
#: one shared input, every healthy pitch an input) or ``"every-channel"`` (every healthy speed
#: and pitch).
VppInputs: TypeAlias = Literal["wang", "every-channel"]
#: Axes a certificate requires to remain after a failure (``rotorfault certify --require-axes``).
CertifiedAxis: TypeAlias = Literal["thrust", "roll", "pitch", "yaw"]
#: The direction a circular reference turns, seen from above (:func:`rotorfault.control.tracking.circle_reference`).
CircleTurn: TypeAlias = Literal["clockwise", "counterclockwise"]
#: How a batch's recording stores its values (:func:`rotorfault.simulate_batch` ``dtype``): double
#: precision, or single (half the memory; each value rounded to nearest).
RecordingDtype: TypeAlias = Literal["float64", "float32"]
#: How :func:`rotorfault.simulate_batch` steps its runs: ``"auto"`` four runs per SIMD register
#: where the batch allows it (same results bit for bit), ``"portable"`` the same groups in the
#: build a CPU without AVX2 runs (same results: a check that they do not depend on AVX2),
#: ``"scalar"`` one run at a time.
BatchLanes: TypeAlias = Literal["auto", "portable", "scalar"]
#: Where the chunks of a scan run: threads on this machine, or a ``dask.distributed`` cluster.
ScanBackend: TypeAlias = Literal["local", "dask"]
#: A named sensor suite (:class:`rotorfault.Sensing` ``suite``): motion capture, GNSS with a
#: magnetometer, GNSS with RTK; each with an IMU and rotor-speed feedback.
SensorSuiteName: TypeAlias = Literal["mocap", "gnss", "rtk"]
#: An IMU part (:class:`rotorfault.Sensing` ``imu``).
ImuPart: TypeAlias = Literal["icm-42688-p", "mpu-6000"]
#: What a controller flies on: the true state, the papers' relative noise on it, or a sensor suite
#: with the estimator (:attr:`rotorfault.Trajectory.sensed`).
Sensed: TypeAlias = Literal["truth", "paper-noise", "mocap", "gnss", "rtk"]
#: Controller of a ``rotorfault simulate`` scenario file: none, a registered controller by its
#: registry name (:mod:`rotorfault.studies.scenario_controllers` builds each), or the first
#: release's names of two designs (``lqr-hover``: linear-feedback, ``open-loop-hover``: open-loop).
ScenarioControllerKind: TypeAlias = Literal[
    "none", "open-loop", "linear-feedback", "lti", "allocated", "uniform-passive-ftc", "lanzon-controller",
    "tracking-feedback", "indi-controller", "relaxed-hover-feedback", "lqr-hover", "open-loop-hover",
]

# <controller-registry> derived from the registry of crates/rfcore-py/src/control/mod.rs
# (`python -m rotorfault.control.registry` prints this block; tests/control/test_registry.py checks it)
#: The Rust controller objects the simulator's loop runs (all can run in a batch).
CoreController: TypeAlias = (
    _rfcore.OpenLoop
    | _rfcore.LinearFeedback
    | _rfcore.Lti
    | _rfcore.Allocated
    | _rfcore.UniformPassiveFtc
    | _rfcore.LanzonController
    | _rfcore.TrackingFeedback
    | _rfcore.IndiController
    | _rfcore.RelaxedHoverFeedback
)
#: Their names: each class name in kebab case (``rotorfault._rfcore.CONTROLLERS``).
CoreControllerName: TypeAlias = Literal[
    "open-loop",
    "linear-feedback",
    "lti",
    "allocated",
    "uniform-passive-ftc",
    "lanzon-controller",
    "tracking-feedback",
    "indi-controller",
    "relaxed-hover-feedback",
]
# </controller-registry>


def core_controller_types() -> tuple[type, ...]:
    """The Rust controller classes, read from the one registry the bindings expose
    (``rotorfault._rfcore.CONTROLLERS``): what the batch type check accepts."""
    return tuple(cls for _, cls in _rfcore.CONTROLLERS)


class Controller(Protocol):
    """What :class:`rotorfault.Simulator` needs from a built-in controller: the Rust object that
    runs it at control period ``dt_s``. A controller that also has a ``u_trim`` attribute (its
    trim command) starts the actuators there. Re-exported as :class:`rotorfault.control.Controller`.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> def core_of(controller: rf.Controller) -> object:
        ...     return controller.core(sim.dt_s)
        >>> type(core_of(rf.lqr_hover(sim))).__name__
        'LinearFeedback'
    """

    def core(self, dt_s: float) -> CoreController: ...


__all__ = [
    "core_controller_types",
    "AcaiFormula",
    "ControlAxes",
    "AllocationMethod",
    "AllocationStatus",
    "RecordingDtype",
    "BatchLanes",
    "Controller",
    "CoreController",
    "CoreControllerName",
    "DivergenceKind",
    "FlightOutcome",
    "FlightVerdict",
    "NumberKind",
    "CircleTurn",
    "ClaimStatus",
    "VppInputs",
    "CertifiedAxis",
    "HoverPoint",
    "KeLaw",
    "KeOutcome",
    "ScanBackend",
    "ScenarioControllerKind",
    "SolvedBy",
    "Spin",
]
