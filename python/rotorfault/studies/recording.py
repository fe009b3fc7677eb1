"""A batch of recorded runs streamed to Parquet (:func:`record_batch`): the runs flown in chunks
(:func:`rotorfault.simulate_batch` on each), every chunk written as it finishes through the
studies' one writer (:func:`~rotorfault.studies.engine.run_chunks`: atomic chunk files, a
manifest, ``resume``/``force``), so the memory a batch takes is a few chunks', whatever its size.

One Parquet row per run: ``run`` (0-based), ``diverged``, ``divergence_time_s`` (NaN without a
divergence), then one list column per recorded signal, named as in
:meth:`rotorfault.Trajectory.to_arrow` (``t_s``, the states, quaternion, primary axis, commands,
thrusts, efficiencies, and the measured or estimated columns when the runs had them), holding
that run's rows (its own times, the divergence row included). Values are ``float64`` or
``float32`` (``dtype``); ``t_s`` is always ``float64``.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import RecordingDtype
from .._util.convert import count
from ..flight.faults import RotorFault
from ..flight.simulator import AnyController, PreparedBatch, Simulator, prepare_batch, recording_bytes
from ..flight.state import State
from ..flight.trajectory import RunViews
from .engine import StreamResult, run_chunks
from .storage import ChunkSpec, pyarrow_module

#: The manifest's ``kind`` of a streamed recording.
RECORDING_KIND = "rotorfault-recording"
#: Bytes of columns a chunk of runs aims at when ``chunk_runs`` is not given (two chunks are in
#: flight while a third is written, so a batch costs a few times this).
CHUNK_BYTES = 4 * 2**20


@dataclass(frozen=True)
class _RecordingTask:
    """Flies runs ``spec.start .. spec.stop`` of a prepared batch and returns their table (one
    row per run); each run keeps the seeds it has in one batch (``seed + i``)."""

    batch: PreparedBatch

    def __call__(self, spec: ChunkSpec) -> Any:
        return run_table(cast(RunViews, self.batch.fly(spec.start, spec.stop).trajectories), spec.start)


def run_table(runs: RunViews, first_run: int = 0) -> Any:
    """One row per run of ``runs`` (a batch's :attr:`~rotorfault.BatchResult.trajectories`):
    ``run`` (numbered from ``first_run``), ``diverged``, ``divergence_time_s`` and one list
    column per signal of :meth:`rotorfault.Trajectory.to_arrow`, gathered from the batch's
    columns without a per-run object."""
    pa = pyarrow_module()
    from .._util.tables import arrow_type

    flat, run = runs._flat()
    counts = np.bincount(run, minlength=len(runs))
    offsets = pa.array(np.concatenate([[0], np.cumsum(counts)]).astype(np.int32))
    divergences = runs._columns.divergences
    names = ["run", "diverged", "divergence_time_s"]
    arrays = [
        pa.array(np.arange(first_run, first_run + len(runs), dtype=np.int64)),
        pa.array(np.array([d is not None for d in divergences], dtype=bool)),
        pa.array(np.array([np.nan if d is None else d.time_s for d in divergences])),
    ]
    for name, kind, values in flat._table_columns():
        names.append(name)
        # The items named "element", as Parquet names them: the schema reads back unchanged.
        list_type = arrow_type(f"list<{kind}>")
        arrays.append(pa.ListArray.from_arrays(offsets, pa.array(np.ascontiguousarray(values), type=arrow_type(kind)), type=list_type))
    return pa.Table.from_arrays(arrays, names=names)


def _fingerprint(values: Iterable[Any]) -> str:
    digest = hashlib.sha256()
    for v in values:
        digest.update(repr(v).encode())
    return digest.hexdigest()


def record_batch(
    simulator: Simulator,
    x0s: Sequence[State],
    duration_s: float,
    *,
    out: str | os.PathLike[str],
    controllers: AnyController | Sequence[AnyController] = None,
    faults: Sequence[Iterable[RotorFault] | None] | None = None,
    initial_command: npt.ArrayLike | None = None,
    record_every: int = 1,
    dtype: RecordingDtype = "float64",
    chunk_runs: int | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool | None = None,
) -> StreamResult:
    """:func:`rotorfault.simulate_batch`'s runs written to the Parquet directory ``out`` as they
    finish, a chunk of ``chunk_runs`` runs per file (default: about :data:`CHUNK_BYTES` of
    columns a chunk), through the studies' one writer (``resume=True`` continues an interrupted
    output, ``force=True`` replaces one; the module docstring gives the table). Memory is a few
    chunks', whatever the number of runs; the values are those :func:`~rotorfault.simulate_batch`
    returns (``dtype``: ``"float64"`` or ``"float32"``). Every argument is checked before any
    run or file write. The output is identified for ``resume`` by the runs' settings, initial
    states, faults and the controllers' ``repr``. Read it back with
    :func:`rotorfault.studies.storage.iter_tables` (a chunk at a time) or ``pyarrow.parquet``.

    Examples:

        >>> import tempfile, pathlib, rotorfault as rf
        >>> from rotorfault.studies import record_batch
        >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
        >>> out = pathlib.Path(tempfile.mkdtemp()) / "runs"
        >>> result = record_batch(sim, [rf.State(position=(0, 0, -1))] * 3, 0.5, out=out, controllers=rf.lqr_hover(sim), chunk_runs=2)
        >>> result.total_rows, result.chunks
        (3, 2)
    """
    if out is None or not isinstance(out, (str, os.PathLike)):
        raise TypeError(f"out: expected a directory path, got {type(out).__name__}")
    batch = prepare_batch(simulator, x0s, duration_s, controllers=controllers, faults=faults,
                          initial_command=initial_command, record_every=record_every, dtype=dtype)
    if chunk_runs is None:
        per_run = max(1, recording_bytes(simulator, 1, batch.duration_s, batch.record_every, batch.dtype))
        chunk_runs = max(1, CHUNK_BYTES // per_run)
    chunk_runs = count("chunk_runs", chunk_runs)
    if chunk_runs < 1:
        raise ValueError(f"chunk_runs: must be at least 1, got {chunk_runs}")
    per_run_controllers = controllers if isinstance(controllers, (list, tuple)) else [controllers]
    arguments = {
        "runs": batch.runs,
        "duration_s": batch.duration_s,
        "record_every": batch.record_every,
        "dtype": batch.dtype,
        "settings": _fingerprint([simulator.airframe.to_toml(), simulator.dt_s, simulator.substeps, simulator.actuator,
                                  simulator.drag, simulator.wind, simulator.wind_profile, simulator.limits,
                                  simulator.noise, simulator.sensing, simulator.ground, simulator.ground_z_m]),
        "x0s": _fingerprint(batch.packed_states),
        "faults": _fingerprint(batch.packed_faults),
        "controllers": _fingerprint(per_run_controllers),
        "initial_command": _fingerprint(batch.starts),
    }
    return run_chunks(
        _RecordingTask(batch), total_rows=batch.runs, chunk_rows=chunk_runs, schema=_schema(batch), arguments=arguments,
        kind=RECORDING_KIND, out=out, metadata={"rotorfault_version": _rfcore.__version__, "row_order": "run index"},
        resume=resume, force=force, progress=progress, description=f"{batch.runs:,} runs", rows_field="runs",
    )


def _schema(batch: PreparedBatch) -> Any:
    """The table's schema: that of the first run flown for one control period (the columns do
    not depend on the length)."""
    sim = batch.simulator
    probe = prepare_batch(sim, [State(position=(0.0, 0.0, (sim.ground_z_m or 0.0) - 1.0))], sim.dt_s,
                          controllers=[None], dtype=batch.dtype)
    return _RecordingTask(probe)(ChunkSpec(0, 0, 1)).schema


__all__ = ["CHUNK_BYTES", "RECORDING_KIND", "record_batch", "run_table"]
