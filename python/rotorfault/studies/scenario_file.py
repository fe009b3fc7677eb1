"""Scenario files for ``rotorfault simulate``: one TOML file names a vehicle, a controller,
faults, wind, noise or sensing and the duration. Unknown keys are errors, so a typo never silently becomes
a default. ``examples/`` has one file per paper flight (``tests/studies/test_scenario_files.py``
flies each and compares the verdict with the paper module's). Schema (every table optional;
``airframe`` or ``[vehicle]`` required)::

    airframe = "quad-x"          # a preset name, or an airframe TOML path (relative to this file)
    duration_s = 10.0
    dt_s = 0.0025                # control period (default: the simulator's, or the vehicle's)
    substeps = 4                 # RK4 steps per control period (likewise)
    record_every = 1             # keep every n-th control step in the trajectory
    ground_z_m = 0.0             # the ground plane (world NED z); contact ends the run as crashed
    ground = true                # false: no ground

    [vehicle]                    # a paper's whole vehicle instead of airframe/[actuator]/[drag]:
    kind = "ke"                  # "ke": preset = "ke-hil" | "ke-experiment" (Ke's quadcopter, lag, drag)
                                 # "lanzon": inertia_zz_kg_m2 = 1.16e-3, limits = true (Table 1)
                                 # "vpp": preset = "wang", failed = [1] (propellers failed from t = 0)

    [initial]                    # world NED; altitude is -position_m[2]
    position_m = [0, 0, -10]     # default: 10 m up; must be above the ground
    velocity_m_s = [0, 0, 0]
    euler_rad = [0, 0, 0]
    omega_rad_s = [0, 0, 0]

    [controller]                 # every registered controller, by its registry name:
    kind = "linear-feedback"     # none, open-loop, linear-feedback (the hover LQR), lti, allocated,
                                 # uniform-passive-ftc (Ke), lanzon-controller, tracking-feedback
                                 # (LQR on a [reference]; Wang's VPP LQR on a vpp vehicle),
                                 # indi-controller; "lqr-hover" and "open-loop-hover" as before
    setpoint_m = [0, 0, -10]     # the position held (default: the initial position), or
    setpoints = [[0, 0, 0, -10]] # [[time_s, north, east, down], ...]
    # ... the controller's own keys (rotorfault.studies.scenario_controllers.BUILDERS), e.g.
    # gains = "ke-hil", law = "feedforward" (uniform-passive-ftc); crossover_rad_s = 30.0
    # (lanzon-controller); trim_speeds = {3 = 9000.0} (tracking-feedback on a vpp vehicle)

    [reference]                  # tracking-feedback: what it follows
    kind = "circle"              # radius_m, period_s, climb_m_s, yaw_amplitude_rad, sample_s, turn
                                 # or "steps": waypoints = [[time_s, north, east, down], ...],
                                 #             yaw_steps = [[time_s, yaw_rad], ...]

    [actuator]                   # fixed-pitch rotors
    time_constant_s = 0.025
    rate_limit_n_s = 50.0

    [drag]                       # fields of rotorfault.Drag
    linear_n_s_m = 0.0

    [wind]
    velocity_m_s = [0, 0, 0]
    profile = [[0, 0, 0, 0], [1, 4, 4, 0]]   # [[time_s, north, east, down], ...] (m/s)

    [noise]                      # fields of rotorfault.Noise (the papers' noise on the state)
    snr_db = 15.0
    seed = 0

    [sensing]                    # fields of rotorfault.Sensing: sensors and the estimator
    suite = "mocap"              # "mocap", "gnss" or "rtk" (not with [noise])
    imu = "icm-42688-p"          # or "mpu-6000"
    imu_rate_hz = 500.0
    # gyro_range_rad_s = 70.0    # optional: replaces the part's +-2000 deg/s (34.9 rad/s)
    seed = 0

    [[fault]]                    # any number
    rotor = 1                    # 1-based
    time_s = 1.0
    efficiency = 0.0

The run is judged as a whole (:func:`rotorfault.flight.outcomes.flight_metrics`, over the last
5 s, against the setpoints, or the reference's positions): :meth:`Scenario.metrics`.
"""

from __future__ import annotations

import contextlib
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast, get_args

from .._typing import CircleTurn, ScenarioControllerKind
from .._util.convert import FloatArray, count, float_array, read_toml, real
from ..analysis.airframe import Airframe
from ..control.tracking import circle_reference, step_reference
from ..flight import Drag, FixedPitchActuator, Noise, RotorFault, Sensing, Simulator, State, Trajectory
from ..flight.outcomes import FlightMetrics, flight_metrics
from ..flight.scenarios import FlightScenario
from ..flight.simulator import DEFAULT_START_M
from . import scenario_controllers
from .scenario_controllers import Context

_TOP = {"airframe", "vehicle", "duration_s", "dt_s", "substeps", "record_every", "ground_z_m", "ground", "initial", "controller",
        "reference", "actuator", "drag", "wind", "noise", "sensing", "fault"}
_TABLES: dict[str, set[str]] = {
    "initial": {"position_m", "velocity_m_s", "euler_rad", "omega_rad_s"},
    "actuator": {"time_constant_s", "rate_limit_n_s", "thrust_coefficient_n_s2"},
    "drag": {"linear_n_s_m", "quadratic_n_s2_m2", "rotational_n_m_s", "rotor_inertia_kg_m2"},
    "wind": {"velocity_m_s", "profile"},
    "noise": {"snr_db", "std", "seed"},
    "sensing": set(Sensing.FIELDS),
    "fault": {"rotor", "time_s", "efficiency"},
}
_VEHICLES: dict[str, set[str]] = {"ke": {"kind", "preset"}, "lanzon": {"kind", "inertia_zz_kg_m2", "limits"}, "vpp": {"kind", "preset", "failed"}}
_REFERENCES: dict[str, set[str]] = {
    "circle": {"kind", "radius_m", "period_s", "climb_m_s", "yaw_amplitude_rad", "sample_s", "turn"},
    "steps": {"kind", "waypoints", "yaw_steps"},
}
CONTROLLERS: tuple[ScenarioControllerKind, ...] = get_args(ScenarioControllerKind)


def _table(data: dict[str, Any], name: str) -> dict[str, Any]:
    value = data.get(name, {})
    if not isinstance(value, dict):
        raise ValueError(f"{name}: expected a table")
    unknown = set(value) - _TABLES[name]
    if unknown:
        raise ValueError(f"{name}: unknown key(s) {', '.join(sorted(unknown))}; allowed: {', '.join(sorted(_TABLES[name]))}")
    return value


@dataclass
class Scenario:
    """A parsed scenario: the simulator, start state, controller (kind and its keys), setpoints,
    reference and faults.

    Examples:

        >>> import pathlib, tempfile
        >>> from rotorfault.studies import load_scenario
        >>> folder = tempfile.TemporaryDirectory()
        >>> path = pathlib.Path(folder.name) / "hover.toml"
        >>> _ = path.write_text('''
        ... airframe = "quad-x"
        ... duration_s = 1.0
        ... [initial]
        ... position_m = [0.0, 0.0, -10.0]
        ... [controller]
        ... kind = "lqr-hover"
        ... ''')
        >>> run = load_scenario(path).run()
        >>> run.events, float(run.t[-1])
        ([], 1.0)
        >>> folder.cleanup()
    """

    name: str
    simulator: Simulator
    initial: State
    controller_kind: ScenarioControllerKind
    faults: list[RotorFault]
    duration_s: float

    #: The file it was read from (prefixes error messages).
    path: Path | None = None
    #: The controller's own keys (the ``[controller]`` table without ``kind`` and the setpoints).
    controller_parameters: dict[str, Any] = field(default_factory=dict)
    #: ``(time_s, (north, east, down))`` steps the controller holds (default: the start).
    setpoint_steps: tuple[tuple[float, tuple[float, float, float]], ...] = ()
    #: ``(times_s, references)`` of a tracking controller (``[reference]``), else None.
    reference: tuple[FloatArray, FloatArray] | None = None
    #: ``[vehicle]``: its kind (``"airframe"`` without one) and the paper vehicle object.
    vehicle_kind: str = "airframe"
    vehicle: Any = None
    record_every: int = 1

    @property
    def setpoints(self) -> list[tuple[float, tuple[float, float, float]]] | None:
        """What the flight is judged against (``None``: no position controller): the reference's
        positions for a tracking controller, else the setpoints held."""
        if self.controller_kind == "none":
            return None
        if self.reference is not None:
            times, refs = self.reference
            return [(float(t), (float(r[0]), float(r[1]), float(r[2]))) for t, r in zip(times, refs)]
        return list(self.setpoint_steps) or [(0.0, self.initial.position)]

    @property
    def title(self) -> str:
        """What the run is, for figures: scenario, airframe, controller and setpoint."""
        text = f"{self.name}: {self.simulator.airframe.name}, controller {self.controller_kind}"
        if self.setpoints and self.reference is None:
            n, e, d = self.setpoints[0][1]
            text += f", setpoint N {n:g}, E {e:g}, alt {-d:g} m"
        return text

    def context(self) -> Context:
        steps = tuple(self.setpoint_steps) or ((0.0, self.initial.position),)
        return Context(self.simulator, self.vehicle_kind, self.vehicle, steps, tuple(self.faults), self.reference)

    def controller(self) -> Any:
        """The controller of the file, designed for its simulator (None for ``kind = "none"``)."""
        with self._errors():
            return scenario_controllers.build(self.controller_kind, self.context(), self.controller_parameters)

    def run(self) -> Trajectory:
        """Flies the scenario; errors name the file and its keys."""
        controller = self.controller()
        with self._errors():
            return self.simulator.run(self.initial, self.duration_s, controller=controller, faults=self.faults, record_every=self.record_every)

    def metrics(self, trajectory: Trajectory) -> FlightMetrics:
        """The verdict on the whole flight (:func:`rotorfault.flight.outcomes.flight_metrics`)
        against :attr:`setpoints` (the start, without a controller)."""
        setpoints = self.setpoints or [(0.0, self.initial.position)]
        efficiency = tuple(float(e) for e in trajectory.efficiency[-1])
        judged = FlightScenario(self.name, self.title, efficiency, tuple(self.faults), self.duration_s, tuple(setpoints))
        return flight_metrics(trajectory, judged)

    @contextlib.contextmanager
    def _errors(self) -> Iterator[None]:
        try:
            with _file_keys():
                yield
        except (ValueError, TypeError) as exc:
            if self.path is None:
                raise
            raise type(exc)(f"{self.path}: {exc}") from None


@contextlib.contextmanager
def _file_keys() -> Iterator[None]:
    """The simulator's field names as the file's keys (``faults[0].rotor`` is ``fault[0].rotor``
    in the file, ``.time`` is ``.time_s``)."""
    try:
        yield
    except (ValueError, TypeError) as exc:
        text = re.sub(r"\bfaults\[(\d+)\]\.time\b", r"fault[\1].time_s", str(exc))
        text = re.sub(r"\bfaults\[(\d+)\]", r"fault[\1]", text)
        text = re.sub(r"\bx0\.position\[", "initial.position_m[", text)
        raise type(exc)(text) from None


def load_scenario(path: str | Path) -> Scenario:
    """Reads and validates a scenario file (errors name the key and the file).

    Examples:

        >>> import pathlib, tempfile
        >>> from rotorfault.studies import load_scenario
        >>> folder = tempfile.TemporaryDirectory()
        >>> path = pathlib.Path(folder.name) / "hover.toml"
        >>> _ = path.write_text('''
        ... airframe = "quad-x"
        ... duration_s = 1.0
        ... [initial]
        ... position_m = [0.0, 0.0, -10.0]
        ... [controller]
        ... kind = "lqr-hover"
        ... ''')
        >>> scenario = load_scenario(path)
        >>> scenario.controller_kind, scenario.duration_s
        ('lqr-hover', 1.0)
        >>> folder.cleanup()
    """
    data = read_toml("scenario_file", path)
    path = Path(path)
    try:
        with _file_keys():
            scenario = _parse(data, path)
    except (ValueError, TypeError) as exc:
        raise type(exc)(f"{path}: {exc}") from None
    scenario.path = path
    return scenario


def _parse(data: dict[str, Any], path: Path) -> Scenario:
    unknown = set(data) - _TOP
    if unknown:
        raise ValueError(f"unknown key(s) {', '.join(sorted(unknown))}; allowed: {', '.join(sorted(_TOP))}")
    kind_vehicle, vehicle, parts = _vehicle(data, path)
    initial = _table(data, "initial")
    state = State(
        position=initial.get("position_m", DEFAULT_START_M),
        velocity=initial.get("velocity_m_s", (0.0, 0.0, 0.0)),
        euler=initial.get("euler_rad", (0.0, 0.0, 0.0)),
        omega=initial.get("omega_rad_s", (0.0, 0.0, 0.0)),
    )
    controller = data.get("controller", {})
    if not isinstance(controller, dict):
        raise ValueError("controller: expected a table")
    parameters = dict(controller)
    kind = parameters.pop("kind", "lqr-hover")
    if kind not in CONTROLLERS:
        raise ValueError(f"controller.kind: must be one of {', '.join(CONTROLLERS)}, got {kind!r}")
    steps = _setpoints(parameters)
    noise = data.get("noise")
    sensing = data.get("sensing")
    faults_raw = data.get("fault", [])
    if not isinstance(faults_raw, list):
        raise ValueError("fault: expected an array of tables ([[fault]])")
    faults = []
    for k, f in enumerate(faults_raw):
        if not isinstance(f, dict) or set(f) - _TABLES["fault"] or "rotor" not in f or "time_s" not in f:
            raise ValueError(f"fault[{k}]: needs rotor and time_s (and optional efficiency), nothing else")
        time_s = real(f"fault[{k}].time_s", f["time_s"])
        efficiency = real(f"fault[{k}].efficiency", f.get("efficiency", 0.0))
        # Checked when the file is read, as the simulator would when flown (a NaN was carried in the
        # scenario); the time below, against the duration.
        if not 0.0 <= efficiency <= 1.0:
            raise ValueError(f"fault[{k}].efficiency: must lie in [0, 1], got {efficiency}")
        faults.append(RotorFault(rotor=f["rotor"], time=time_s, efficiency=efficiency))
    wind = _table(data, "wind")
    timing = {key: data[key] for key in ("dt_s", "substeps") if key in data}
    simulator = Simulator(
        parts["airframe"],
        dt_s=timing.get("dt_s", parts["dt_s"]),
        substeps=timing.get("substeps", parts["substeps"]),
        drag=parts["drag"],
        wind=wind.get("velocity_m_s", (0.0, 0.0, 0.0)),
        wind_profile=_rows("wind.profile", wind["profile"], 4, lambda r: (r[0], tuple(r[1:]))) if "profile" in wind else None,
        actuator=parts["actuator"],
        noise=None if noise is None else Noise(**_table(data, "noise")),
        sensing=None if sensing is None else Sensing(**_table(data, "sensing")),
        ground_z_m=data.get("ground_z_m"),
        ground=data.get("ground", True),
    )
    duration_s = real("duration_s", data.get("duration_s", 10.0))
    if not duration_s >= simulator.dt_s:
        raise ValueError(f"duration_s: must be at least one control period (dt_s = {simulator.dt_s:g} s), got {duration_s:g}")
    for k, fault in enumerate(faults):
        if not 0.0 <= fault.time < duration_s:
            raise ValueError(f"fault[{k}].time_s: must lie in [0, duration_s) = [0, {duration_s:g}) s, got {fault.time:g}")
    # The controller table refused now, not when the controller is designed for a run.
    scenario_controllers.check(kind, kind_vehicle, parameters)
    reference = _reference(data, duration_s)
    if reference is not None and kind != "tracking-feedback":
        raise ValueError(f"reference: only a tracking-feedback controller follows a reference, not {kind}")
    record_every = count("record_every", data.get("record_every", 1))
    if record_every < 1:
        raise ValueError("record_every: must be at least 1")
    return Scenario(path.stem, simulator, state, cast(ScenarioControllerKind, kind), faults, duration_s, None, parameters, steps,
                    reference, kind_vehicle, vehicle, record_every)


def _vehicle(data: dict[str, Any], path: Path) -> tuple[str, Any, dict[str, Any]]:
    """``(kind, vehicle object, simulator parts)`` from ``airframe`` and ``[actuator]``/``[drag]``,
    or from ``[vehicle]`` (a paper's vehicle: its own airframe, actuator, drag and timing)."""
    raw = data.get("vehicle")
    if raw is None:
        if "airframe" not in data or not isinstance(data["airframe"], str):
            raise ValueError("airframe: required (a preset name or an airframe TOML path), or give a [vehicle]")
        actuator = _table(data, "actuator")
        return "airframe", None, {
            "airframe": Airframe.load(data["airframe"], relative_to=path.parent),
            "actuator": FixedPitchActuator(
                time_constant_s=actuator.get("time_constant_s", 0.0),
                rate_limit_n_s=actuator.get("rate_limit_n_s", math.inf),
                thrust_coefficient_n_s2=actuator.get("thrust_coefficient_n_s2", 0.0),
            ),
            "drag": Drag(**_table(data, "drag")),
            "dt_s": 1.0 / 400.0,
            "substeps": 4,
        }
    if not isinstance(raw, dict):
        raise ValueError("vehicle: expected a table")
    for key in ("airframe", "actuator", "drag"):
        if key in data:
            raise ValueError(f"{key}: a [vehicle] brings its own airframe, actuator and drag; give one or the other")
    kind = raw.get("kind")
    if kind not in _VEHICLES:
        raise ValueError(f"vehicle.kind: must be one of {', '.join(_VEHICLES)}, got {kind!r}")
    unknown = set(raw) - _VEHICLES[kind]
    if unknown:
        raise ValueError(f"vehicle: unknown key(s) {', '.join(sorted(unknown))} for kind {kind}; allowed: {', '.join(sorted(_VEHICLES[kind]))}")
    vehicle: Any
    if kind == "ke":
        from ..control import ke

        vehicle = ke.preset(raw.get("preset", "ke-hil"))
        sim = vehicle.simulator()
    elif kind == "lanzon":
        from ..control.lanzon import LanzonVehicle

        vehicle = LanzonVehicle(**({"inertia_zz_kg_m2": real("vehicle.inertia_zz_kg_m2", raw["inertia_zz_kg_m2"])} if "inertia_zz_kg_m2" in raw else {}))
        limits = raw.get("limits", True)
        if not isinstance(limits, bool):
            raise TypeError(f"vehicle.limits: expected true or false, got {type(limits).__name__}")
        sim = vehicle.simulator(limits=limits)
    else:
        from ..control import vpp

        vehicle = vpp.preset(raw.get("preset", "wang"))
        sim = vehicle.simulator(failed=raw.get("failed", ()))
    return kind, vehicle, {"airframe": sim.airframe, "actuator": sim.actuator, "drag": sim.drag, "dt_s": sim.dt_s, "substeps": sim.substeps}


def _rows(field_name: str, value: Any, width: int, make: Any) -> list[Any]:
    rows = float_array(field_name, value, 2)
    if rows.shape[1] != width:
        raise ValueError(f"{field_name}: expected rows of {width} numbers, got {rows.shape[1]}")
    return [make([float(v) for v in row]) for row in rows]


def _setpoints(parameters: dict[str, Any]) -> tuple[tuple[float, tuple[float, float, float]], ...]:
    """The ``setpoint_m`` / ``setpoints`` keys of ``[controller]`` (removed from ``parameters``)."""
    if "setpoint_m" in parameters and "setpoints" in parameters:
        raise ValueError("controller.setpoint_m, controller.setpoints: give one or the other")
    if "setpoint_m" in parameters:
        point = float_array("controller.setpoint_m", parameters.pop("setpoint_m"), 1)
        if point.shape != (3,):
            raise ValueError(f"controller.setpoint_m: expected [north, east, down], got {point.shape[0]} entries")
        return ((0.0, (float(point[0]), float(point[1]), float(point[2]))),)
    if "setpoints" in parameters:
        return tuple(_rows("controller.setpoints", parameters.pop("setpoints"), 4, lambda r: (r[0], (r[1], r[2], r[3]))))
    return ()


def _reference(data: dict[str, Any], duration_s: float) -> tuple[FloatArray, FloatArray] | None:
    raw = data.get("reference")
    if raw is None:
        return None
    if not isinstance(raw, dict):
        raise ValueError("reference: expected a table")
    kind = raw.get("kind")
    if kind not in _REFERENCES:
        raise ValueError(f"reference.kind: must be one of {', '.join(_REFERENCES)}, got {kind!r}")
    unknown = set(raw) - _REFERENCES[kind]
    if unknown:
        raise ValueError(f"reference: unknown key(s) {', '.join(sorted(unknown))} for kind {kind}; allowed: {', '.join(sorted(_REFERENCES[kind]))}")
    if kind == "circle":
        values = {k: real(f"reference.{k}", raw[k]) for k in _REFERENCES["circle"] - {"kind", "turn"} if k in raw}
        for key in ("radius_m", "period_s"):
            if key not in values:
                raise ValueError(f"reference.{key}: required for a circle")
        turn = raw.get("turn", "clockwise")
        if turn not in get_args(CircleTurn):
            raise ValueError(f"reference.turn: must be one of {', '.join(get_args(CircleTurn))}, got {turn!r}")
        return circle_reference(duration_s=duration_s, turn=turn, **values)
    if "waypoints" not in raw:
        raise ValueError("reference.waypoints: required for steps ([[time_s, north, east, down], ...])")
    waypoints = _rows("reference.waypoints", raw["waypoints"], 4, lambda r: (r[0], (r[1], r[2], r[3])))
    yaw_steps = _rows("reference.yaw_steps", raw["yaw_steps"], 2, lambda r: (r[0], r[1])) if "yaw_steps" in raw else []
    return step_reference(waypoints, yaw_steps)
