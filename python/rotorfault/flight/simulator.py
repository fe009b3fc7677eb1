"""The flight simulator: a Rust 6-DOF rigid body integrated with RK4, rotor actuators with lag,
saturation, rate limits and faults, drag and wind, closed by a controller at its own rate.

Frames: world NED (north, east, down; altitude is ``-position[2]``), body FRD. Rotor numbers in
faults are 1-based like the papers; arrays are ordered rotor 1..m.

The ground is the plane ``z = ground_z_m`` (default 0: altitude is height above the ground); the
centre of mass reaching it ends the run with a ``crashed`` event (time, impact speed, attitude).
There is no ground reaction, so a run starts above the ground; ``ground=False`` removes it.

What the controller flies on: the true state (default), the papers' relative noise on it
(``noise=``) or sensors with the estimator (``sensing=``, :data:`rotorfault.Sensing`); the
trajectory records the truth and, with sensing, the estimate beside it
(:attr:`~rotorfault.Trajectory.estimate`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any, TypeAlias, cast, get_args

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import BatchLanes, Controller, CoreController, RecordingDtype, core_controller_types
from .._util.convert import FloatArray, count, flag, float_array, real
from .._util.deprecation import dataclass_compat
from .._util.progress import chunks
from ..analysis.airframe import Airframe, require_airframe
from .faults import RotorFault, _faults
from .models import Drag, FixedPitchActuator, Noise, Sensing, VariablePitchActuator, sensing_with_offset
from .state import State, _vector3
from .trajectory import BatchResult, RunViews, Trajectory

#: A controller the simulator flies: a built-in one (anything with ``core(dt_s)``, see
#: :class:`rotorfault.control.Controller`), a Python callable ``f(t, x) -> commands`` (the slow
#: path) or ``None`` (all rotors at zero).
AnyController: TypeAlias = Controller | Callable[[float, FloatArray], npt.ArrayLike] | None

#: The Rust controller objects :func:`core_controller` can return (all can run in a batch): read
#: from the one registry the bindings expose (``rotorfault._rfcore.CONTROLLERS``).
CORE_TYPES: tuple[type, ...] = core_controller_types()


def core_controller(controller: AnyController, dt_s: float) -> CoreController | Callable[[float, FloatArray], npt.ArrayLike] | None:
    """The object the Rust loop runs for ``controller`` (``None``: all rotors at zero): a built-in
    controller's ``core(dt_s)``, or the callable itself."""
    if controller is None:
        return None
    core = getattr(controller, "core", None)
    if callable(core):
        return cast(Controller, controller).core(dt_s)
    if callable(controller):
        return controller
    names = ", ".join(cls.__name__ for cls in core_controller_types())
    raise TypeError(
        f"controller: expected {names} (anything with core(dt_s)), a callable f(t, x) or None, got {type(controller).__name__}"
    )


def trim_command(controller: object) -> FloatArray | None:
    """The trim command a controller holds, if any (the actuators start there); a controller
    flying another design until a known failure (``before_failure``) starts at that one's."""
    controller = getattr(controller, "before_failure", None) or controller
    u_trim = getattr(controller, "u_trim", None)
    return None if u_trim is None else np.asarray(u_trim, dtype=np.float64)


#: Largest ``h max(|omega|, 1 / time_constant)`` the simulator accepts, ``h = dt_s / substeps``
#: the RK4 substep: a run whose initial spin or actuator lag is faster is refused (``ValueError``
#: naming ``substeps`` and the numbers), and one whose body rate grows past ``MAX_RATE_STEP / h``
#: ends with a ``step-size`` event (a numerical cause, not the vehicle's).
MAX_RATE_STEP: float = _rfcore.MAX_RATE_STEP

#: Where :meth:`Simulator.run` starts when no ``x0`` is given: at rest, level, 10 m above a ground
#: at z = 0 (world NED).
DEFAULT_START_M = (0.0, 0.0, -10.0)

_DEFAULT_CONFIG = _rfcore.SimulationConfig()


#: A run ends with an event when it passes one of these (``math.inf``: no limit): the core's class,
#: used directly (keyword-only ``max_tilt_rad``, ``max_altitude_loss_m``, ``max_speed_m_s``,
#: ``max_rate_rad_s``; defaults from the core's ``Default``; values checked with the run's
#: settings; frozen, ``replace(**changes)``, ``FIELDS``).
DivergenceLimits = _rfcore.DivergenceLimits
dataclass_compat(DivergenceLimits)


def _check_duration(duration_s: Any, dt_s: float) -> float:
    duration = real("duration_s", duration_s)
    if not math.isfinite(duration):
        raise ValueError(f"duration_s: must be finite, got {duration}")
    if not duration >= dt_s:
        raise ValueError(f"duration_s: must be at least one control period (dt_s = {dt_s:g} s), got {duration:g}")
    return duration


class Simulator:
    """One airframe with its actuators, drag and wind, ready to fly controllers through faults.

    ``dt_s`` is the control period (s); the rigid body takes ``substeps`` RK4 steps per period.
    ``wind`` is a constant world-frame (NED) wind in m/s; ``wind_profile`` an optional sequence of
    ``(time_s, (n, e, d))`` points added to it, interpolated linearly (times not decreasing; a
    time given twice is a step: ``[(1.0, (0, 0, 0)), (1.0, (4, 4, 0))]`` is 4 m/s from 1 s on,
    exactly). The ground is the plane
    ``z = ground_z_m`` (world NED, m; default the core's, 0); ``ground=False``: no ground.
    ``ground_z_m`` holds the ground in effect (``None`` without one). The controller flies on the
    true state, on it with the papers' ``noise``, or on ``sensing`` (sensors and the estimator; a
    :data:`rotorfault.Sensing`); one of the two at most.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> controller = rf.lqr_hover(sim, position=(0, 0, -1))
        >>> run = sim.run(rf.State(position=(0.5, 0, -1)), 3.0, controller=controller)
        >>> run.events, round(float(run.position[-1, 0]), 3), float(run.t[-1])
        ([], 0.091, 3.0)
    """

    def __init__(
        self,
        airframe: Airframe,
        *,
        dt_s: float = _DEFAULT_CONFIG.dt_s,
        substeps: int = _DEFAULT_CONFIG.substeps,
        drag: Drag | None = None,
        wind: npt.ArrayLike = (0.0, 0.0, 0.0),
        wind_profile: Sequence[tuple[float, npt.ArrayLike]] | None = None,
        actuator: FixedPitchActuator | VariablePitchActuator | None = None,
        limits: DivergenceLimits | None = None,
        noise: Noise | None = None,
        ground_z_m: float | None = None,
        ground: bool = True,
        sensing: Sensing | None = None,
    ) -> None:
        self.airframe = require_airframe(airframe)
        self.dt_s = real("dt_s", dt_s)
        self.substeps = count("substeps", substeps)
        self.drag = Drag() if drag is None else drag
        if not isinstance(self.drag, Drag):
            raise TypeError(f"drag: expected rotorfault.Drag, got {type(drag).__name__}")
        self.wind = _vector3("wind", wind)
        self.wind_profile = [
            (real(f"wind_profile[{k}].time", t), _vector3(f"wind_profile[{k}]", w))
            for k, (t, w) in enumerate(wind_profile or [])
        ]
        self.actuator = FixedPitchActuator() if actuator is None else actuator
        if not isinstance(self.actuator, (FixedPitchActuator, VariablePitchActuator)):
            raise TypeError(f"actuator: expected FixedPitchActuator or VariablePitchActuator, got {type(actuator).__name__}")
        self.limits = DivergenceLimits() if limits is None else limits
        if not isinstance(self.limits, DivergenceLimits):
            raise TypeError(f"limits: expected rotorfault.DivergenceLimits, got {type(limits).__name__}")
        if noise is not None and not isinstance(noise, Noise):
            raise TypeError(f"noise: expected rotorfault.Noise, got {type(noise).__name__}")
        self.noise = noise
        if sensing is not None and not isinstance(sensing, Sensing):
            raise TypeError(f"sensing: expected rotorfault.Sensing, got {type(sensing).__name__}")
        self.sensing = sensing
        self.ground = flag("ground", ground)
        self.ground_z_m: float | None = None if ground_z_m is None else real("ground_z_m", ground_z_m)
        # Fail early on bad parameters: the core validates them in a zero-length run (from above
        # the ground). (Every run rebuilds the core objects from these attributes, so changing one
        # later takes effect.)
        config = self._config(0.0)
        self.ground_z_m = config.ground_z_m
        above = State(position=(0.0, 0.0, (self.ground_z_m or 0.0) - 1.0))
        _rfcore.simulate(
            self.airframe._core, self.actuator, self.drag, None, above._packed(), [],
            self.airframe.efficiency, None, config,
        )

    @property
    def command_count(self) -> int:
        """Commands per control step: one per rotor (thrust) or two (speed, pitch)."""
        per_rotor = 2 if isinstance(self.actuator, VariablePitchActuator) else 1
        return per_rotor * self.airframe.rotor_count

    def _config(self, duration_s: float, record_every: int = 1, seed_offset: int = 0) -> _rfcore.SimulationConfig:
        """The core's run settings; ``seed_offset`` shifts the noise and sensing seeds (run ``i``
        of a batch uses ``seed + i``, so a batch sent in chunks flies every run exactly as one call
        would)."""
        return _rfcore.SimulationConfig(
            dt_s=self.dt_s,
            substeps=self.substeps,
            duration_s=real("duration_s", duration_s),
            limits=self.limits,
            ground_z_m=self.ground_z_m,
            ground=self.ground,
            wind_m_s=self.wind,
            wind_profile=self.wind_profile,
            noise=None if self.noise is None else self.noise._core(seed_offset),
            sensing=None if self.sensing is None else sensing_with_offset(self.sensing, seed_offset),
            record_every=count("record_every", record_every),
        )

    def _start(self, controller: AnyController, initial_command: npt.ArrayLike | None) -> FloatArray | None:
        if initial_command is not None:
            return float_array("initial_command", initial_command, 1)
        trim = trim_command(controller)
        # A trim of the wrong length is the controller's error; the core reports it as such.
        return trim if trim is not None and trim.shape == (self.command_count,) else None

    def run(
        self,
        x0: State | None = None,
        duration_s: float = 10.0,
        *,
        controller: AnyController = None,
        faults: Iterable[RotorFault] | None = None,
        initial_command: npt.ArrayLike | None = None,
        record_every: int = 1,
    ) -> Trajectory:
        """Flies from ``x0`` (default: at rest, level, at :data:`DEFAULT_START_M`, 10 m up) for
        ``duration_s`` seconds; a start on or below the ground is refused. The actuators start settled at
        ``initial_command`` (default: the controller's trim command if it has one, else zero).
        Rotor efficiency starts at the airframe's own; ``faults`` change it on schedule.
        ``record_every`` keeps every n-th control step (plus the last and any divergence)."""
        x0 = State(position=DEFAULT_START_M) if x0 is None else x0
        if not isinstance(x0, State):
            raise TypeError(f"x0: expected rotorfault.State, got {type(x0).__name__}")
        duration_s = _check_duration(duration_s, self.dt_s)
        fault_list = _faults(faults, duration_s)
        core = core_controller(controller, self.dt_s)
        start = self._start(controller, initial_command)
        config = self._config(duration_s, record_every)
        # Made once, as this Trajectory: the core's record goes straight to its constructor.
        run: Trajectory = _rfcore.simulate(
            self.airframe._core,
            self.actuator,
            self.drag,
            core,
            x0._packed(),
            [f._packed() for f in fault_list],
            self.airframe.efficiency,
            start,
            config,
            trajectory_type=Trajectory,
            extra={"faults": fault_list},
        )
        return run

    def state_derivative(self, x: npt.ArrayLike, command: npt.ArrayLike, efficiency: npt.ArrayLike | None = None) -> FloatArray:
        """d/dt of the 12-element state vector with the actuators settled at ``command`` (clamped to
        its bounds, as the actuators do) and rotor ``efficiency`` (default: the airframe's own), in
        the constant ``wind`` (``wind_profile`` is a time-varying disturbance and is left out): the
        model :func:`rotorfault.control.lqr.hover_trim` balances and ``linearize`` differentiates."""
        eff = self.airframe.efficiency if efficiency is None else float_array("efficiency", efficiency, 1)
        return _rfcore.state_derivative(
            self.airframe._core,
            self.actuator,
            self.drag,
            list(float_array("x", x, 1)),
            float_array("command", command, 1),
            eff,
            list(self.wind),
        )


#: Values one recorded row holds per run in a batch's columns (:func:`simulate_batch`): position,
#: velocity, quaternion, Euler angles, body rates and primary axis (19), then per command channel
#: one and per rotor two (thrust, efficiency); sensor noise adds the 12 measured states, sensing
#: the 31 of the estimate (13 packed, 3 Euler angles, 15 sigmas) and two flags. Each run's slot
#: has one row more than the recording grid (an off-grid divergence row).
ROW_VALUES_FIXED = 19
ROW_VALUES_NOISE = 12
ROW_VALUES_SENSING = 31


def recording_bytes(simulator: Simulator, runs: int, duration_s: float, record_every: int = 1, dtype: RecordingDtype = "float64") -> int:
    """Memory the columns of a :func:`simulate_batch` of ``runs`` runs take (bytes): slots of
    recorded rows times the values of a row (:data:`ROW_VALUES_FIXED` and the command, thrust and
    efficiency channels, sensor noise, sensing) times 8 bytes (``float64``) or 4 (``float32``)."""
    steps = math.ceil(duration_s / simulator.dt_s - 1e-9)
    rows = steps // max(record_every, 1) + 3
    values = ROW_VALUES_FIXED + simulator.command_count + 2 * simulator.airframe.rotor_count
    values += ROW_VALUES_NOISE if simulator.noise is not None else 0
    values += ROW_VALUES_SENSING if simulator.sensing is not None else 0
    flags = 2 if simulator.sensing is not None else 0
    return int(runs * rows * (values * _ITEM_BYTES[dtype] + flags))


_ITEM_BYTES = {"float64": 8, "float32": 4}


def check_dtype(dtype: Any) -> RecordingDtype:
    """``dtype`` checked: one of :data:`rotorfault._typing.RecordingDtype`."""
    if not isinstance(dtype, str):
        raise TypeError(f"dtype: expected a string ('float64' or 'float32'), got {type(dtype).__name__}")
    if dtype not in get_args(RecordingDtype):
        raise ValueError(f"dtype: must be 'float64' or 'float32', got {dtype!r}")
    return cast(RecordingDtype, dtype)


def check_lanes(lanes: Any) -> BatchLanes:
    """``lanes`` checked: one of :data:`rotorfault._typing.BatchLanes`."""
    if not isinstance(lanes, str):
        raise TypeError(f"lanes: expected a string (one of {', '.join(get_args(BatchLanes))}), got {type(lanes).__name__}")
    if lanes not in get_args(BatchLanes):
        raise ValueError(f"lanes: must be one of {', '.join(get_args(BatchLanes))}, got {lanes!r}")
    return cast(BatchLanes, lanes)


def available_memory_bytes() -> int:
    """Memory available to new allocations (``MemAvailable`` on Linux, else total physical)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def _check_memory(simulator: Simulator, runs: int, duration_s: float, record_every: int, budget: int | None, dtype: RecordingDtype) -> None:
    if budget is None:
        budget = available_memory_bytes() // 2
    else:
        budget = count("memory_budget_bytes", budget)
    need = recording_bytes(simulator, runs, duration_s, record_every, dtype)
    if need > budget:
        raise ValueError(
            f"memory_budget_bytes: recording {runs:,} runs of {duration_s:g} s with record_every={record_every} "
            f"needs about {need / 2**30:.2f} GiB, more than the budget of {budget / 2**30:.2f} GiB "
            f"(default: half the available memory): record less (record_every), fewer runs per call, "
            f"float32 storage (dtype), stream the runs to Parquet (rotorfault.studies.record_batch), "
            f"or keep per-run summaries only (rotorfault.studies.run_campaign)"
        )


def simulate_batch(
    simulator: Simulator,
    x0s: Sequence[State],
    duration_s: float,
    *,
    controllers: AnyController | Sequence[AnyController] = None,
    faults: Sequence[Iterable[RotorFault] | None] | None = None,
    initial_command: npt.ArrayLike | None = None,
    record_every: int = 1,
    progress: bool | None = None,
    memory_budget_bytes: int | None = None,
    dtype: RecordingDtype = "float64",
    lanes: BatchLanes = "auto",
) -> BatchResult:
    """Many runs in parallel (Rust threads, GIL released). ``controllers`` is one controller for
    every run or a sequence with one per run; ``faults`` one fault list per run. Python callables
    cannot run in a batch (they would serialise on the GIL). ``record_every`` thins what is
    recorded (every n-th control step, plus the last and any divergence): large batches need it
    to keep memory bounded; the stacked arrays then sit on the thinned grid ``BatchResult.t``
    (times, not step indices; see :class:`BatchResult`). ``dtype``: ``"float64"`` (default) or
    ``"float32"`` (half the memory; every value rounded to nearest). The core records into one
    buffer per signal for the whole batch, handed to NumPy without a copy
    (:attr:`BatchResult.columns`); the stacked arrays are views of it and each run's
    :class:`Trajectory` is built on demand from views. ``progress=True`` shows a progress bar
    (runs done, rate, ETA) on standard error; the runs then go to the core in chunks, with
    identical results. ``memory_budget_bytes`` (default: half the available memory): a batch
    whose recordings would need more is refused up front with the estimate (see
    :func:`recording_bytes`); a batch larger than memory streams to Parquet with
    :func:`rotorfault.studies.record_batch`. ``lanes``: ``"auto"`` (default) flies groups of four
    runs in one AVX2 register where the batch allows it (Rust controllers, no sensor noise,
    constant wind, fixed-pitch rotors without a rate limit, no quadratic drag or rotor inertia;
    runs grouped by equal fault times; on sensors the truth flies in the lanes and, on motion
    capture and RTK, so do the truth the sensors read, their schedule and the runs' estimators,
    each run's sensors drawing their own noise), with results equal bit for bit to
    ``"scalar"``, one run at a time; ``"portable"`` flies the same groups in the build a CPU
    without AVX2 runs (the same results again: to check on one machine that they do not depend
    on AVX2).

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> starts = [rf.State(position=(0, 0, -1)), rf.State(position=(0.5, 0, -1))]
        >>> batch = rf.simulate_batch(sim, starts, 2.0, controllers=rf.lqr_hover(sim), record_every=40)
        >>> batch.position.shape, batch.diverged.tolist()
        ((2, 21, 3), [False, False])
    """
    batch = prepare_batch(simulator, x0s, duration_s, controllers=controllers, faults=faults,
                          initial_command=initial_command, record_every=record_every, dtype=dtype,
                          lanes=lanes)
    _check_memory(simulator, batch.runs, batch.duration_s, batch.record_every, memory_budget_bytes, batch.dtype)
    return batch.fly(0, batch.runs, progress=progress)


@dataclass(frozen=True)
class PreparedBatch:
    """A batch's runs checked and packed for the core (:func:`prepare_batch`), flown a slice
    of runs at a time by :meth:`fly` (run ``i`` keeps its seeds, ``seed + i``, in any slice)."""

    simulator: Simulator
    duration_s: float
    record_every: int
    dtype: RecordingDtype
    cores: list[CoreController | None]
    starts: list[list[float] | None]
    packed_states: list[Any]
    packed_faults: list[list[Any]]
    fault_lists: list[tuple[RotorFault, ...]]
    lanes: BatchLanes = "auto"

    @property
    def runs(self) -> int:
        return len(self.cores)

    def fly(self, first: int, last: int, *, progress: bool | None = None) -> BatchResult:
        """Runs ``first .. last - 1`` recorded into columns (``progress``: in chunks, with a bar)."""
        sim, n = self.simulator, last - first
        # Chunks of a few runs per thread keep the bar moving and cost nothing measurable.
        size = max(n, 1) if not progress else max(8 * (os.cpu_count() or 1), n // 100)
        parts: list[Any] = []
        for a, b in chunks(n, size, description=f"{n:,} runs", show=progress):
            a, b = first + a, first + b
            parts.append(_rfcore.simulate_batch_columns(
                sim.airframe._core, sim.actuator, sim.drag, self.cores[a:b], self.packed_states[a:b],
                self.packed_faults[a:b], sim.airframe.efficiency, self.starts[a:b],
                sim._config(self.duration_s, self.record_every, seed_offset=a), self.dtype, self.lanes,
            ))
        grid = sim._config(self.duration_s, self.record_every).record_times()
        if not parts:  # no runs
            parts.append(_rfcore.simulate_batch_columns(
                sim.airframe._core, sim.actuator, sim.drag, [], [], [], sim.airframe.efficiency, [],
                sim._config(self.duration_s, self.record_every), self.dtype, self.lanes,
            ))
        columns = parts[0] if len(parts) == 1 else _JoinedColumns(parts, n, len(grid))
        return BatchResult._from_columns(grid, columns, tuple(self.fault_lists[first:last]))


def prepare_batch(
    simulator: Simulator,
    x0s: Sequence[State],
    duration_s: float,
    *,
    controllers: AnyController | Sequence[AnyController] = None,
    faults: Sequence[Iterable[RotorFault] | None] | None = None,
    initial_command: npt.ArrayLike | None = None,
    record_every: int = 1,
    dtype: RecordingDtype = "float64",
    lanes: BatchLanes = "auto",
) -> PreparedBatch:
    """Every check of :func:`simulate_batch` but the memory budget, before any run: the runs
    packed for the core."""
    if not isinstance(simulator, Simulator):
        raise TypeError(f"simulator: expected rotorfault.Simulator, got {type(simulator).__name__}")
    dtype = check_dtype(dtype)
    lanes = check_lanes(lanes)
    states = list(x0s)
    n = len(states)
    for s in states:
        if not isinstance(s, State):
            raise TypeError(f"x0s: expected rotorfault.State items, got {type(s).__name__}")
    per_run: list[AnyController] = list(controllers) if isinstance(controllers, (list, tuple)) else [controllers] * n  # type: ignore[list-item]
    duration_s = _check_duration(duration_s, simulator.dt_s)
    fault_lists = [_faults(f, duration_s, f"faults[{i}]") for i, f in enumerate(faults if faults is not None else [None] * n)]
    if len(per_run) != n or len(fault_lists) != n:
        raise ValueError(f"controllers, faults: expected one entry per run ({n})")
    cores: list[CoreController | None] = []
    for c in per_run:
        core = core_controller(c, simulator.dt_s)
        if core is not None and not isinstance(core, core_controller_types()):
            raise TypeError("controllers: Python callables cannot run in a batch; use Simulator.run")
        cores.append(cast(CoreController | None, core))
    # Each run's actuators start at initial_command, else at its own controller's trim.
    starts: list[list[float] | None] = []
    for c in per_run:
        start = simulator._start(c, initial_command)
        starts.append(None if start is None else [float(v) for v in start])
    record_every = count("record_every", record_every)
    simulator._config(duration_s, record_every)  # checks the settings before any run
    return PreparedBatch(
        simulator, duration_s, record_every, dtype, cores, starts, [s._packed() for s in states],
        [[f._packed() for f in fl] for fl in fault_lists], fault_lists, lanes,
    )


#: The per-signal arrays of :class:`rotorfault._rfcore.BatchColumns` (runs on axis 0).
_BLOCKS = ("position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command", "rotor_thrust",
           "efficiency", "recorded_measurements", "estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated",
           "rows_on_grid", "off_grid_row")


class _JoinedColumns:
    """The columns of a batch sent to the core in chunks (``progress=True``): each chunk's
    arrays copied into one preallocated array per signal, so the whole batch costs its columns
    plus one chunk."""

    def __init__(self, parts: list[Any], runs: int, grid_rows: int) -> None:
        self.grid_rows = grid_rows
        for name in _BLOCKS:
            first = getattr(parts[0], name)
            out = np.empty((runs, *first.shape[1:]), dtype=first.dtype)
            at = 0
            for part in parts:
                block = getattr(part, name)
                out[at : at + len(block)] = block
                at += len(block)
            setattr(self, name, out)
        self.divergences = [d for part in parts for d in part.divergences]
        self.sensing_counts = [c for part in parts for c in part.sensing_counts]
        self.sensed = [s for part in parts for s in part.sensed]


def __getattr__(name: str) -> object:
    if name == "Event":  # the old rotorfault.simulation name of Divergence: warns (flight.trajectory)
        from . import trajectory

        return trajectory.Event
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "MAX_RATE_STEP",
    "AnyController",
    "DivergenceLimits",
    "Simulator",
    "available_memory_bytes",
    "core_controller",
    "recording_bytes",
    "simulate_batch",
    "trim_command",
]
