"""Scenario files for ``rotorfault simulate``: one TOML file names an airframe, a controller,
faults, wind, noise and the duration. Unknown keys are errors, so a typo never silently becomes
a default. Schema (every table optional except the top-level ``airframe``)::

    airframe = "quad-x"          # a preset name, or an airframe TOML path (relative to this file)
    duration_s = 10.0
    dt_s = 0.0025                # control period
    substeps = 4                 # RK4 steps per control period
    ground_z_m = 0.0             # the ground plane (world NED z); contact ends the run as crashed
    ground = true                # false: no ground

    [initial]                    # world NED; altitude is -position_m[2]
    position_m = [0, 0, -10]     # default: 10 m up; must be above the ground
    velocity_m_s = [0, 0, 0]
    euler_rad = [0, 0, 0]
    omega_rad_s = [0, 0, 0]

    [controller]
    kind = "lqr-hover"           # "none", "open-loop-hover" or "lqr-hover" (holds the initial position)

    [actuator]                   # fixed-pitch rotors
    time_constant_s = 0.025
    rate_limit_n_s = 50.0

    [drag]                       # fields of rotorfault.Drag
    linear_n_s_m = 0.0

    [wind]
    velocity_m_s = [0, 0, 0]

    [noise]                      # fields of rotorfault.Noise
    snr_db = 15.0
    seed = 0

    [[fault]]                    # any number
    rotor = 1                    # 1-based
    time_s = 1.0
    efficiency = 0.0
"""

from __future__ import annotations

import contextlib
import math
import re
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast, get_args

from .._typing import ScenarioControllerKind
from .._util.convert import real
from ..analysis.airframe import Airframe
from ..control import OpenLoop, hover_trim, lqr_hover
from ..flight import Drag, FixedPitchActuator, Noise, RotorFault, Simulator, State, Trajectory
from ..flight.simulator import DEFAULT_START_M

_TOP = {"airframe", "duration_s", "dt_s", "substeps", "ground_z_m", "ground", "initial", "controller", "actuator", "drag", "wind", "noise", "fault"}
_TABLES: dict[str, set[str]] = {
    "initial": {"position_m", "velocity_m_s", "euler_rad", "omega_rad_s"},
    "controller": {"kind"},
    "actuator": {"time_constant_s", "rate_limit_n_s", "thrust_coefficient_n_s2"},
    "drag": {"linear_n_s_m", "quadratic_n_s2_m2", "rotational_n_m_s", "rotor_inertia_kg_m2"},
    "wind": {"velocity_m_s"},
    "noise": {"snr_db", "std", "seed"},
    "fault": {"rotor", "time_s", "efficiency"},
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
    """A parsed scenario: the simulator, start state, controller kind and faults."""

    name: str
    simulator: Simulator
    initial: State
    controller_kind: ScenarioControllerKind
    faults: list[RotorFault]
    duration_s: float

    #: The file it was read from (prefixes error messages).
    path: Path | None = None

    @property
    def setpoints(self) -> list[tuple[float, tuple[float, float, float]]] | None:
        """The position the controller holds (``None``: no position controller)."""
        return None if self.controller_kind == "none" else [(0.0, self.initial.position)]

    @property
    def title(self) -> str:
        """What the run is, for figures: scenario, airframe, controller and setpoint."""
        text = f"{self.name}: {self.simulator.airframe.name}, controller {self.controller_kind}"
        if self.setpoints:
            n, e, d = self.setpoints[0][1]
            text += f", setpoint N {n:g}, E {e:g}, alt {-d:g} m"
        return text

    def run(self) -> Trajectory:
        """Flies the scenario; errors name the file and its keys."""
        controller: Any = None
        target = self.initial.position
        try:
            with _file_keys():
                if self.controller_kind == "lqr-hover":
                    controller = lqr_hover(self.simulator, position=target)
                elif self.controller_kind == "open-loop-hover":
                    controller = OpenLoop.constant(hover_trim(self.simulator, position=target).command)
                return self.simulator.run(self.initial, self.duration_s, controller=controller, faults=self.faults)
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
    """Reads and validates a scenario file (errors name the key and the file)."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ValueError(f"scenario_file: {str(path)!r} does not exist") from None
    except OSError as exc:
        raise ValueError(f"scenario_file: cannot read {str(path)!r}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{path}: not UTF-8 text ({exc.reason} at byte {exc.start}); a scenario file is TOML") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: {exc}") from None
    except RecursionError:
        raise ValueError(f"{path}: nested too deeply to read (a scenario file has at most two levels of tables)") from None
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
    if "airframe" not in data or not isinstance(data["airframe"], str):
        raise ValueError("airframe: required, a preset name or an airframe TOML path")
    airframe = Airframe.load(data["airframe"], relative_to=path.parent)
    initial = _table(data, "initial")
    state = State(
        position=initial.get("position_m", DEFAULT_START_M),
        velocity=initial.get("velocity_m_s", (0.0, 0.0, 0.0)),
        euler=initial.get("euler_rad", (0.0, 0.0, 0.0)),
        omega=initial.get("omega_rad_s", (0.0, 0.0, 0.0)),
    )
    kind = _table(data, "controller").get("kind", "lqr-hover")
    if kind not in CONTROLLERS:
        raise ValueError(f"controller.kind: must be one of {', '.join(CONTROLLERS)}, got {kind!r}")
    actuator = _table(data, "actuator")
    noise = data.get("noise")
    faults_raw = data.get("fault", [])
    if not isinstance(faults_raw, list):
        raise ValueError("fault: expected an array of tables ([[fault]])")
    faults = []
    for k, f in enumerate(faults_raw):
        if not isinstance(f, dict) or set(f) - _TABLES["fault"] or "rotor" not in f or "time_s" not in f:
            raise ValueError(f"fault[{k}]: needs rotor and time_s (and optional efficiency), nothing else")
        time_s = real(f"fault[{k}].time_s", f["time_s"])
        faults.append(RotorFault(rotor=f["rotor"], time=time_s, efficiency=f.get("efficiency", 0.0)))
    simulator = Simulator(
        airframe,
        dt_s=data.get("dt_s", 1.0 / 400.0),
        substeps=data.get("substeps", 4),
        drag=Drag(**_table(data, "drag")),
        wind=_table(data, "wind").get("velocity_m_s", (0.0, 0.0, 0.0)),
        actuator=FixedPitchActuator(
            time_constant_s=actuator.get("time_constant_s", 0.0),
            rate_limit_n_s=actuator.get("rate_limit_n_s", math.inf),
            thrust_coefficient_n_s2=actuator.get("thrust_coefficient_n_s2", 0.0),
        ),
        noise=None if noise is None else Noise(**_table(data, "noise")),
        ground_z_m=data.get("ground_z_m"),
        ground=data.get("ground", True),
    )
    duration_s = real("duration_s", data.get("duration_s", 10.0))
    if not duration_s >= simulator.dt_s:
        raise ValueError(f"duration_s: must be at least one control period (dt_s = {simulator.dt_s:g} s), got {duration_s:g}")
    for k, fault in enumerate(faults):
        if not 0.0 <= fault.time < duration_s:
            raise ValueError(f"fault[{k}].time_s: must lie in [0, duration_s) = [0, {duration_s:g}) s, got {fault.time:g}")
    return Scenario(path.stem, simulator, state, cast(ScenarioControllerKind, kind), faults, duration_s)
