"""Fault campaigns through the scans' streaming machinery (issue 13, execution): Parquet output
with the campaign in its manifest, resume after an interruption (no row twice, rows identical to
an uninterrupted run), refusal of another campaign's output, the Dask backend (rows identical to
local), and a worst case re-flown from a Parquet output equal to its row."""

from __future__ import annotations

import json
import math
import time
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rotorfault.studies import engine, storage
from rotorfault.studies.campaign import SUMMARY_FIELDS, Campaign, campaign_schema, read_campaign, run_campaign, summarize

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")

#: Float fields of a re-flown run agree with its row to this (as in test_campaign.py).
RTOL = 1e-9


def _campaign(**changes: Any) -> Campaign:
    # 10 runs in 5 chunks of 2, 8 s each: holds, circling, lost (front pair), with wind, noise
    # and vehicle errors, so equal rows mean equal draws and equal flights.
    base = Campaign(
        runs=10, seed=11, chunk_size=2, duration_s=8.0, failures=((), (1,), (1, 4)), efficiency=(0.0, 0.6), ramp_s=(0.0, 0.3),
        fault_time_s=(1.0, 2.0), gap_s=(1.0, 2.0), wind_m_s=(0.0, 1.0), gust_m_s=(0.0, 1.0), noise_std=(0.005, 0.005, 0.0005, 0.005),
        mass_rel=0.05, thrust_rel=0.03, lag_rel=0.1,
    )
    return replace(base, **changes)


def _read_all(path: Path) -> Any:
    return pa.concat_tables(list(storage.iter_tables(path)))


def _same(a: Any, b: Any) -> bool:
    """Equal Arrow tables, NaN equal to NaN (``Table.equals`` calls NaN unequal; fault-free runs
    and lost runs have NaN cells): same schema, same values bit for bit otherwise."""
    assert a.schema.remove_metadata().equals(b.schema.remove_metadata())
    for name in a.column_names:
        x, y = a.column(name).to_numpy(zero_copy_only=False), b.column(name).to_numpy(zero_copy_only=False)
        if x.dtype.kind == "f":
            assert np.array_equal(x.view(np.int64), y.view(np.int64)) or np.array_equal(x, y, equal_nan=True), name
        else:
            assert x.tolist() == y.tolist(), name
    return True


def _memory_table(c: Campaign) -> Any:
    from rotorfault.studies.campaign import _CampaignTask

    return pa.concat_tables([_CampaignTask(c)(spec) for spec in storage.chunk_specs(c.runs, c.chunk_size)])


def _equal(a: Any, b: Any) -> bool:
    if isinstance(a, str) or isinstance(b, str):
        return bool(a == b)
    x, y = float(a), float(b)
    return (math.isnan(x) and math.isnan(y)) or abs(x - y) <= RTOL * max(1.0, abs(x))


def test_description_round_trips_through_toml_and_json() -> None:
    from rotorfault.control.ke import preset

    c = _campaign(gains=preset("ke-hil").gains.replace(k_v=0.25, weights=(1.0, 10.0, 10.0, 0.01)))
    assert Campaign.from_dict(tomllib.loads(c.to_toml())) == c
    assert Campaign.from_dict(json.loads(json.dumps(c.to_dict()))) == c
    assert Campaign.from_dict(tomllib.loads(Campaign().to_toml())) == Campaign()


def test_parquet_output_holds_the_campaign_and_the_in_memory_rows(tmp_path: Path) -> None:
    c = _campaign()
    out = tmp_path / "campaign.parquet"
    memory = run_campaign(c)
    result = run_campaign(c, out=out)
    assert result.out == out and result.loaded is None and (result.computed_chunks, result.skipped_chunks) == (5, 0)
    manifest = storage.read_manifest(out)
    assert manifest["kind"] == "rotorfault-campaign" and manifest["complete"]
    assert Campaign.from_dict(manifest["arguments"]["campaign"]) == c
    assert Campaign.from_dict(tomllib.loads(manifest["metadata"]["campaign_toml"])) == c
    back = _read_all(out)
    assert back.schema.remove_metadata().equals(campaign_schema())
    assert _same(back, _memory_table(c))
    # The columns read back from Parquet equal those gathered in memory (dtypes too).
    for key, values in memory.columns.items():
        np.testing.assert_array_equal(result.columns[key], values, err_msg=key)
        assert result.columns[key].dtype.kind == values.dtype.kind, key
    assert read_campaign(out).table() == memory.table()


def test_resume_after_an_interruption_writes_no_row_twice(tmp_path: Path) -> None:
    c = _campaign()
    out = tmp_path / "campaign.parquet"

    class Stop(Exception):
        pass

    written: list[int] = []

    def stop_after_two(spec: storage.ChunkSpec) -> None:
        written.append(spec.index)
        if len(written) == 2:
            raise Stop

    original = engine.run_chunks

    def interrupted(*args: Any, **kwargs: Any) -> Any:
        return original(*args, **{**kwargs, "on_chunk_written": stop_after_two})

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(engine, "run_chunks", interrupted)
        with pytest.raises(Stop):
            run_campaign(c, out=out)
    assert not storage.read_manifest(out)["complete"]
    assert sorted(p.name for p in out.glob("chunk-*.parquet")) == ["chunk-000000000.parquet", "chunk-000000001.parquet"]
    with pytest.raises(ValueError, match="interrupted campaign"):
        read_campaign(out)
    with pytest.raises(ValueError, match="interrupted output of this campaign; pass --resume"):
        run_campaign(c, out=out)
    stamps = {p.name: p.stat().st_mtime_ns for p in out.glob("chunk-*.parquet")}
    result = run_campaign(c, out=out, resume=True)
    assert (result.skipped_chunks, result.computed_chunks) == (2, 3)
    for name, stamp in stamps.items():
        assert (out / name).stat().st_mtime_ns == stamp  # not rewritten
    back = _read_all(out)
    assert back.column("index").to_pylist() == list(range(c.runs))  # every run once, in order
    # Identical to an uninterrupted run, to its own output and in memory.
    whole = tmp_path / "whole.parquet"
    run_campaign(c, out=whole)
    assert _same(back, _read_all(whole)) and _same(back, _memory_table(c))
    assert run_campaign(c, out=out, resume=True).computed_chunks == 0


def test_another_campaigns_output_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "campaign.parquet"
    run_campaign(_campaign(), out=out)
    before = sorted((p.name, p.stat().st_mtime_ns) for p in out.iterdir())
    with pytest.raises(ValueError, match=r"^out: .* holds an output written with other arguments: arguments\.campaign\.seed \(written 11, asked 12\)"):
        run_campaign(_campaign(seed=12), out=out, resume=True)
    assert sorted((p.name, p.stat().st_mtime_ns) for p in out.iterdir()) == before
    with pytest.raises(ValueError, match="holds a complete output"):
        run_campaign(_campaign(), out=out)
    replaced = run_campaign(_campaign(seed=12), out=out, force=True)
    assert replaced.campaign.seed == 12 and read_campaign(out).campaign.seed == 12
    (tmp_path / "scan").mkdir()
    (tmp_path / "scan" / "_rotorfault.json").write_text(json.dumps({"format": 1, "kind": "rotorfault-scan"}))
    with pytest.raises(ValueError, match="not a campaign"):
        read_campaign(tmp_path / "scan")


def test_a_worst_case_reflown_from_parquet_equals_its_row(tmp_path: Path) -> None:
    c = _campaign()
    out = tmp_path / "campaign.parquet"
    run_campaign(c, out=out)
    result = read_campaign(out)
    worst = result.worst(2)
    assert worst[0]["outcome"] not in ("holds-position", "circling", "off-station")  # the front pair is lost
    upper = result.campaign.vehicle().airframe.max_thrust_n
    for row in worst:
        full = summarize(result.campaign.refly(row["index"]), upper=upper)
        for key in ("outcome", "verdict", "cause", *SUMMARY_FIELDS):
            assert _equal(full[key], row[key]), (row["index"], key, full[key], row[key])


def test_dask_rows_identical_to_local(tmp_path: Path) -> None:
    """A LocalCluster of 2 worker processes: the same rows as the local backend, chunk by chunk.
    Bounded: 5 chunks of 2 runs of 8 s (a few seconds) plus the cluster's start, under 120 s."""
    distributed = pytest.importorskip("distributed")
    c = _campaign()
    local, remote = tmp_path / "local.parquet", tmp_path / "dask.parquet"
    run_campaign(c, out=local)
    started = time.monotonic()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster:
        with distributed.Client(cluster) as client:
            result = run_campaign(c, out=remote, backend="dask", dask=client)
            memory = run_campaign(c, backend="dask", dask=client)
    assert time.monotonic() - started < 120
    assert result.computed_chunks == 5
    assert _same(_read_all(remote), _read_all(local))
    for a, b in zip(sorted(local.glob("chunk-*")), sorted(remote.glob("chunk-*"))):
        assert _same(pq.read_table(a), pq.read_table(b))
    for key, values in run_campaign(c).columns.items():
        np.testing.assert_array_equal(memory.columns[key], values, err_msg=key)


def test_bad_backend_arguments() -> None:
    with pytest.raises(ValueError, match="^dask: backend='dask' needs"):
        run_campaign(_campaign(), backend="dask")
    with pytest.raises(ValueError, match="^backend"):
        run_campaign(_campaign(), backend="spark")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^out"):
        run_campaign(_campaign(), out=3)  # type: ignore[arg-type]


def test_cli_campaign_out_resume_and_refusal(tmp_path: Path) -> None:
    from click.testing import CliRunner

    from rotorfault.cli import cli

    path = tmp_path / "c.toml"
    path.write_text("runs = 4\nchunk_size = 2\nduration_s = 6.0\nfailures = [[1], [2]]\n")
    out = tmp_path / "out"
    first = CliRunner().invoke(cli, ["campaign", str(path), "--no-progress", "--out", str(out)])
    assert first.exit_code == 0, first.output
    assert "2 chunks flown, 0 already written" in first.output and "Wilson" in first.output
    again = CliRunner().invoke(cli, ["campaign", str(path), "--no-progress", "--out", str(out)])
    assert again.exit_code == 1 and "--resume" in again.output
    resumed = CliRunner().invoke(cli, ["campaign", str(path), "--no-progress", "--out", str(out), "--resume"])
    assert resumed.exit_code == 0 and "0 chunks flown, 2 already written" in resumed.output
    other = CliRunner().invoke(cli, ["campaign", str(path), "--runs", "6", "--no-progress", "--out", str(out), "--resume"])
    assert other.exit_code == 1 and "other arguments" in other.output
    forced = CliRunner().invoke(cli, ["campaign", str(path), "--runs", "6", "--no-progress", "--out", str(out), "--force"])
    assert forced.exit_code == 0 and read_campaign(out).campaign.runs == 6
    lonely = CliRunner().invoke(cli, ["campaign", str(path), "--resume"])
    assert lonely.exit_code == 1 and "need --out" in lonely.output
