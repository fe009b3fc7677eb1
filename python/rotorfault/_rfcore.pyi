"""Type stubs of the Rust extension (checked by mypy.stubtest in tests/test_stubs.py)."""

from typing import Any, final

import numpy as np
import numpy.typing as npt

__version__: str
RANK_RTOL: float
MAX_RATE_STEP: float
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
    def with_efficiency(self, efficiency: _F64) -> Airframe: ...
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

@final
class AcaiResult:
    @property
    def acai(self) -> float: ...
    @property
    def hover(self) -> str: ...

@final
class AcaiBatch:
    @property
    def acai(self) -> _F64: ...
    @property
    def hover_code(self) -> npt.NDArray[np.int8]: ...

def acai(airframe: Airframe, efficiency: _F64, give_up_yaw: bool, formula: str) -> AcaiResult: ...
def acai_batch(airframe: Airframe, efficiencies: _F64, give_up_yaw: bool, formula: str) -> _F64: ...
def acai_batch_with_hover(airframe: Airframe, efficiencies: _F64, give_up_yaw: bool, formula: str) -> AcaiBatch: ...
def acai_from_matrix(
    effectiveness_matrix: _F64, f_min: _F64, f_max: _F64, g_vec: _F64, formula: str
) -> AcaiResult: ...
@final
class ControllabilityReport:
    @property
    def state_dimension(self) -> int: ...
    @property
    def controllability_rank(self) -> int: ...
    @property
    def virtual_control_dimension(self) -> int: ...
    @property
    def effectiveness_rank(self) -> int: ...
    @property
    def acai(self) -> float: ...
    @property
    def formula(self) -> str: ...
    @property
    def verdict(self) -> str: ...
    @property
    def controllable(self) -> bool: ...
    @property
    def hover(self) -> str: ...

def controllability(
    airframe: Airframe, efficiency: _F64, give_up_yaw: bool, formula: str
) -> ControllabilityReport: ...
def failure_table(
    airframe: Airframe, max_failed: int, formula: str
) -> list[tuple[list[int], ControllabilityReport, ControllabilityReport]]: ...

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
class Lti:
    def __new__(cls, a: _F64, b: _F64, c: _F64, d: _F64, x_trim: _F64, u_trim: _F64) -> Lti: ...

_Actuator = FixedPitchActuator | VariablePitchActuator

@final
class Drag:
    def __new__(
        cls,
        *,
        linear_n_s_m: float | None = None,
        quadratic_n_s2_m2: float | None = None,
        rotational_n_m_s: float | None = None,
        rotor_inertia_kg_m2: float | None = None,
    ) -> Drag: ...
    @property
    def linear_n_s_m(self) -> float: ...
    @property
    def quadratic_n_s2_m2(self) -> float: ...
    @property
    def rotational_n_m_s(self) -> float: ...
    @property
    def rotor_inertia_kg_m2(self) -> float: ...

@final
class DivergenceLimits:
    def __new__(
        cls,
        *,
        max_tilt_rad: float | None = None,
        max_altitude_loss_m: float | None = None,
        max_speed_m_s: float | None = None,
        max_rate_rad_s: float | None = None,
    ) -> DivergenceLimits: ...
    @property
    def max_tilt_rad(self) -> float: ...
    @property
    def max_altitude_loss_m(self) -> float: ...
    @property
    def max_speed_m_s(self) -> float: ...
    @property
    def max_rate_rad_s(self) -> float: ...

@final
class SensorNoise:
    def __new__(cls, *, relative_std: float, absolute_std: list[float], seed: int) -> SensorNoise: ...
    @property
    def relative_std(self) -> float: ...
    @property
    def absolute_std(self) -> list[float]: ...
    @property
    def seed(self) -> int: ...

@final
class SimulationConfig:
    def __new__(
        cls,
        *,
        dt_s: float | None = None,
        substeps: int | None = None,
        duration_s: float | None = None,
        limits: DivergenceLimits | None = None,
        wind_m_s: tuple[float, float, float] | None = None,
        wind_profile: list[tuple[float, tuple[float, float, float]]] | None = None,
        noise: SensorNoise | None = None,
        record_every: int | None = None,
    ) -> SimulationConfig: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def substeps(self) -> int: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def record_every(self) -> int: ...
    @property
    def limits(self) -> DivergenceLimits: ...
    @property
    def wind_m_s(self) -> list[float]: ...
    def record_times(self) -> _F64: ...

@final
class Divergence:
    @property
    def time_s(self) -> float: ...
    @property
    def reason(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def state(self) -> list[float]: ...

@final
class Trajectory:
    @property
    def t(self) -> _F64: ...
    @property
    def position(self) -> _F64: ...
    @property
    def velocity(self) -> _F64: ...
    @property
    def quaternion(self) -> _F64: ...
    @property
    def euler(self) -> _F64: ...
    @property
    def omega(self) -> _F64: ...
    @property
    def primary_axis(self) -> _F64: ...
    @property
    def command(self) -> _F64: ...
    @property
    def thrust(self) -> _F64: ...
    @property
    def efficiency(self) -> _F64: ...
    @property
    def measured(self) -> _F64: ...
    @property
    def divergence(self) -> Divergence | None: ...

_Controller = OpenLoop | LinearFeedback | Lti | Allocated | UniformPassiveFtc | LanzonController

def simulate(
    airframe: Airframe,
    actuator: _Actuator,
    drag: Drag,
    controller: Any,
    x0: list[float],
    fault_list: list[tuple[int, float, float]],
    efficiency: _F64,
    settle: _F64 | None,
    config: SimulationConfig,
) -> Trajectory: ...
def simulate_batch(
    airframe: Airframe,
    actuator: _Actuator,
    drag: Drag,
    controllers: list[_Controller | None],
    x0s: list[list[float]],
    fault_lists: list[list[tuple[int, float, float]]],
    efficiency: _F64,
    settles: list[list[float] | None],
    config: SimulationConfig,
) -> list[Trajectory]: ...
def state_derivative(
    airframe: Airframe,
    actuator: _Actuator,
    drag: Drag,
    x: list[float],
    command: _F64,
    efficiency: _F64,
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
    def __new__(cls, law: OpenLoop | LinearFeedback | Lti, problem: AllocationProblem) -> Allocated: ...

@final
class AllocationBatch:
    @property
    def commands(self) -> _F64: ...
    @property
    def achieved(self) -> _F64: ...
    @property
    def statuses(self) -> list[str]: ...
    @property
    def iterations(self) -> list[int]: ...

def allocate(
    problem: AllocationProblem,
    controls: _F64,
    method_name: str,
    priorities: list[list[int]] | None,
    tolerance: float,
    max_iterations: int,
) -> AllocationBatch: ...
def time_allocations(problem: AllocationProblem, controls: _F64, method_name: str, repeats: int) -> _F64: ...
@final
class DirectionalLimit:
    @property
    def scale(self) -> float: ...
    @property
    def commands(self) -> list[float]: ...
    @property
    def status(self) -> str: ...

@final
class HoverMargin:
    @property
    def max_thrust_n(self) -> float: ...
    @property
    def weight_n(self) -> float: ...
    @property
    def margin_n(self) -> float: ...
    @property
    def commands(self) -> list[float] | None: ...
    @property
    def status(self) -> str: ...

def max_along_direction(
    matrix_: _F64, lower: _F64, upper: _F64, direction: _F64, base: _F64, tolerance: float
) -> DirectionalLimit | None: ...
def hover_thrust_margin(airframe: Airframe, give_up_yaw: bool, tolerance: float) -> HoverMargin: ...

@final
class KeGains:
    def __new__(
        cls,
        *,
        k_p: float | None = None,
        k_v: float | None = None,
        k_vz: float | None = None,
        accel_limit_m_s2: float | None = None,
        k_n3: float | None = None,
        k_omega: float | None = None,
        k_r: float | None = None,
        k_cp: float | None = None,
        epsilon_s: float | None = None,
        k_rotor: float | None = None,
        k_rotor_z: float | None = None,
        k_iz: float | None = None,
        weights: list[float] | None = None,
    ) -> KeGains: ...
    @property
    def k_p(self) -> float: ...
    @property
    def k_v(self) -> float: ...
    @property
    def k_vz(self) -> float: ...
    @property
    def accel_limit_m_s2(self) -> float: ...
    @property
    def k_n3(self) -> float: ...
    @property
    def k_omega(self) -> float: ...
    @property
    def k_r(self) -> float: ...
    @property
    def k_cp(self) -> float: ...
    @property
    def epsilon_s(self) -> float: ...
    @property
    def k_rotor(self) -> float: ...
    @property
    def k_rotor_z(self) -> float: ...
    @property
    def k_iz(self) -> float: ...
    @property
    def weights(self) -> list[float]: ...

@final
class UniformPassiveFtc:
    def __new__(
        cls,
        airframe: Airframe,
        *,
        law: str,
        setpoints: list[tuple[float, tuple[float, float, float]]],
        dt_s: float,
        gains: KeGains,
    ) -> UniformPassiveFtc: ...

@final
class LanzonModel:
    def __new__(
        cls,
        *,
        mass_kg: float | None = None,
        gravity_m_s2: float | None = None,
        inertia_xx_kg_m2: float | None = None,
        inertia_zz_kg_m2: float | None = None,
        arm_length_m: float | None = None,
        drag_torque_ratio_m: float | None = None,
        rotational_drag_n_m_s: float | None = None,
        linear_drag_n_s_m: float | None = None,
    ) -> LanzonModel: ...
    @property
    def mass_kg(self) -> float: ...
    @property
    def gravity_m_s2(self) -> float: ...
    @property
    def inertia_xx_kg_m2(self) -> float: ...
    @property
    def inertia_zz_kg_m2(self) -> float: ...
    @property
    def arm_length_m(self) -> float: ...
    @property
    def drag_torque_ratio_m(self) -> float: ...
    @property
    def rotational_drag_n_m_s(self) -> float: ...
    @property
    def linear_drag_n_s_m(self) -> float: ...

@final
class LanzonOuterLoop:
    def __new__(
        cls,
        *,
        k_p_xy: float | None = None,
        k_d_xy: float | None = None,
        k_p_z: float | None = None,
        k_d_z: float | None = None,
        max_tilt_rad: float | None = None,
        max_vertical_accel_m_s2: float | None = None,
    ) -> LanzonOuterLoop: ...
    @property
    def k_p_xy(self) -> float: ...
    @property
    def k_d_xy(self) -> float: ...
    @property
    def k_p_z(self) -> float: ...
    @property
    def k_d_z(self) -> float: ...
    @property
    def max_tilt_rad(self) -> float: ...
    @property
    def max_vertical_accel_m_s2(self) -> float: ...

@final
class LanzonController:
    def __new__(
        cls,
        *,
        model: LanzonModel,
        a_k: npt.NDArray[np.float64],
        b_k: npt.NDArray[np.float64],
        c_k: npt.NDArray[np.float64],
        d_k: npt.NDArray[np.float64],
        attitude_reference: list[float] | None = None,
        position: list[float] | None = None,
        outer_loop: LanzonOuterLoop | None = None,
    ) -> LanzonController: ...

@final
class FtcPreset:
    @staticmethod
    def from_toml_str(text: str, origin: str) -> FtcPreset: ...
    @property
    def name(self) -> str: ...
    @property
    def description(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def airframe(self) -> str: ...
    @property
    def gains(self) -> KeGains: ...
    @property
    def rotor_time_constant_s(self) -> float: ...
    @property
    def rotational_drag_n_m_s(self) -> float: ...
    @property
    def linear_drag_n_s_m(self) -> float: ...

def replay(
    controller: _Controller,
    times: _F64,
    states: _F64,
    command_count: int,
) -> _F64: ...
