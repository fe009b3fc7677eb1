"""A batch recorded into columns (one buffer per signal, runs viewed lazily) holds exactly the
values the per-run path (``_rfcore.simulate_batch``, one ``Trajectory`` per run) records:
truth, sensor noise and sensing, a divergence row on and off the recording grid; float32
storage is float64 rounded to nearest; ``record_every`` keeps the right rows."""

from __future__ import annotations

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.flight.trajectory import Estimates, RunViews, Trajectory


def _runs(sim: rf.Simulator) -> tuple[list[rf.State], list[object]]:
    hold = rf.lqr_hover(sim, position=(0, 0, -1))
    # Run 1 flies nothing and crashes at 0.452 s, between two grid times at record_every=7.
    return [rf.State(position=(0.3, 0, -1)), rf.State(position=(0, 0, -1)), rf.State(position=(0, 0.2, -1))], [hold, None, hold]


def _per_run(sim: rf.Simulator, x0s: list[rf.State], controllers: list[object], duration_s: float, record_every: int) -> list[Trajectory]:
    """The per-run path: one core ``Trajectory`` per run, converted one by one."""
    cores = [None if c is None else c.core(sim.dt_s) for c in controllers]  # type: ignore[attr-defined]
    starts = [None if (s := sim._start(c, None)) is None else list(s) for c in controllers]  # type: ignore[arg-type]
    raws = _rfcore.simulate_batch(sim.airframe._core, sim.actuator, sim.drag, cores, [x._packed() for x in x0s],
                                  [[] for _ in x0s], sim.airframe.efficiency, starts, sim._config(duration_s, record_every))
    return [Trajectory(**{name: getattr(raw, name) for name in raw.FIELDS}) for raw in raws]


def _assert_same(new: Trajectory, old: Trajectory) -> None:
    for name in Trajectory.FIELDS:
        a, b = getattr(new, name), getattr(old, name)
        if isinstance(b, np.ndarray):
            assert a.shape == b.shape and a.dtype == b.dtype, name
            np.testing.assert_array_equal(a, b, err_msg=name)
        elif isinstance(b, _rfcore.Divergence):
            assert (a.time_s, a.kind) == (b.time_s, b.kind), name
            np.testing.assert_array_equal(a.state, b.state, err_msg=name)
        elif isinstance(b, _rfcore.SensingCounts):
            assert a.__getnewargs_ex__() == b.__getnewargs_ex__(), name
        else:
            assert a == b, name
    assert [(e.time_s, e.kind, e.description, e.impact_speed_m_s) for e in new.events] == [(e.time_s, e.kind, e.description, e.impact_speed_m_s) for e in old.events]
    for e, g in zip(new.events, old.events):
        np.testing.assert_array_equal(e.state, g.state)
    if old.estimate is not None:
        assert new.estimate is not None
        for name in Estimates.FIELDS:
            x, y = getattr(new.estimate, name), getattr(old.estimate, name)
            if isinstance(y, np.ndarray):
                np.testing.assert_array_equal(x, y, err_msg=name)


@pytest.mark.parametrize("setup", ["truth", "noise", "sensing"])
def test_columns_hold_the_per_run_values_exactly(setup: str) -> None:
    frame = rf.Airframe.preset("quad-x")
    extra = {"noise": rf.Noise(snr_db=20.0, seed=3)} if setup == "noise" else {"sensing": rf.Sensing(suite="mocap")} if setup == "sensing" else {}
    sim = rf.Simulator(frame, **extra)  # type: ignore[arg-type]
    x0s, controllers = _runs(sim)
    batch = rf.simulate_batch(sim, x0s, 0.6, controllers=controllers, record_every=7)
    old = _per_run(sim, x0s, controllers, 0.6, 7)
    assert isinstance(batch.trajectories, RunViews) and len(batch.trajectories) == 3
    assert batch.diverged.tolist() == [False, True, False]
    assert batch.columns.off_grid_row.tolist() == [False, True, False]  # the crash is between grid times
    for new, before in zip(batch.trajectories, old):
        _assert_same(new, before)
    # The stacked arrays: each run's grid rows, NaN after (the off-grid crash row is not stacked).
    crash_rows = int(batch.columns.rows_on_grid[1])
    np.testing.assert_array_equal(batch.position[1, :crash_rows], old[1].position[:crash_rows])
    assert np.isnan(batch.position[1, crash_rows:]).all()
    np.testing.assert_array_equal(batch.position[0], old[0].position)
    # The batch's table is the per-run tables one after another.
    table = batch.to_arrow()
    assert table.num_rows == sum(len(t.t) for t in old)
    first = old[1].to_arrow()
    rows = table.filter(table.column("run").to_numpy() == 1).drop_columns(["run"])
    assert rows.column_names == first.column_names
    for name in first.column_names:
        np.testing.assert_array_equal(rows.column(name).to_numpy(), first.column(name).to_numpy(), err_msg=name)
    with pytest.raises(ValueError, match="read-only"):
        batch.trajectories[0].position[0, 0] = 1.0  # views of the batch: never silently shared writes


def test_chunked_batch_equals_one_call() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), noise=rf.Noise(snr_db=20.0, seed=5))
    x0s, controllers = _runs(sim)
    one = rf.simulate_batch(sim, x0s * 6, 0.3, controllers=controllers * 6, record_every=3)
    chunked = rf.simulate_batch(sim, x0s * 6, 0.3, controllers=controllers * 6, record_every=3, progress=True)
    for name in ("position", "omega", "efficiency"):
        np.testing.assert_array_equal(getattr(one, name), getattr(chunked, name))
    _assert_same(chunked.trajectories[-2], one.trajectories[-2])


def test_float32_storage_is_float64_rounded() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    x0s, controllers = _runs(sim)
    wide = rf.simulate_batch(sim, x0s, 0.6, controllers=controllers, record_every=7)
    narrow = rf.simulate_batch(sim, x0s, 0.6, controllers=controllers, record_every=7, dtype="float32")
    for name in ("position", "velocity", "quaternion", "euler", "omega", "rotor_command", "rotor_thrust", "efficiency"):
        a, b = getattr(narrow.columns, name), getattr(wide.columns, name)
        assert a.dtype == np.float32 and a.nbytes * 2 == b.nbytes
        np.testing.assert_array_equal(a, b.astype(np.float32), err_msg=name)
    run = narrow.trajectories[1]
    assert run.t.dtype == np.float64 and run.position.dtype == np.float32
    np.testing.assert_array_equal(run.t, wide.trajectories[1].t)
    assert narrow.to_arrow().schema.field("north_m").type == "float"


def test_record_every_keeps_every_nth_step_and_the_last() -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    x0s, controllers = _runs(sim)
    full = rf.simulate_batch(sim, x0s[:1], 0.31, controllers=controllers[:1])
    thin = rf.simulate_batch(sim, x0s[:1], 0.31, controllers=controllers[:1], record_every=10)
    steps = len(full.t)  # 0.31 s at 400 Hz: steps 0..124, the last one shortened to end at 0.31 s
    keep = [*range(0, steps - 1, 10), steps - 1]
    np.testing.assert_array_equal(thin.t, full.t[keep])
    np.testing.assert_array_equal(thin.position, full.position[:, keep])
    _assert_same(thin.trajectories[0], _per_run(sim, x0s[:1], controllers[:1], 0.31, 10)[0])


@pytest.mark.parametrize(("dtype", "error", "match"), [
    ("float16", ValueError, r"^dtype: must be 'float64' or 'float32', got 'float16'"),
    (32, TypeError, r"^dtype: expected a string"),
])
def test_bad_dtype_refused(dtype: object, error: type[Exception], match: str) -> None:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    with pytest.raises(error, match=match):
        rf.simulate_batch(sim, [rf.State()], 1.0, dtype=dtype)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^record_every: "):
        rf.simulate_batch(sim, [rf.State()], 1.0, record_every=0)
