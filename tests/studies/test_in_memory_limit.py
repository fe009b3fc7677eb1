"""What a study may hold in memory (issue 27): results gathered in memory (``out=None``) are sized
by the bytes a row takes, not by a point count, and refused above
:data:`~rotorfault.studies.engine.MAX_IN_MEMORY_BYTES` (1 GiB) before any work, naming the field
and pointing at the streaming path (``out=``, ``--out``), which takes the same job. And
``failure_samples`` builds its rows by block copies, with exactly the rows of the row-by-row
construction it replaced."""

from __future__ import annotations

import math
from itertools import combinations
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import studies
from rotorfault.studies import campaign as campaign_module
from rotorfault.studies import engine
from rotorfault.studies import scan as scan_module
from rotorfault.studies.scan import acai_scan, failure_samples, scan_schema

pytest.importorskip("pyarrow")

THREE_AXES = ("efficiency_1", "efficiency_2", "efficiency_5")


def _no_work(*args: Any, **kwargs: Any) -> Any:
    raise AssertionError("work started before the size was checked")


def test_a_row_takes_the_bytes_of_its_columns() -> None:
    """Per row: 8 bytes per float64 axis and ACAI, 1 per hover code, verdict (NumPy's bool) and
    rank; a campaign's 27 numbers and 4 strings (64 bytes each, engine.STRING_CELL_BYTES)."""
    assert engine.MAX_IN_MEMORY_BYTES == 2**30
    assert engine.row_bytes(scan_schema(THREE_AXES, ("eq13", "facet-margin"), False)) == 3 * 8 + 2 * 8 + 3 == 43
    assert engine.row_bytes(scan_schema(THREE_AXES, ("eq13",), True)) == 3 * 8 + 2 * (8 + 3) == 46
    schema = campaign_module.campaign_schema()
    strings = sum(1 for f in schema if str(f.type) == "string")
    assert strings == 4 and len(schema) == 31
    assert engine.row_bytes(schema) == (len(schema) - strings) * 8 + strings * engine.STRING_CELL_BYTES == 472


def test_the_limit_sits_at_one_gib_of_rows() -> None:
    most = engine.MAX_IN_MEMORY_BYTES // 43
    engine.check_in_memory("axes", most, 43)
    with pytest.raises(ValueError, match=r"^axes: 24,970,741 rows of 43 bytes \(1\.0 GiB\) exceed the in-memory limit of 1 GiB of results \(24,970,740 rows\); stream them to Parquet with out=DIR"):
        engine.check_in_memory("axes", most + 1, 43)


def test_a_scan_too_large_for_memory_is_refused_before_any_work(monkeypatch: pytest.MonkeyPatch, pnpnpn: rf.Airframe) -> None:
    monkeypatch.setattr(scan_module, "acai_batch", _no_work)
    monkeypatch.setattr(scan_module, "_check_axis_values", _no_work)
    grid = {name: np.linspace(0.0, 1.0, 300) for name in THREE_AXES}  # 27,000,000 rows of 43 bytes: 1.08 GiB
    with pytest.raises(ValueError, match=r"^axes: 27,000,000 rows of 43 bytes .* \(300 x 300 x 300 grid points\) stream them to Parquet with out=DIR \(CLI: rotorfault scan --out DIR\)"):
        acai_scan(pnpnpn, grid)
    with pytest.raises(ValueError, match=r"^step, rotors: 125,751,501 rows of 33 bytes .* \(501\^3 grid points\) .* acai_scan\(\.\.\., out=DIR\)"):
        rf.efficiency_scan(pnpnpn, (1, 2, 5), 0.002)


def test_a_campaign_too_large_for_memory_is_refused_before_any_run(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(campaign_module, "run_chunk", _no_work)
    with pytest.raises(ValueError, match=r"^runs: 10,000,000 rows of 472 bytes .* stream them to Parquet with out=DIR \(CLI: --out DIR\)"):
        studies.run_campaign(studies.Campaign(runs=10_000_000))


def test_the_streaming_path_takes_what_memory_refuses(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, pnpnpn: rf.Airframe) -> None:
    """The same grid under a limit of 100 rows: refused in memory, streamed to Parquet with the
    rows the in-memory scan gives under the real limit."""
    grid = {name: np.linspace(0.0, 1.0, 5) for name in THREE_AXES}  # 125 rows
    whole = acai_scan(pnpnpn, grid).to_arrow()
    monkeypatch.setattr(engine, "MAX_IN_MEMORY_BYTES", 100 * 43)
    with pytest.raises(ValueError, match=r"^axes: 125 rows of 43 bytes"):
        acai_scan(pnpnpn, grid)
    streamed = acai_scan(pnpnpn, grid, out=tmp_path / "scan", chunk_points=50)
    assert streamed.to_arrow().equals(whole)
    samples = {name: whole[name].to_numpy() for name in THREE_AXES}
    with pytest.raises(ValueError, match=r"^samples: 125 rows of 43 bytes"):
        acai_scan(pnpnpn, samples=samples)
    assert acai_scan(pnpnpn, samples=samples, out=tmp_path / "samples", chunk_points=50).to_arrow().equals(whole)


def _failure_samples_row_by_row(rotor_count: int, max_failed: int) -> dict[str, np.ndarray]:
    """The construction failure_samples used before: one Python statement per row."""
    rows = [c for k in range(0, max_failed + 1) for c in combinations(range(rotor_count), k)]
    eff = np.ones((len(rows), rotor_count))
    for i, failed in enumerate(rows):
        eff[i, list(failed)] = 0.0
    return {f"efficiency_{r + 1}": eff[:, r].copy() for r in range(rotor_count)}


@pytest.mark.parametrize(("rotor_count", "max_failed"), [(1, 0), (1, 1), (4, 2), (6, 6), (8, 4), (12, 5), (17, 3)])
def test_failure_samples_are_the_rows_of_the_row_by_row_construction(rotor_count: int, max_failed: int) -> None:
    fast = failure_samples(rotor_count, max_failed)
    slow = _failure_samples_row_by_row(rotor_count, max_failed)
    assert list(fast) == list(slow)
    for name in slow:
        assert fast[name].dtype == slow[name].dtype and fast[name].flags.c_contiguous
        np.testing.assert_array_equal(fast[name], slow[name])
    assert len(slow["efficiency_1"]) == sum(math.comb(rotor_count, k) for k in range(max_failed + 1))


def test_failure_samples_too_large_for_memory_are_refused_by_count() -> None:
    with pytest.raises(ValueError, match=r"^max_failed: 8,656,937 rows of 240 bytes .* \(30 rotors, up to 8 failed\) give fewer failed rotors"):
        failure_samples(30, 8)


def test_failure_samples_of_a_billion_rotors_are_refused_at_once() -> None:
    """Found by the long hostile run: the count summed C(1e9, k) for every k up to 1e9 first."""
    with pytest.raises(ValueError, match=r"^max_failed: at least 1 rows of 8,?000,?000,?000 bytes"):
        failure_samples(10**9, 10**9)
    with pytest.raises(ValueError, match=r"^max_failed: at least 1,000,001 rows of 8000000 bytes"):
        failure_samples(10**6, 10**6)
