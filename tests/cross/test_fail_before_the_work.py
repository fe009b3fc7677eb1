"""Fail before the work (issue 27): every input (the bench JSON of ``reproduce``, the Dask backend
and its address, the output target, a campaign's step counts, TOML nesting) is checked before the
first expensive step, and nothing is written when a check fails."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault._util.optional import MissingDependency
from rotorfault.cli import cli
from rotorfault.control import vpp
from rotorfault.papers import reproduce
from rotorfault.studies import Campaign, run_campaign
from rotorfault.studies.scan import acai_scan

GOOD_BENCH: dict[str, Any] = {
    "schema": "rotorfault-bench/1", "bench": "b", "title": "t", "command": "c", "date": "d", "reduced": None,
    "machine": {"cpu": "x", "cpus": 2, "system": "s", "python": "3", "rotorfault": "0", "load_average_1min": 1.0},
    "figures": [{"what": "w", "value": 1.0, "unit": "u", "baseline": None, "baseline_value": None, "ratio": None, "target": None}],
}


def _broken(mutate: Any) -> dict[str, Any]:
    data = json.loads(json.dumps(GOOD_BENCH))
    mutate(data)
    return data


@pytest.mark.parametrize(
    ("content", "field"),
    [
        (_broken(lambda d: d["figures"][0].update(value="fast")), r"figures\[0\]\.value must be int or float"),
        (_broken(lambda d: d["machine"].pop("cpus")), r"machine\.cpus is missing"),
        (_broken(lambda d: d["machine"].update(load_average_1min="high")), r"machine\.load_average_1min"),
        (_broken(lambda d: d.update(figures={"a": 1})), r"figures must be list"),
        (_broken(lambda d: d["figures"].append(3)), r"figures\[1\]\. must be a JSON object|must be a JSON object"),
        (_broken(lambda d: d.update(title=None)), r"title must be str"),
        ("[" * 100_000 + "]" * 100_000, r"is not a bench result"),
    ],
)
def test_a_malformed_bench_file_stops_reproduce_before_any_section(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, content: Any, field: str) -> None:
    benches = tmp_path / "benches"
    benches.mkdir()
    (benches / "b.json").write_text(content if isinstance(content, str) else json.dumps(content))

    def no_work(paper: Any) -> Any:
        raise AssertionError("a section was computed before the bench files were checked")

    monkeypatch.setattr(reproduce, "provider", no_work)
    out = tmp_path / "report"
    result = CliRunner().invoke(cli, ["reproduce", "--quick", "--benches", str(benches), "--out", str(out)])
    assert result.exit_code == 1, result.output
    assert "benches: " in result.output and len(result.output.strip().splitlines()) == 1
    assert re.search(field, result.output), result.output
    assert not out.exists()


def test_the_good_bench_file_passes(tmp_path: Path) -> None:
    (tmp_path / "b.json").write_text(json.dumps(GOOD_BENCH))
    assert reproduce.bench_results(tmp_path)[0].figures[0]["value"] == 1.0


@pytest.fixture
def no_dask(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError


@pytest.mark.parametrize("command", [
    ["scan", "-a", "quad-x", "--rotors", "1,2", "--step", "0.5", "--dask", "local:2"],
    ["campaign", "--runs", "2", "--dask", "local:2"],
])
def test_dask_not_installed_is_one_line_before_any_output(tmp_path: Path, no_dask: None, command: list[str]) -> None:
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, [*command, "--out", str(out)])
    assert result.exit_code == 1, result.output
    assert result.output == 'Error: backend=\'dask\' needs distributed, which is not installed: pip install "rotorfault[scale]"\n' and "Traceback" not in result.output
    assert not out.exists()


def test_dask_arguments_are_checked_before_any_output(tmp_path: Path, no_dask: None) -> None:
    frame = rf.Airframe.preset("quad-x")
    out = tmp_path / "out"
    with pytest.raises(MissingDependency, match=r"^backend='dask' needs distributed, which is not installed: pip install \"rotorfault\[scale\]\"$"):
        acai_scan(frame, {"efficiency_1": [0.0, 1.0]}, out=out, backend="dask", dask="local:2")
    assert not out.exists()


@pytest.mark.parametrize(("address", "message"), [("nowhere", "scheduler address"), ("local:0", "positive worker count"), ("local:x", "positive worker count"), (3, "expected a distributed.Client")])
def test_bad_dask_addresses_write_nothing(tmp_path: Path, address: Any, message: str) -> None:
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    with pytest.raises((ValueError, TypeError), match=message):
        acai_scan(rf.Airframe.preset("quad-x"), {"efficiency_1": [0.0, 1.0]}, out=out, backend="dask", dask=address)
    assert not out.exists()


def test_an_output_that_is_a_file_is_refused_untouched(tmp_path: Path) -> None:
    target = tmp_path / "file"
    target.write_text("mine")
    with pytest.raises(ValueError, match="out: .* exists and is not a directory"):
        run_campaign(Campaign(runs=2, chunk_size=1, duration_s=1.0, fault_time_s=0.5, gap_s=0.1), out=target)
    assert target.read_text() == "mine"


def test_small_cases_name_their_field(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"substeps: must be >= 1"):
        Campaign(substeps=-1)
    with pytest.raises(ValueError, match=r"duration_s, dt_s: .* control steps exceed"):
        Campaign(duration_s=1e6, dt_s=1e-6, fault_time_s=1.0, gap_s=1.0)
    deep = tmp_path / "deep.toml"
    deep.write_text("runs = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ValueError, match="nested too deeply"):
        Campaign.from_toml(deep)
    result = CliRunner().invoke(cli, ["campaign", str(deep)])
    assert result.exit_code == 1 and "nested too deeply" in result.output
    with pytest.raises(ValueError, match=r"fixed_rotors: propeller 1 is failed"):
        vpp.feasible_speeds(vpp.preset(), fixed_rotors=(1, 3))  # main: KeyError 1
    with pytest.raises(ValueError, match=r"fixed_rotors: rotor numbers run from 1 to 4"):
        vpp.feasible_speeds(vpp.preset(), fixed_rotors=(7,))
    assert np.isfinite(vpp.feasible_speeds(vpp.preset(), fixed_rotors=(3,)).fixed_speed_range).all()
