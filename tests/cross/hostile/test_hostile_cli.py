"""The hostile-input harness over the command line (issue 27): every command of the ``rotorfault``
group has a strategy of hostile invocations (``COMMANDS``; a new command without one fails
:func:`test_every_command_has_a_strategy`), with the files users hand it: TOML airframes (presets,
mutated, hostile values, deep nesting, not TOML), PX4 ``.params`` files (values and names changed,
lines dropped or added), scenario and campaign files.

Each invocation must end with exit status 0 (its JSON output parsed, every number finite or
null), 1 with one line ``Error: ...`` on standard error, 2 (click's usage error) or 3 (a
requirement not met), never a traceback, within the time limit (``hostile_runner.py``)."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from hostile_runner import TEST_TIMEOUT_S, run_target
from hostile_targets import SCRATCH, Call, Target, scratch_file
from hostile_values import EDGE_FLOATS, EXAMPLES, HOSTILE_NAMES, PRESETS, airframe_toml, px4_params, scenario_toml
from hypothesis import strategies as st

from rotorfault.cli import cli

NUMBERS = tuple(repr(x) for x in EDGE_FLOATS) + ("1e-310", "x", "", "1,2", "-0", "99999999999999999999999")


def _airframe_spec() -> st.SearchStrategy[str]:
    return st.one_of(
        st.sampled_from(PRESETS), st.sampled_from(PRESETS),
        airframe_toml().map(lambda t: str(scratch_file(t, ".toml"))),
        px4_params().map(lambda t: str(scratch_file(t, ".params"))),
        st.sampled_from(("nonexistent", "", "/", "x.toml", "../x.params", *HOSTILE_NAMES[:4])),
    )


def _value(valid: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
    return st.one_of(valid, valid, st.sampled_from(NUMBERS), st.text(max_size=12))


def _option(name: str, value: st.SearchStrategy[str]) -> st.SearchStrategy[list[str]]:
    return st.one_of(st.just([]), value.map(lambda v: [name, v]))


def _flag(name: str) -> st.SearchStrategy[list[str]]:
    return st.sampled_from(([], [name]))


def _out_dir() -> st.SearchStrategy[str]:
    return st.one_of(
        st.builds(lambda: str(Path(tempfile.mkdtemp(dir=SCRATCH)) / "out")),
        st.just("/proc/forbidden-out"),
        st.builds(lambda: str(scratch_file("not a directory", ".txt"))),
    )


def _airframe_command(name: str, *extra: st.SearchStrategy[list[str]]) -> st.SearchStrategy[list[str]]:
    parts = [st.just([name, "--airframe"]), _airframe_spec().map(lambda s: [s]), _option("--mass", _value(st.sampled_from(("1.0", "2.5")))),
             *extra, _flag("--give-up-yaw") if name in ("acai", "scan") else st.just([]), st.just(["--format", "json"])]
    return st.tuples(*parts).map(lambda ps: [p for part in ps for p in part])


def _args(*parts: st.SearchStrategy[list[str]]) -> st.SearchStrategy[list[str]]:
    return st.tuples(*parts).map(lambda ps: [p for part in ps for p in part])


def _file(texts: st.SearchStrategy[str], suffix: str) -> st.SearchStrategy[list[str]]:
    return st.one_of(texts.map(lambda t: [str(scratch_file(t, suffix))]), st.just(["/nonexistent" + suffix]), st.sampled_from([[str(p)] for p in EXAMPLES]))


def _campaign_toml() -> st.SearchStrategy[str]:
    lines = st.lists(st.sampled_from((
        "runs = 2", "runs = -1", "runs = 1e300", "duration_s = 1.0", "duration_s = nan", "duration_s = 1e-310", "fault_time_s = [0.2, 0.4]",
        "gap_s = [0.2, 0.3]", "substeps = 0", "controller = \"x\"", "failures = [[1], [9]]", "chunk_size = 0", "seed = -5", "[x]",
        "mass_rel = inf", "a = " + "[" * 2000 + "]" * 2000,
    )), max_size=6, unique=True)
    return lines.map(lambda ls: "runs = 2\nduration_s = 1.0\nfault_time_s = [0.2, 0.4]\ngap_s = [0.2, 0.3]\n" + "\n".join(ls) + "\n")


COMMANDS: dict[str, st.SearchStrategy[list[str]]] = {
    "airframes": _args(st.just(["airframes"]), st.sampled_from((["--format", "json"], ["--format", "csv"], ["--format", "xml"]))),
    "acai": _airframe_command("acai", _option("--efficiency", _value(st.sampled_from(("1,1,1,0", "0.5,1,1,1,1,1", "1,nan,1,1", "1e-310,1,1,1"))))),
    "failures": _airframe_command("failures", _option("--max-failed", _value(st.sampled_from(("1", "2", "0", "-1", "99", "1000000000000"))))),
    "certify": _airframe_command("certify", _option("--require", st.sampled_from(("single", "double", "triple")))),
    "design": _airframe_command("design", _option("--parameter", st.sampled_from(("arm_length_m", "mass_kg", "x", "efficiency_1", "\n"))),
                                _option("--values", _value(st.sampled_from(("0.2,0.3", "1,2", "nan", "")))), _option("--top", _value(st.just("1")))),
    "scan": _airframe_command("scan", _option("--rotors", _value(st.sampled_from(("1,2", "1,2,3", "0", "9", "1,1")))),
                              st.one_of(st.just(["--step", "0.5"]), _option("--step", _value(st.sampled_from(("0.25", "1e-9", "0.3"))))),
                              _option("--axis", st.sampled_from(("mass_kg=1,2", "k_mu=0.1", "efficiency_1=0.5", "x=1", "mass_kg=nan", "=1"))),
                              _option("--chunk-points", _value(st.sampled_from(("10", "0", "-1")))),
                              st.one_of(st.just([]), _out_dir().map(lambda d: ["--out", d]))),
    "simulate": _args(st.just(["simulate"]), _file(scenario_toml(), ".toml"), st.just(["--format", "json"])),
    "campaign": _args(st.just(["campaign"]), _file(_campaign_toml(), ".toml"), _option("--runs", _value(st.sampled_from(("1", "2")))),
                      st.one_of(st.just([]), _out_dir().map(lambda d: ["--out", d])), _flag("--resume"), st.just(["--no-progress", "--format", "json"])),
    # Reports: hostile options, an output that cannot be written, a bench folder of malformed JSON;
    # the long work itself is the reports' own tests.
    "ftc-report": _args(st.just(["ftc-report"]), _out_dir().map(lambda d: ["--out", d]), st.sampled_from((
        ["--laws", "x"], ["--laws", ""], ["--laws", "feedforward,x"], ["--preset", "x"], ["--preset", "\n"], ["--scenarios", "nonexistent-scenario"],
        ["--scenarios", ""]))),
    "lanzon-report": _args(st.just(["lanzon-report", "--quick"]), _out_dir().map(lambda d: ["--out", d]), st.sampled_from((["--runs", "-1"], ["--runs", "x"], ["--runs", "1e300"]))),
    "reproduce": _args(st.just(["reproduce", "--quick"]), _out_dir().map(lambda d: ["--out", d]),
                       st.sampled_from(("{", "[]", '{"x": 1}', "null", "\x00")).map(lambda t: ["--benches", str(_bench_dir(t))])),
    "vpp-report": _args(st.just(["vpp-report"]), st.sampled_from((["--out", "/proc/forbidden-out"], ["--out", ""], ["--quick", "--out", "/proc/x"]))),
}


def _bench_dir(text: str) -> Path:
    folder = Path(tempfile.mkdtemp(dir=SCRATCH))
    for name in ("acai.json", "allocation.json", "simulation.json"):
        (folder / name).write_text(text)
    return folder


def _finite_json(value: Any) -> None:
    if isinstance(value, float):
        assert math.isfinite(value), value
    elif isinstance(value, list):
        for item in value[:200]:
            _finite_json(item)
    elif isinstance(value, dict):
        for item in value.values():
            _finite_json(item)


def invoke(args: list[str]) -> Any:
    result = CliRunner().invoke(cli, args)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise AssertionError(f"traceback from {args!r}: {type(result.exception).__name__}: {result.exception}")
    return result


def check_invocation(result: Any, call: Call) -> None:
    args = call.args[0]
    code = result.exit_code
    assert code in (0, 1, 2, 3), (code, args, result.output)
    if code == 1:
        err = result.stderr.strip()
        assert err.startswith("Error: ") and len(err.splitlines()) == 1 and len(err) > len("Error: "), (args, err)
    if code == 0 and "json" in args and result.stdout.strip():
        _finite_json(json.loads(result.stdout))


TARGETS = {name: Target(strategy.map(lambda a: Call(invoke, (a,), {}, frozenset())), check_invocation) for name, strategy in COMMANDS.items()}


def test_every_command_has_a_strategy() -> None:
    assert sorted(COMMANDS) == sorted(cli.commands), "add a strategy for each new command to tests/cross/hostile/test_hostile_cli.py"


@pytest.mark.timeout(TEST_TIMEOUT_S, method="thread")
@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_hostile_invocations(name: str) -> None:
    assert run_target(f"cli {name}", TARGETS[name])["calls"] > 0
