"""A scriptable command line (issue 31): every command writes ``--format json`` that validates
against the schema documented in ``docs/cli.md``, ``--format csv`` with the JSON keys as header,
plain unwrapped text when standard output is not a terminal, nothing with ``--quiet``, and the
documented exit statuses (0 ok, 1 error, 2 usage, 3 requirement not met); defaults that work for
every preset; a missing optional package named before any work."""

from __future__ import annotations

import csv
import io
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from quick_report import QuickReport
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli
from rotorfault.cli.output import EXIT_CODES, FORMATS

from without_packages import prelude

jsonschema = pytest.importorskip("jsonschema")

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "cli.md"
EXAMPLE = str(ROOT / "examples" / "quad-x-rotor-failure.toml")


def documented_schemas() -> dict[str, Any]:
    """The JSON schema of each command, as docs/cli.md documents it."""
    text = DOC.read_text(encoding="utf-8")
    blocks = re.findall(r"<!-- json-schema: ([a-z-]+) -->\n```json\n(.*?)```", text, flags=re.S)
    return {name: json.loads(body) for name, body in blocks}


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, list(args), terminal_width=200)
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("cli")
    (path / "campaign.toml").write_text("runs = 4\nchunk_size = 2\nduration_s = 8.0\n")
    return path


def commands(workdir: Path) -> dict[str, list[list[str]]]:
    """For every command, argument lists that succeed (each mode of the command once)."""
    return {
        "airframes": [[]],
        "acai": [["-a", "hexa-pnpnpn"], ["-a", "hexa-pnpnpn", "--efficiency", "0,0,0,1,1,1", "--give-up-yaw"]],
        "failures": [["-a", "hexa-ppnnpn", "-k", "2"], ["-a", "octo-x", "-k", "1", "--formula", "facet-margin"]],
        "certify": [["-a", "quad-x", "--require", "single"], ["-a", "hexa-ppnnpn", "--require", "double"]],
        "scan": [["-a", "quad-x", "--step", "0.25"], ["-a", "hexa-pnpnpn", "--step", "0.5", "--out", str(workdir / "scan.parquet")]],
        "design": [["-a", "quad-x"], ["-a", "quad-x", "--parameter", "arm_length_m", "--values", "0.2,0.3", "--top", "2"]],
        "simulate": [[EXAMPLE]],
        "campaign": [[str(workdir / "campaign.toml"), "--no-progress"],
                     [str(workdir / "campaign.toml"), "--no-progress", "--out", str(workdir / "campaign.parquet")],
                     ["--suite", "deciding", "--runs", "1", "--no-progress"]],
        "ftc-report": [["--scenarios", "fault-free", "--laws", "feedforward", "--no-figures", "--out", str(workdir / "ftc")]],
        "vpp-report": [["--quick", "--out", str(workdir / "vpp")]],
        "lanzon-report": [["--quick", "--runs", "2", "--no-figures", "--out", str(workdir / "lanzon")]],
        # reproduce: the session's one quick report (``quick_report``, built with --format json).
    }


def test_every_command_has_a_documented_schema() -> None:
    schemas = documented_schemas()
    assert set(schemas) == set(cli.commands), set(cli.commands) ^ set(schemas)
    for schema in schemas.values():
        jsonschema.Draft202012Validator.check_schema(schema)


def test_every_command_has_format_and_quiet() -> None:
    for name, command in cli.commands.items():
        options = {opt for p in command.params for opt in p.opts}
        assert {"--format", "--quiet", "-q"} <= options, name


@pytest.fixture(scope="module")
def json_outputs(workdir: Path, quick_report: QuickReport) -> dict[str, list[dict[str, Any]]]:
    out: dict[str, list[dict[str, Any]]] = {"reproduce": [quick_report.document]}
    for name, variants in commands(workdir).items():
        for args in variants:
            code, stdout, stderr = run(name, *args, "--format", "json", "--force") if name in ("ftc-report", "vpp-report", "lanzon-report", "reproduce") \
                else run(name, *args, "--format", "json")
            assert code in (0, 3), (name, args, stderr)
            out.setdefault(name, []).append(json.loads(stdout))
    return out


def test_json_matches_the_documented_schema(json_outputs: dict[str, list[dict[str, Any]]]) -> None:
    schemas = documented_schemas()
    for name, documents in json_outputs.items():
        for document in documents:
            assert document["command"] == name and document["schema_version"] == 1
            jsonschema.validate(document, schemas[name])


def test_json_says_what_the_api_says(json_outputs: dict[str, list[dict[str, Any]]]) -> None:
    failures = json_outputs["failures"][0]
    table = rf.failure_table(rf.Airframe.preset("hexa-ppnnpn"), max_failed=2)
    assert failures["case_count"] == 22 and failures["controllable_count"] == 8
    assert failures["cases"] == [{k: (None if isinstance(v, float) and v == float("-inf") else v) for k, v in row.items()}
                                 for row in table.to_arrow().to_pylist()]
    certify = json_outputs["certify"][0]
    assert certify["requirement_met"] is False and certify["failing"] == [[1], [2], [3], [4]]
    hexa = json_outputs["certify"][1]
    assert hexa["requirement_met"] is False and [1] not in hexa["failing"] and [5, 6] in hexa["failing"]
    assert json_outputs["simulate"][0]["outcome"] == "crashed"


def test_csv_is_the_main_table(workdir: Path) -> None:
    code, out, _ = run("failures", "-a", "hexa-ppnnpn", "-k", "2", "--format", "csv")
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == 22 and rows[0]["failed_rotors"] == "" and rows[7]["failed_rotors"] == "1 2"
    assert rows[0]["acai_eq13"] == repr(float(rf.acai(rf.Airframe.preset("hexa-ppnnpn"))))
    code, out, _ = run("acai", "-a", "quad-x", "--format", "csv")
    header, values = list(csv.reader(io.StringIO(out)))
    assert code == 0 and header[0] == "airframe" and values[0] == "quad-x" and values[header.index("efficiency")] == "1.0 1.0 1.0 1.0"
    code, out, _ = run("simulate", EXAMPLE, "--format", "csv")
    trajectory = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and trajectory[0]["t_s"] == "0.0" and "rotor_1_thrust_n" in trajectory[0]


@pytest.mark.parametrize("name", ["airframes", "acai", "failures", "certify", "scan", "design", "simulate"])
def test_quiet_writes_nothing(name: str, workdir: Path) -> None:
    args = commands(workdir)[name][0]
    code, out, _ = run(name, *args, "--quiet")
    assert code in (0, 3) and out == ""


def _shell(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """The installed command with standard output a pipe (not a terminal), 40 columns declared."""
    import os

    return subprocess.run([sys.executable, "-m", "rotorfault", *args], capture_output=True, text=True, check=False,
                          env={**os.environ, "COLUMNS": "40", **(env or {})})


def test_piped_output_is_plain_unwrapped_text() -> None:
    done = _shell("failures", "-a", "hexa-ppnnpn", "-k", "2")
    assert done.returncode == 0
    lines = done.stdout.splitlines()
    assert not re.search("[\u2500-\u257f\x1b]", done.stdout), "box drawing or escape codes in piped output"
    rows = [line.split() for line in lines if re.match(r"^(none|\d+(, \d+)?)\s+\d+\s+\d+\s+(-?\d+\.\d{4}\*?|undefined)\s", line)]
    assert len(rows) == 22  # one line per case, however narrow the declared terminal
    assert [r for r in rows if r[0] == "5"][0][3] == "0.0000*"  # awk '$1 == 5 {print $4}'
    assert max(len(line) for line in lines) > 40


EXIT_CASES = [
    # (command, arguments, status)
    ("airframes", ["--bogus"], 2),
    ("acai", ["-a", "no-such-frame"], 1),
    ("acai", [], 2),
    ("failures", ["-a", "quad-x", "-k", "9"], 1),
    ("certify", ["-a", "quad-x", "--require", "single"], 3),
    # Rotor 5 or 6 lost leaves hover only by giving up yaw: met with the axes that must remain
    # named (--require-axes), not met with the default (all four).
    ("certify", ["-a", "hexa-ppnnpn", "--require", "single", "--require-axes", "thrust,roll,pitch"], 0),
    ("certify", ["-a", "hexa-ppnnpn", "--require", "single"], 3),
    ("certify", ["-a", "hexa-ppnnpn", "--require", "double"], 3),
    ("certify", ["-a", "octo-x", "--require", "single"], 0),
    ("certify", ["-a", "no-such-frame"], 1),
    ("scan", ["-a", "quad-x", "--rotors", "1,9"], 1),
    ("design", ["-a", "quad-x", "--top", "-1"], 1),
    ("simulate", ["missing.toml"], 1),
    ("simulate", [], 2),
    ("campaign", ["missing.toml"], 1),
    ("ftc-report", ["--laws", "bogus"], 1),
    ("vpp-report", ["--out", "."], 1),
    ("lanzon-report", ["--runs", "-1"], 1),
    ("reproduce", ["--out", "."], 1),
]


@pytest.mark.parametrize(("name", "args", "status"), EXIT_CASES)
def test_exit_statuses(name: str, args: list[str], status: int) -> None:
    code, out, err = run(name, *args)
    assert code == status, (out, err)
    if status == 1:
        assert err.startswith("Error: ") and len(err.strip().splitlines()) == 1


def test_every_command_has_its_exit_statuses_tested() -> None:
    tested = {(name, status) for name, _, status in EXIT_CASES}
    for name in cli.commands:
        assert (name, 2) in tested or (name, 1) in tested, name
        code, _, _ = run(name, "--format", "xml")
        assert code == 2  # a bad --format is a usage error, for every command
    assert set(EXIT_CODES) == {0, 1, 2, 3, 130} and FORMATS == ("table", "json", "csv")
    doc = DOC.read_text(encoding="utf-8")
    for status in EXIT_CODES:
        assert f"| {status} |" in doc


@pytest.mark.parametrize("preset", rf.Airframe.presets())
def test_defaults_work_for_every_preset(preset: str) -> None:
    for name, args in (("acai", []), ("failures", []), ("certify", []), ("scan", ["--step", "0.25"]), ("design", ["--top", "1"])):
        code, _, err = run(name, "-a", preset, *args, "--quiet")
        # Wang's fixed-pitch layout cannot command yaw apart from roll and pitch even healthy (rank
        # 10, issue 25): certify's default requirement (the healthy frame hovers with all four
        # axes) is not met, and says so with status 3.
        expected = 3 if (name, preset) == ("certify", "wang-fixed-pitch") else 0
        assert code == expected, (name, preset, err)


def test_a_missing_dask_is_named_before_any_work(tmp_path: Path) -> None:
    out = tmp_path / "scan.parquet"
    code = prelude(("dask", "distributed")) + (
        "import sys\nfrom rotorfault.cli import main\n"
        f"sys.argv = ['rotorfault', 'scan', '-a', 'quad-x', '--step', '0.5', '--out', {str(out)!r}, '--dask', 'local:1']\nmain()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip() == "Error: backend='dask' needs dask, which is not installed: pip install \"rotorfault[scale]\""
    assert done.stdout == "" and not out.exists()
