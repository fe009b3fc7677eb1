"""A recorded batch streamed to Parquet (``studies.record_batch``): one row per run with list
columns, the values ``simulate_batch`` returns, written through the studies' one writer
(chunks, manifest, resume); bad input refused before any run or file write."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import rotorfault as rf
from rotorfault.studies import record_batch
from rotorfault.studies.storage import read_manifest


def _batch() -> tuple[rf.Simulator, list[rf.State], list[object]]:
    sim = rf.Simulator(rf.Airframe.preset("quad-x"), noise=rf.Noise(snr_db=20.0, seed=2))
    hold = rf.lqr_hover(sim, position=(0, 0, -1))
    return sim, [rf.State(position=(0.1 * k, 0, -1)) for k in range(5)], [hold, None, hold, hold, None]


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_parquet_round_trip(tmp_path: Path, dtype: str) -> None:
    sim, x0s, controllers = _batch()
    out = tmp_path / "runs"
    result = record_batch(sim, x0s, 0.5, out=out, controllers=controllers, record_every=3, dtype=dtype, chunk_runs=2)
    assert (result.total_rows, result.chunks, result.computed_chunks) == (5, 3, 3)
    assert read_manifest(out)["complete"] and len(list(out.glob("chunk-*.parquet"))) == 3
    table = pq.read_table(out)
    memory = rf.simulate_batch(sim, x0s, 0.5, controllers=controllers, record_every=3, dtype=dtype)
    long = memory.to_arrow()
    assert table.column_names == ["run", "diverged", "divergence_time_s", *long.column_names[1:]]
    value = "float" if dtype == "float32" else "double"
    assert str(table.schema.field("north_m").type) == f"list<element: {value}>"
    assert str(table.schema.field("t_s").type) == "list<element: double>"
    assert table.column("run").to_pylist() == [0, 1, 2, 3, 4]
    assert table.column("diverged").to_pylist() == memory.diverged.tolist() == [False, True, False, False, True]
    np.testing.assert_array_equal(table.column("divergence_time_s").to_numpy(), memory.divergence_time)
    runs = long.column("run").to_numpy()
    for name in long.column_names[1:]:
        for k in range(5):
            np.testing.assert_array_equal(np.asarray(table.column(name)[k].values), long.column(name).to_numpy()[runs == k], err_msg=name)
    # The same job again: refused without resume; with it, nothing is recomputed.
    with pytest.raises(ValueError, match=r"^out: .*holds a complete output.*resume"):
        record_batch(sim, x0s, 0.5, out=out, controllers=controllers, record_every=3, dtype=dtype, chunk_runs=2)
    again = record_batch(sim, x0s, 0.5, out=out, controllers=controllers, record_every=3, dtype=dtype, chunk_runs=2, resume=True)
    assert (again.computed_chunks, again.skipped_chunks) == (0, 3)
    # Other arguments on the same output: refused, naming what differs.
    with pytest.raises(ValueError, match=r"^out: .*holds an output written with other arguments"):
        record_batch(sim, x0s[::-1], 0.5, out=out, controllers=controllers, record_every=3, dtype=dtype, chunk_runs=2, resume=True)


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"dtype": "float16"}, ValueError, r"^dtype: must be 'float64' or 'float32'"),
    ({"record_every": 0}, ValueError, r"^record_every: "),
    ({"chunk_runs": 0}, ValueError, r"^chunk_runs: must be at least 1"),
    ({"out": 3}, TypeError, r"^out: expected a directory path"),
    ({"out": "/nonexistent/dir/runs"}, ValueError, r"^out: directory '/nonexistent/dir' does not exist"),
])
def test_bad_input_refused_before_any_work(tmp_path: Path, kwargs: dict[str, object], error: type[Exception], match: str) -> None:
    sim, x0s, controllers = _batch()
    args: dict[str, object] = {"out": tmp_path / "runs", **kwargs}
    with pytest.raises(error, match=match):
        record_batch(sim, x0s, 0.5, controllers=controllers, **args)  # type: ignore[arg-type]
    assert list(tmp_path.iterdir()) == []
