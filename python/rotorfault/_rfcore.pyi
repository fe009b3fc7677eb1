"""Type stubs of the Rust extension (checked by mypy.stubtest in tests/test_stubs.py)."""

from typing import Any, final

import numpy as np
import numpy.typing as npt

__version__: str
RANK_RTOL: float
ZERO_RTOL: float
DEFAULT_GRAVITY_M_S2: float

_F64 = npt.NDArray[np.float64]

@final
class Airframe:
    def __new__(
        cls,
        name: str,
        arm_angle_rad: _F64,
        arm_length_m: _F64,
        spin_sign: _F64,
        max_thrust_n: _F64,
        min_thrust_n: _F64,
        efficiency: _F64,
        mass_kg: float,
        inertia_kg_m2: _F64,
        drag_torque_ratio_m: float,
        gravity_m_s2: float,
    ) -> Airframe: ...
    @staticmethod
    def from_toml_str(text: str, origin: str) -> Airframe: ...
    def with_efficiency(self, eta: _F64) -> Airframe: ...
    def to_toml_str(self) -> str: ...
    def effectiveness_matrix(self) -> _F64: ...
    @property
    def name(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def rotor_count(self) -> int: ...
    @property
    def mass_kg(self) -> float: ...
    @property
    def drag_torque_ratio_m(self) -> float: ...
    @property
    def gravity_m_s2(self) -> float: ...
    @property
    def inertia_kg_m2(self) -> _F64: ...
    @property
    def arm_angle_rad(self) -> _F64: ...
    @property
    def arm_length_m(self) -> _F64: ...
    @property
    def spin_sign(self) -> _F64: ...
    @property
    def max_thrust_n(self) -> _F64: ...
    @property
    def min_thrust_n(self) -> _F64: ...
    @property
    def efficiency(self) -> _F64: ...

def acai(airframe: Airframe, eta: _F64, give_up_yaw: bool, formula: str) -> float: ...
def acai_batch(airframe: Airframe, etas: _F64, give_up_yaw: bool, formula: str) -> _F64: ...
def acai_from_matrix(
    effectiveness_matrix: _F64, f_min: _F64, f_max: _F64, g_vec: _F64, formula: str
) -> float: ...
def controllability(
    airframe: Airframe, eta: _F64, give_up_yaw: bool, formula: str
) -> dict[str, Any]: ...
def failure_table(
    airframe: Airframe, max_failed: int, formula: str
) -> list[tuple[list[int], dict[str, Any], dict[str, Any]]]: ...

@final
class FixedPitchActuator:
    def __new__(
        cls, time_constant_s: float, rate_limit_per_s: float, thrust_coefficient_n_s2: float
    ) -> FixedPitchActuator: ...

@final
class VariablePitchActuator:
    def __new__(
        cls,
        coefficients: tuple[float, float, float, float],
        speed_bounds: tuple[float, float],
        pitch_bounds: tuple[float, float],
        speed_to_rad_s: float,
        time_constant_s: float,
        rate_limit_per_s: float,
    ) -> VariablePitchActuator: ...

@final
class OpenLoop:
    def __new__(cls, times_s: _F64, commands: _F64) -> OpenLoop: ...

@final
class LinearFeedback:
    def __new__(cls, x_trim: _F64, u_trim: _F64, gain: _F64) -> LinearFeedback: ...

@final
class DiscreteLti:
    def __new__(cls, a: _F64, b: _F64, c: _F64, d: _F64, x_trim: _F64, u_trim: _F64) -> DiscreteLti: ...

_Actuator = FixedPitchActuator | VariablePitchActuator
_Config = tuple[
    float,
    int,
    float,
    list[float],
    list[float],
    list[tuple[float, tuple[float, float, float]]],
    tuple[float, list[float], int] | None,
]

def simulate(
    airframe: Airframe,
    actuator: _Actuator,
    aero: list[float],
    controller: Any,
    x0: list[float],
    fault_list: list[tuple[int, float, float]],
    health: _F64,
    settle: _F64 | None,
    config_args: _Config,
) -> dict[str, Any]: ...
def simulate_batch(
    airframe: Airframe,
    actuator: _Actuator,
    aero: list[float],
    controllers: list[Any],
    x0s: list[list[float]],
    fault_lists: list[list[tuple[int, float, float]]],
    health: _F64,
    settles: list[list[float] | None],
    config_args: _Config,
) -> list[dict[str, Any]]: ...
def state_derivative(
    airframe: Airframe,
    actuator: _Actuator,
    aero: list[float],
    x: list[float],
    command: _F64,
    health: _F64,
    wind: list[float],
) -> _F64: ...

@final
class AllocationProblem:
    def __new__(
        cls,
        matrix_: _F64,
        weights: _F64,
        lower: _F64,
        upper: _F64,
        regularization: float,
        preferred: _F64,
    ) -> AllocationProblem: ...
    def objective(self, virtual_control: _F64, commands: _F64) -> tuple[float, float]: ...
    def rate_limited_bounds(self, previous: _F64, max_change: _F64) -> tuple[_F64, _F64]: ...

@final
class Allocated:
    def __new__(cls, law: OpenLoop | LinearFeedback | DiscreteLti, problem: AllocationProblem) -> Allocated: ...

def allocate(
    problem: AllocationProblem,
    controls: _F64,
    method_name: str,
    priorities: list[list[int]] | None,
    tolerance: float,
    max_iterations: int,
) -> tuple[_F64, _F64, list[str], list[int]]: ...
def time_allocations(problem: AllocationProblem, controls: _F64, method_name: str, repeats: int) -> _F64: ...
def max_along_direction(
    matrix_: _F64, lower: _F64, upper: _F64, direction: _F64, base: _F64, tolerance: float
) -> tuple[float, _F64, str] | None: ...
def hover_thrust_margin(
    airframe: Airframe, give_up_yaw: bool, tolerance: float
) -> tuple[float, float, float, _F64 | None, str]: ...

@final
class UniformPassiveFtc:
    def __new__(
        cls,
        airframe: Airframe,
        law: str,
        setpoints: list[tuple[float, tuple[float, float, float]]],
        dt: float,
        k_p: float,
        k_v: float,
        k_vz: float,
        accel_limit_m_s2: float,
        k_n3: float,
        k_omega: float,
        k_r: float,
        k_cp: float,
        epsilon_s: float,
        k_rotor: float,
        k_rotor_z: float,
        weights: list[float],
        k_iz: float,
    ) -> UniformPassiveFtc: ...

def ftc_preset_from_toml(text: str, origin: str) -> dict[str, Any]: ...
def replay(
    controller: OpenLoop | LinearFeedback | DiscreteLti | Allocated | UniformPassiveFtc,
    times: _F64,
    states: _F64,
    command_count: int,
) -> _F64: ...
