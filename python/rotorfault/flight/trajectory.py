"""What a flight returns: the :class:`Trajectory` of one run (sampled at the control rate, with
the :data:`Divergence` that ended it early, if any) and the :class:`BatchResult` of many."""

from __future__ import annotations

import operator
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Self, overload

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._util.convert import FloatArray
from .._util.deprecation import dataclass_compat, warn
from .._util.numeric import scaled_norm
from .._util.tables import Column, Tabular, arrow_table, pyarrow, schema_metadata
from .faults import RotorFault

if TYPE_CHECKING:
    from matplotlib.figure import Figure


#: The 12 states as table columns (:meth:`Trajectory.to_arrow`), in the state vector's order:
#: NED position and velocity, Z-Y-X Euler angles, body rates (FRD).
STATE_COLUMNS: tuple[str, ...] = (
    "north_m", "east_m", "down_m",
    "velocity_north_m_s", "velocity_east_m_s", "velocity_down_m_s",
    "roll_rad", "pitch_rad", "yaw_rad",
    "roll_rate_rad_s", "pitch_rate_rad_s", "yaw_rate_rad_s",
)


#: The filter's 15-element error state as table columns (its one-sigma ``Estimates.std`` in
#: :meth:`Trajectory.to_arrow`, each prefixed ``estimate_std_``): position and velocity (NED), the
#: attitude error and the gyro and accelerometer biases (body axes FRD: forward, right, down).
ERROR_STATE_COLUMNS: tuple[str, ...] = (
    "north_m", "east_m", "down_m",
    "velocity_north_m_s", "velocity_east_m_s", "velocity_down_m_s",
    "attitude_forward_rad", "attitude_right_rad", "attitude_down_rad",
    "gyro_bias_forward_rad_s", "gyro_bias_right_rad_s", "gyro_bias_down_rad_s",
    "accel_bias_forward_m_s2", "accel_bias_right_m_s2", "accel_bias_down_m_s2",
)


def command_columns(command_count: int, rotor_count: int) -> list[str]:
    """Names of the command channels: ``rotor_<i>_command_n`` (fixed pitch, one thrust per rotor)
    or ``rotor_<i>_speed_command`` and ``rotor_<i>_pitch_command_rad`` (variable pitch, interleaved;
    the speed in the preset's unit)."""
    if command_count == 2 * rotor_count:
        return [f"rotor_{j // 2 + 1}_{'pitch_command_rad' if j % 2 else 'speed_command'}" for j in range(command_count)]
    return [f"rotor_{j + 1}_command_n" for j in range(command_count)]


#: Why and when a run ended early (``Trajectory.divergence``; ``Trajectory.events`` lists it):
#: the core's class, used directly (see its page: ``time_s``, ``kind``, ``state``, and what is
#: derived from them, the description and a crash's impact).
Divergence = _rfcore.Divergence


class _EventType(type):
    """An old ``Event`` is any :data:`Divergence` (``isinstance`` keeps answering as before)."""

    def __instancecheck__(cls, obj: Any) -> bool:
        return isinstance(obj, _rfcore.Divergence)


class _Event(metaclass=_EventType):
    """The old ``rotorfault.Event`` (a Python copy of the core's divergence), kept one release
    behind a warning: its constructor ``Event(time, kind, description, state, impact_speed_m_s,
    impact_vertical_speed_m_s, impact_tilt_rad)`` (the old dataclass's order, by position or keyword)
    makes a :data:`Divergence` (the description and the impact, now derived from the kind and the
    state, must agree with them; ``None``, the old default, gives none)."""

    def __new__(  # type: ignore[misc]
        cls,
        time: float,
        kind: str,
        description: str | None = None,
        state: Any = None,
        impact_speed_m_s: float | None = None,
        impact_vertical_speed_m_s: float | None = None,
        impact_tilt_rad: float | None = None,
    ) -> Divergence:
        given = {"impact_speed_m_s": impact_speed_m_s, "impact_vertical_speed_m_s": impact_vertical_speed_m_s,
                 "impact_tilt_rad": impact_tilt_rad}
        impact: dict[str, Any] = {name: value for name, value in given.items() if value is not None}
        return _rfcore.Divergence(time_s=time, kind=kind, state=state, description=description, **impact)


def __getattr__(name: str) -> Any:
    if name == "Event":
        warn("rotorfault.Event", "rotorfault.Divergence (keywords: time_s, kind, state)")
        return _Event
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: What the estimator gave the controller beside the truth (``Trajectory.estimate``, a run with
#: :data:`rotorfault.Sensing`): the core's class, used directly (see its page).
Estimates = _rfcore.Estimates


def _divergence(events: Sequence[Divergence]) -> Divergence | None:
    """The divergence of a run constructed with ``events`` (at most one: a run ends once)."""
    if len(events) > 1:
        raise ValueError(f"events: a run ends at most once, got {len(events)} events")
    if not events:
        return None
    if not isinstance(events[0], _rfcore.Divergence):
        raise TypeError(f"events: expected rotorfault.Divergence items, got {type(events[0]).__name__}")
    return events[0]


def _estimate_fields(e: Estimates) -> dict[str, Any]:
    """The core's estimate fields of an :data:`Estimates` (the constructor's old ``estimate=``)."""
    if not isinstance(e, _rfcore.Estimates):
        raise TypeError(f"estimate: expected rotorfault.flight.Estimates, got {type(e).__name__}")
    return {"estimate_state": e.state, "estimate_euler": e.euler, "estimate_std": e.std, "gyro_saturated": e.gyro_saturated,
            "accel_saturated": e.accel_saturated, "sensing_counts": e.counts}


class Trajectory(_rfcore.Trajectory, Tabular):
    """A run sampled at the control rate. Arrays have one row per control step: ``t`` (s),
    ``position`` (NED, m), ``velocity`` (NED, m/s), ``quaternion``, ``euler`` (Z-Y-X roll, pitch,
    yaw in rad), ``omega`` (body rates p, q, r in rad/s), ``primary_axis`` (body z in the world
    frame, Ke's n3), ``rotor_command`` and ``rotor_thrust`` (N for fixed pitch; speed and pitch
    channels for variable pitch), ``efficiency`` (0 to 1, faults included),
    ``recorded_measurements`` (the core's sensor readings, empty without noise; see
    :attr:`measured`); ``sensed`` says what the controller flew on (``"truth"``,
    ``"paper-noise"`` or the sensor suite's name), ``events`` why it ended early, ``faults`` the
    faults it flew, ``estimate`` (with sensing) the estimate beside the truth.

    The core's trajectory itself (issue 26: no field-by-field copy): the arrays are made once, by
    the simulator or by the keyword-only constructor (the core's fields, shapes checked there;
    ``events``, ``faults`` and ``estimate`` as before), and this subclass adds only what reads
    them in Python: the derived arrays, the table, the plot. Frozen; picklable.

    ``to_arrow()`` / ``to_pandas()``: one row per recorded step (``t_s``, the 12 states of
    :data:`STATE_COLUMNS`, the quaternion, the primary axis, each rotor's command, thrust and
    efficiency, and the measured states ``measured_<state>`` when the run had sensor noise; with
    sensing the estimate beside the truth: ``estimate_<state>``, ``estimate_quaternion_<wxyz>``,
    the filter's one sigma ``estimate_std_<error state>`` of :data:`ERROR_STATE_COLUMNS` and the
    ``gyro_saturated`` / ``accel_saturated`` flags); what the controller flew on (``sensed``), the
    sensing counts, the events and faults are in the schema's metadata.

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> run = sim.run(rf.State(position=(0, 0, -1)), 0.5, controller=rf.lqr_hover(sim, position=(0, 0, -1)))
        >>> run.position.shape, list(run.to_arrow().column_names[:4])
        ((201, 3), ['t_s', 'north_m', 'east_m', 'down_m'])
    """

    __slots__ = ("faults",)

    #: The rotor faults the run flew (as given to :meth:`~rotorfault.Simulator.run`).
    faults: tuple[RotorFault, ...]
    #: The constructor's keywords: the core's fields and ``faults``.
    FIELDS: ClassVar[list[str]] = [*_rfcore.Trajectory.FIELDS, "faults"]

    def __new__(
        cls,
        *,
        events: Sequence[Divergence] | None = None,
        faults: Sequence[RotorFault] = (),
        estimate: Estimates | None = None,
        **core: Any,
    ) -> Self:
        if events is not None:
            core["divergence"] = _divergence(events)
        if estimate is not None:
            core.update(_estimate_fields(estimate))
        self = super().__new__(cls, **core)
        object.__setattr__(self, "faults", tuple(faults))
        return self

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"Trajectory is frozen: cannot set {name}")

    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, Any]]:
        return (), {name: getattr(self, name) for name in self.FIELDS}

    def __getstate__(self) -> None:
        return None  # everything is in the constructor's arguments

    @property
    def events(self) -> list[Divergence]:
        """Why and when the run ended early: its :data:`Divergence`, or none."""
        return [] if self.divergence is None else [self.divergence]

    @property
    def estimate_attitude_error_rad(self) -> FloatArray:
        """Per row, the angle between the estimated and the true attitude (rad); a run without
        sensing has none (``ValueError``)."""
        e = self._estimate("estimate_attitude_error_rad")
        dot = np.abs(np.einsum("ij,ij->i", e.quaternion, self.quaternion))
        out: FloatArray = 2.0 * np.arccos(np.clip(dot, 0.0, 1.0))
        return out

    @property
    def estimate_position_error_m(self) -> FloatArray:
        """Per row, the distance between the estimated and the true position (m)."""
        e = self._estimate("estimate_position_error_m")
        out: FloatArray = scaled_norm(e.position - self.position, axis=1)
        return out

    def _estimate(self, name: str) -> Estimates:
        estimate = self.estimate
        if estimate is None:
            raise ValueError(f"{name}: the run flew on {self.sensed}, without sensing there is no estimate")
        return estimate

    @property
    def measured(self) -> FloatArray:
        """What the controller saw: the 12-element state vector per step (with sensor noise; with
        sensing the estimate; otherwise the true state, built on demand). The divergence row is
        NaN."""
        estimate = self.estimate
        if estimate is not None:
            return estimate.vector
        if self.recorded_measurements.shape[1] > 0:
            return self.recorded_measurements
        measured = np.hstack([self.position, self.velocity, self.euler, self.omega])
        if self.diverged:
            measured[-1] = np.nan  # no command was computed at the divergence
        return measured

    @property
    def rotation(self) -> FloatArray:
        """Rotation matrices body -> world (N x 3 x 3) from the quaternions."""
        w, x, y, z = self.quaternion.T
        return np.stack(
            [
                np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
                np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
                np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
            ],
            axis=1,
        )

    def _table_columns(self) -> list[Column]:
        m = self.efficiency.shape[1]
        states = np.hstack([self.position, self.velocity, self.euler, self.omega])
        # A float32 recording (simulate_batch dtype) keeps its width in the table; time is float64.
        value_type = "float32" if self.position.dtype == np.float32 else "float64"
        columns: list[Column] = [("t_s", "float64", self.t)]
        columns += [(name, value_type, states[:, k]) for k, name in enumerate(STATE_COLUMNS)]
        columns += [(f"quaternion_{c}", value_type, self.quaternion[:, k]) for k, c in enumerate("wxyz")]
        columns += [(f"primary_axis_{c}", value_type, self.primary_axis[:, k]) for k, c in enumerate(("north", "east", "down"))]
        names = command_columns(self.rotor_command.shape[1], m)
        columns += [(name, value_type, self.rotor_command[:, k]) for k, name in enumerate(names)]
        columns += [(f"rotor_{k + 1}_thrust_n", value_type, self.rotor_thrust[:, k]) for k in range(m)]
        columns += [(f"rotor_{k + 1}_efficiency", value_type, self.efficiency[:, k]) for k in range(m)]
        if self.recorded_measurements.shape[1] > 0:
            columns += [(f"measured_{name}", value_type, self.recorded_measurements[:, k]) for k, name in enumerate(STATE_COLUMNS)]
        e = self.estimate
        if e is not None:
            estimated = e.vector
            columns += [(f"estimate_{name}", value_type, estimated[:, k]) for k, name in enumerate(STATE_COLUMNS)]
            columns += [(f"estimate_quaternion_{c}", value_type, e.quaternion[:, k]) for k, c in enumerate("wxyz")]
            columns += [(f"estimate_std_{name}", value_type, e.std[:, k]) for k, name in enumerate(ERROR_STATE_COLUMNS)]
            columns += [("gyro_saturated", "bool", e.gyro_saturated), ("accel_saturated", "bool", e.accel_saturated)]
        return columns

    def _table_title(self) -> str:
        events = self.events
        end = f"ended: {events[0]}" if events else "no divergence"
        return f"trajectory: {len(self.t)} steps to {self.t[-1]:g} s, {end}"

    def _table_metadata(self) -> dict[str, Any]:
        sensing = {}
        c = self.sensing_counts
        if c is not None:
            sensing = {"sensing_counts": {
                "imu_samples": c.imu_samples, "gyro_saturated_samples": c.gyro_saturated_samples,
                "accel_saturated_samples": c.accel_saturated_samples, "fused_measurements": c.fused_measurements,
                "rejected_measurements": c.rejected_measurements, "late_measurements": c.late_measurements,
                "thinned_measurements": c.thinned_measurements,
            }}
        return {
            "kind": "trajectory",
            "sensed": self.sensed,
            **sensing,
            "events": [{"kind": e.kind, "time_s": e.time_s, "description": e.description} for e in self.events],
            "faults": [{"rotor": f.rotor, "time_s": f.time, "efficiency": f.efficiency} for f in self.faults],
        }

    def plot(
        self,
        path: str | None = None,
        *,
        title: str | None = None,
        setpoints: Sequence[tuple[float, npt.ArrayLike]] | None = None,
    ) -> Figure:
        """Position (with the setpoint, if given as ``(time, NED position)`` steps), roll and
        pitch, yaw (wrapped, or its rate for a spinning vehicle), body rates and rotor thrusts
        against time, with fault and loss markers and, when the setpoints are given, the flight's
        verdict (:mod:`rotorfault.flight.outcomes`) in the title
        (:func:`rotorfault.plotting.timeseries.plot_trajectory`). Returns the figure (not
        registered with pyplot), saved to ``path`` (``.png``, ``.pdf`` or ``.svg``, written
        atomically) if given."""
        from ..plotting.timeseries import plot_trajectory
        from .outcomes import flight_metrics

        verdict = None
        if setpoints and len(self.t) >= 2:
            verdict = flight_metrics(self, _Setpoints(tuple(setpoints))).verdict_label
        return plot_trajectory(self, path, title=title, setpoints=setpoints, verdict=verdict)


dataclass_compat(Trajectory)


@dataclass(frozen=True)
class _Setpoints:
    """What :func:`~rotorfault.flight.outcomes.flight_metrics` reads of a scenario."""

    setpoints: tuple[tuple[float, npt.ArrayLike], ...]


class RunViews(Sequence[Trajectory]):
    """A batch's runs as :class:`Trajectory` objects, each built when asked for from views of the
    batch's columns (no copy; a run whose divergence row lies between two grid times joins that
    row to its grid rows, a copy of that run alone). Indexing, slicing, ``len`` and iteration
    work as on a list; the arrays are read-only (they are the batch's)."""

    def __init__(self, grid: FloatArray, columns: Any, faults: tuple[tuple[RotorFault, ...], ...]) -> None:
        self._grid = grid
        self._columns = columns
        self._faults = faults

    def __len__(self) -> int:
        return len(self._faults)

    @overload
    def __getitem__(self, index: int) -> Trajectory: ...
    @overload
    def __getitem__(self, index: slice) -> list[Trajectory]: ...
    def __getitem__(self, index: int | slice) -> Trajectory | list[Trajectory]:
        if isinstance(index, slice):
            return [self._run(i) for i in range(*index.indices(len(self)))]
        i = operator.index(index)
        if not -len(self) <= i < len(self):
            raise IndexError(f"run {i} out of range for a batch of {len(self)} runs")
        return self._run(i % len(self))

    def _run(self, i: int) -> Trajectory:
        c = self._columns
        k, off, last = int(c.rows_on_grid[i]), bool(c.off_grid_row[i]), c.grid_rows

        def rows(block: Any) -> Any:
            if not off:
                return block[i, :k]
            return np.concatenate([block[i, :k], block[i, last : last + 1]])

        divergence = c.divergences[i]
        t = self._grid[:k] if not off else np.append(self._grid[:k], divergence.time_s)
        return Trajectory(
            t=t, **self._signals(rows), divergence=divergence, faults=self._faults[i], sensed=c.sensed[i],
            **(self._estimate_signals(rows, c.sensing_counts[i]) if c.sensing_counts[i] is not None else {}),
        )

    def _signals(self, rows: Any) -> dict[str, Any]:
        """The core trajectory's arrays of a run (or of every run, flat) by ``rows`` of each column."""
        c = self._columns
        return {
            "position": rows(c.position), "velocity": rows(c.velocity), "quaternion": rows(c.quaternion),
            "euler": rows(c.euler), "omega": rows(c.omega), "primary_axis": rows(c.primary_axis),
            "rotor_command": rows(c.rotor_command), "rotor_thrust": rows(c.rotor_thrust), "efficiency": rows(c.efficiency),
            "recorded_measurements": rows(c.recorded_measurements),
        }

    def _estimate_signals(self, rows: Any, counts: _rfcore.SensingCounts) -> dict[str, Any]:
        """The core trajectory's estimate fields by ``rows`` of each column (a run with sensing)."""
        c = self._columns
        return {
            "estimate_state": rows(c.estimate_state), "estimate_euler": rows(c.estimate_euler),
            "estimate_std": rows(c.estimate_std), "gyro_saturated": rows(c.gyro_saturated),
            "accel_saturated": rows(c.accel_saturated), "sensing_counts": counts,
        }

    def _flat(self) -> tuple[Trajectory, np.ndarray[Any, np.dtype[np.int64]]]:
        """Every run's rows one after another, as one :class:`Trajectory` (its arrays only), and
        the run each row belongs to: what a table of the whole batch is made of, gathered per
        signal without a per-run object."""
        c = self._columns
        n, slot = len(self), c.grid_rows + 1
        counts = np.asarray(c.rows_on_grid, dtype=np.int64) + np.asarray(c.off_grid_row, dtype=np.int64)
        run = np.repeat(np.arange(n, dtype=np.int64), counts)
        starts = np.cumsum(counts) - counts
        within = np.arange(len(run), dtype=np.int64) - np.repeat(starts, counts)
        # A run's off-grid divergence row is its last row, kept in the slot's last row.
        off_row = np.repeat(np.asarray(c.off_grid_row, dtype=bool), counts) & (within == np.repeat(counts - 1, counts))
        slot_row = np.where(off_row, c.grid_rows, within)
        flat_index = run * slot + slot_row
        times = np.append(self._grid, np.nan)[slot_row]
        divergence_times = np.array([np.nan if d is None else d.time_s for d in c.divergences])
        times[off_row] = divergence_times[run[off_row]]

        def rows(block: Any) -> Any:
            return block.reshape(n * slot, *block.shape[2:])[flat_index]

        sensing = next((x for x in c.sensing_counts if x is not None), None)
        flat = Trajectory(t=times, **self._signals(rows), **(self._estimate_signals(rows, sensing) if sensing is not None else {}))
        return flat, run


@dataclass(frozen=True)
class BatchResult(Tabular):
    """Runs stacked along axis 0 on one time axis ``t``, the recording grid: the recorded control
    steps (``k dt_s`` for every ``record_every``-th ``k``) and the end, exactly ``duration_s``;
    equal to the ``t`` of every run that does not diverge. A run that diverges fills the rows up
    to its last recorded step before the divergence and NaN after: its divergence row, at the
    located crossing time, is stacked only when that time is a grid time (never into a row of
    another time); it is always the last row of ``trajectories[i]``, and ``divergence_time[i]``
    is its time. The arrays are :class:`Trajectory`'s with a leading run axis: ``position`` (NED,
    m), ``velocity`` (NED, m/s), ``omega`` (body rates, rad/s), ``t`` (s); from
    :func:`~rotorfault.simulate_batch` they are read-only views of the batch's columns
    (``columns``: one array per signal, ``runs x (grid rows + 1) x width``, the last row of a
    run's slot holding a divergence row off the grid), and ``trajectories`` builds each run's
    :class:`Trajectory` from views when asked (:class:`RunViews`).

    Examples:

        >>> import rotorfault as rf
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> controller = rf.lqr_hover(sim, position=(0, 0, -1))
        >>> batch = rf.simulate_batch(sim, [rf.State(position=(0, 0, -1))] * 2, 1.0, controllers=controller, record_every=100)
        >>> batch.t.tolist(), len(batch.trajectories)
        ([0.0, 0.25, 0.5, 0.75, 1.0], 2)
    """

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    euler: FloatArray
    omega: FloatArray
    rotor_thrust: FloatArray
    efficiency: FloatArray
    diverged: np.ndarray[Any, np.dtype[np.bool_]]
    divergence_time: FloatArray
    trajectories: Sequence[Trajectory]
    #: The core's columns (:class:`rotorfault._rfcore.BatchColumns`), or ``None`` for a batch
    #: assembled from trajectories.
    columns: Any = None

    @classmethod
    def _from_columns(cls, grid: FloatArray, columns: Any, faults: tuple[tuple[RotorFault, ...], ...]) -> BatchResult:
        for name in ("position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command", "rotor_thrust",
                     "efficiency", "recorded_measurements", "estimate_state", "estimate_euler", "estimate_std",
                     "gyro_saturated", "accel_saturated"):
            getattr(columns, name).flags.writeable = False  # views of it are handed out
        g = len(grid)
        return cls(
            t=grid,
            position=columns.position[:, :g],
            velocity=columns.velocity[:, :g],
            euler=columns.euler[:, :g],
            omega=columns.omega[:, :g],
            rotor_thrust=columns.rotor_thrust[:, :g],
            efficiency=columns.efficiency[:, :g],
            diverged=np.array([d is not None for d in columns.divergences], dtype=bool),
            divergence_time=np.array([np.nan if d is None else d.time_s for d in columns.divergences]),
            trajectories=RunViews(grid, columns, faults),
            columns=columns,
        )

    def to_arrow(self) -> Any:
        """Every run's :meth:`Trajectory.to_arrow` rows, one table: a ``run`` column (0-based, the
        index into ``trajectories``) first, then one row per recorded step of that run (its own
        times, the divergence row included; no padding)."""
        pa = pyarrow()
        if not len(self.trajectories):
            return arrow_table([("run", "int64", [])], metadata={"kind": "batch"})
        meta = {"kind": "batch", "runs": len(self.trajectories), "diverged": [bool(d) for d in self.diverged]}
        if isinstance(self.trajectories, RunViews):
            flat, run = self.trajectories._flat()
            table = arrow_table(flat._table_columns())
            table = table.add_column(0, pa.field("run", pa.int64()), pa.array(run))
            return table.replace_schema_metadata(schema_metadata(meta))
        tables = []
        for k, one in enumerate(self.trajectories):
            table = arrow_table(one._table_columns())
            tables.append(table.add_column(0, pa.field("run", pa.int64()), pa.array(np.full(table.num_rows, k, dtype=np.int64))))
        return pa.concat_tables(tables).replace_schema_metadata(schema_metadata(meta))

    def _table_title(self) -> str:
        return f"batch: {len(self.trajectories)} runs, {int(np.sum(self.diverged))} diverged"


__all__ = ["ERROR_STATE_COLUMNS", "STATE_COLUMNS", "BatchResult", "Divergence", "Estimates", "RunViews", "Trajectory", "command_columns"]
