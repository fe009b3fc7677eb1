"""The README tested (issues 21 and 31): every Python block runs as written and the numbers its
comments print are what the code gives now (:data:`CLAIMS`); every command it shows runs
(:data:`COMMANDS`, with the stand-ins the README allows for the long ones) or is run by the test
named for it (:data:`RUN_ELSEWHERE`); the terminal output it shows is what the command prints
now, token by token."""

from __future__ import annotations

import contextlib
import io
import math
import re
import shlex
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import matplotlib
import pytest
from click.testing import CliRunner

from rotorfault.cli import cli

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"


@pytest.fixture(scope="module")
def executed(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, list[dict[str, Any]], str]]:
    """Every Python block of the README run once, in order, each in a namespace of its own, in a
    fresh directory: (that directory, the namespaces, what the blocks printed)."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    assert blocks, "README has a Python example"
    matplotlib.use("Agg")
    work = tmp_path_factory.mktemp("readme")
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(work)
        printed = io.StringIO()
        namespaces: list[dict[str, Any]] = []
        with contextlib.redirect_stdout(printed):
            for block in blocks:
                namespace: dict[str, Any] = {}
                exec(compile(block, str(README), "exec"), namespace)
                namespaces.append(namespace)
        yield work, namespaces, printed.getvalue()


def test_readme_python_example_runs(executed: tuple[Path, list[dict[str, Any]], str]) -> None:
    work, _, printed = executed
    assert (work / "fig4.png").stat().st_size > 10_000
    assert (work / "failure.png").stat().st_size > 10_000
    assert "hexa-pnpnpn" in printed


#: The README's "this snippet gives X" claims: (text on the README line, a name the block defines,
#: expression evaluated in that block's namespace, expected value, absolute tolerance). The
#: tolerance is the last printed digit's half unit.
CLAIMS = [
    ("rf.acai(hexa)                                     # 1.4861 (Table II)", "hexa", "rf.acai(hexa)", 1.4861, 0.5e-4),
    ("# 0.0: uncontrollable with any one rotor failed", "hexa", "rf.acai(hexa.with_failed_rotors([1]))", 0.0, 0.0),
    ("# 1.2882 > 0: it can still hover spinning", "hexa", "rf.acai(hexa.with_failed_rotors([1]), give_up_yaw=True)", 1.2882, 0.5e-4),
    ("# Du Fig. 4: 17,576 points", "scan", "len(scan.acai)", 17_576, 0),
    ("kind='crashed'", "lqr", "run.events[0].kind == 'crashed'", True, 0),
    ("kind='crashed'", "lqr", "float(run.position[-1, 2] - run.position[0, 2])", 10.0, 1e-9),
    ("# r = -41.2 rad/s: a steady spin of about 41 rad/s", "preset", "float(run.omega[-1, 2])", -41.2, 0.05),
    ("# two opposite rotors (1 front right, 3 rear left)", "preset", "[f.rotor for f in run.faults]", [1, 3], 0),
    ("Ke Table II (efficiency = diag of Ke's health matrix): 0, 0.5, 1", "preset",
     "[round(float(v.real), 12) for v in ke.n_eigenvalues(preset.airframe, [0, 0, 1, 1])]", [0.0, 0.5, 1.0], 0),
    ("# mocap 0", "sensed", "(run.sensed, int(run.estimate.counts.gyro_saturated_samples))", ("mocap", 0), 0),
    ("# 0.19 mm after the first second", "sensed", "round(1e3 * float(run.estimate_position_error_m[400:].max()), 2)", 0.19, 0.005),
    ("# 'drifts' (see the findings below)", "preset", "ke_paper.run_scenario('one-failure').metrics.verdict", "drifts", 0),
    ("# 1.527, 1.680 (stability margin 1/gamma)", "ours", "round(ours.gamma_min, 3), round(ours.gamma, 3)", (1.527, 1.680), 0),
    ("# holds-position, within 1 cm of (0, 0, 1) m after 60 s", "ours", "run.outcome == 'holds-position' and run.final_error_m < 0.01", True, 0),
    # The one LQR and its refusals (issue 25).
    ("# [[1. 1.732]]: K = [1, sqrt 3] for q = I, r = 1", "d", "bool(np.allclose(d.gain, [[1.0, 3**0.5]], rtol=1e-13, atol=0))", True, 0),
    ("# stabilisability: ... no input moves yaw rate r together with p and q: 0.132 p + 0.132 q - r", "fixed",
     "refusal.startswith('stabilisability: ') and 'no input moves yaw rate r together with p and q: 0.132 p + 0.132 q - r' in refusal",
     True, 0),
    # INDI fault-tolerant control (issue 30).
    ("# True: one torque axis left, output redefined", "indi", "indi.failure_modes()[1].single_axis", True, 0),
    ("# the spin: about 40 rad/s", "indi", "float(abs(run.omega[run.t > 10, 2]).mean())", 40.0, 1.0),
    # Tilted rotors: the 6-D wrench ACAI the README prints (issue 31: it printed 1.3378).
    ("# True 1.3392 (a convex hull agrees)", "tilted", "bool(tilted.is_fully_actuated)", True, 0),
    ("# True 1.3392 (a convex hull agrees)", "tilted", "float(rf.acai(tilted, axes='wrench'))", 1.3392, 0.5e-4),
    # Relaxed hover (issue 30).
    ("# 10 strategies, best first", "analysis", "len(analysis)", 10, 0),
    ("# 15.22 rad/s, rotors 2, 3, 4 at 2.459 N each, 6.04 N headroom", "best",
     "(round(best.spin_rate_rad_s, 2), best.carrying, [round(float(f), 3) for f in best.thrust_n[1:]], round(best.thrust_margin_n, 2))",
     (15.22, [2, 3, 4], [2.459, 2.459, 2.459], 6.04), 0),
    # Issue 31: the remaining numbers the README's code blocks print.
    ("# HoverTrim: leans 0.76 degrees into the wind", "trim", "round(math.degrees(trim.state[7]), 2)", 0.76, 0),
    ("# HoverTrim: leans 0.76 degrees into the wind", "trim", "trim.saturated_rotors", (), 0),
    ("print(grid.table.num_rows, grid.controllable_count())        # 50 points, in memory", "grid", "grid.table.num_rows", 50, 0),
    ("# PPNPNN: Du's PPNNPN, mirrored", "grid", "rf.design_search(hexa).best().spins", "PPNPNN", 0),
    ("give_up_yaw=True).max_thrust_n)  # 17 N", "p", "rf.hover_thrust_margin(ke, efficiency=[1, 1, 0, 1], give_up_yaw=True).max_thrust_n", 17.0, 0.5),
    ("# omega_2* = 6355, alpha_2* = 0.2476", "wang", "round(float(trim.command[2])), round(float(trim.command[3]), 4)", (6355, 0.2476), 0),
    ('vpp.controllability(vpp.linearize(wang, trim, inputs="wang")).rank      # 12', "wang",
     'vpp.controllability(vpp.linearize(wang, trim, inputs="wang")).rank', 12, 0),
    ("# 4 chunk files + _rotorfault.json", "small", "sorted(p.name for p in Path('campaign.parquet').iterdir() if p.suffix == '.parquet').__len__()", 4, 0),
    ("# 4 chunk files + _rotorfault.json", "small", "(Path('campaign.parquet') / '_rotorfault.json').is_file()", True, 0),
    # The simulator's time grid, step-size guard and divergence detection (issue 18).
    ("# [0.  0.3 0.6 0.9 1. ]: ends at 1.0 s exactly", "limited", "[round(float(v), 12) for v in fall.t]", [0.0, 0.3, 0.6, 0.9, 1.0], 0),
    ("# [0.  0.3 0.6 0.9 1. ]: ends at 1.0 s exactly", "limited", "float(fall.t[-1])", 1.0, 0.0),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited", "lost.events[0].kind", "altitude-loss", 0),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited", "lost.events[0].time_s", 0.6389, 0.5e-4),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited",
     "lost.events[0].time_s - math.sqrt(2 * 2.0 / quad.gravity_m_s2)", 0.0, 1e-12),
    ("# 1.7e-06 of the amplitude lost per step", "limited", "1 - abs(1 + h + h**2 / 2 + h**3 / 6 + h**4 / 24)", 1.7e-6, 0.05e-6),
    ("at `MAX_RATE_STEP = 0.25` it loses 1.7e-6 of the amplitude per step", "limited", "rf.MAX_RATE_STEP", 0.25, 0.0),
    ("# substeps: ... = 3.75 exceeds 0.25 ...: use substeps >= 15", "limited",
     "refused.startswith('substeps: ') and '= 3.75 exceeds 0.25' in refused and 'use substeps >= 15 ' in refused", True, 0),
]


def test_readme_claims_hold(executed: tuple[Path, list[dict[str, Any]], str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 21 item 6: every README claim of the kind "this snippet gives X" that runs in
    seconds is checked here, and the README still makes it (word for word)."""
    text = README.read_text(encoding="utf-8")
    work, namespaces, _ = executed
    monkeypatch.chdir(work)
    for line, defines, expression, expected, tolerance in CLAIMS:
        assert line in text, f"README no longer says {line!r}"
        namespace = next(ns for ns in namespaces if defines in ns)
        value = eval(expression, {"math": math, "Path": Path, **namespace})  # noqa: S307 - the README's own code
        if isinstance(expected, float):
            assert abs(value - expected) <= tolerance, (expression, value)
        else:
            assert value == expected, (expression, value)


#: The README's commands: (the command as the README shows it, what the test runs when it is not
#: that command verbatim or None, the exit status). A stand-in keeps every option the README
#: shows and changes only a size (the README says so beside the scans: "the test runs them with
#: --step 0.5"), a placeholder (NAME), or a bracketed alternative.
COMMANDS: list[tuple[str, str | None, int]] = [
    ("rotorfault failures --airframe hexa-ppnnpn --max-failed 2", None, 0),
    ("rotorfault airframes", None, 0),
    ("rotorfault acai -a hexa-ppnnpn --efficiency 1,1,0.5,1,1,1 [--give-up-yaw] [--formula facet-margin]",
     "rotorfault acai -a hexa-ppnnpn --efficiency 1,1,0.5,1,1,1 --give-up-yaw --formula facet-margin", 0),
    ("rotorfault acai -a hexa-ppnnpn --efficiency 1,1,0.5,1,1,1", None, 0),
    ("rotorfault failures -a NAME -k 2", "rotorfault failures -a octo-x -k 2", 0),
    ("rotorfault scan -a hexa-pnpnpn --rotors 1,2,5 --step 0.04 --plot fig4.png", "rotorfault scan -a hexa-pnpnpn --rotors 1,2,5 --step 0.04 --plot fig4.png --force", 0),
    ("rotorfault scan -a octo-x --rotors 1,2,3,4,5,6 --step 0.05 --out scan.parquet [--give-up-yaw]",
     "rotorfault scan -a octo-x --rotors 1,2,3,4,5,6 --step 0.5 --out scan.parquet --give-up-yaw --axis max_thrust_n=6,7,8 --chunk-points 500", 0),
    ("rotorfault scan ... --out scan.parquet --resume",
     "rotorfault scan -a octo-x --rotors 1,2,3,4,5,6 --step 0.5 --out scan.parquet --give-up-yaw --axis max_thrust_n=6,7,8 --chunk-points 500 --resume", 0),
    ("[--dask local:2 | --dask tcp://host:8786]",
     "rotorfault scan -a octo-x --rotors 1,2,3,4,5,6 --step 0.5 --out scan-dask.parquet --chunk-points 300 --dask local:2", 0),
    ("rotorfault scan -a hexa-pnpnpn --rotors 1,2,5 --step 0.04 --out fig4.parquet --plot fig4.png",
     "rotorfault scan -a hexa-pnpnpn --rotors 1,2,5 --step 0.04 --out fig4.parquet --plot fig4.png --force", 0),
    ("rotorfault design -a hexa-pnpnpn", None, 0),
    ("rotorfault design -a octo-x --parameter arm_length_m --values 0.2,0.3 --top 3", None, 0),
    ("rotorfault simulate examples/quad-x-rotor-failure.toml --plot failure.png",
     f"rotorfault simulate {ROOT / 'examples' / 'quad-x-rotor-failure.toml'} --plot failure.png --force", 0),
    ("rotorfault certify --airframe vehicle.params [--require single|double] [--require-axes thrust,roll,pitch[,yaw]] [--json cert.json|-]",
     "rotorfault certify --airframe vehicle.params --require single --json cert.json", 3),  # only by spinning (README)
    ("rotorfault certify --airframe vehicle.params [--require single|double] [--require-axes thrust,roll,pitch[,yaw]] [--json cert.json|-]",
     "rotorfault certify --airframe vehicle.params --require single --require-axes thrust,roll,pitch --json cert2.json", 0),
    ("rotorfault certify --airframe vehicle.params [--require single|double] [--require-axes thrust,roll,pitch[,yaw]] [--json cert.json|-]",
     "rotorfault certify --airframe vehicle.params --require double --json -", 3),
    ("rotorfault campaign campaign.toml --plot campaign.png", "rotorfault campaign campaign.toml --plot campaign.png --force", 0),
    ("rotorfault campaign campaign.toml --out runs/", None, 0),
    ("rotorfault campaign campaign.toml --out runs/ --resume", None, 0),
    ("rotorfault campaign campaign.toml --out runs/ --force", None, 0),
    ("rotorfault campaign campaign.toml --out runs/ --dask local:2", "rotorfault campaign campaign.toml --out runs/ --dask local:2 --force", 0),
]
#: The README's commands run by another test (long, or needing what that test sets up).
RUN_ELSEWHERE = {
    "pip install . && rotorfault reproduce --quick --out report/": "the main job: .ci/run, compared by tests/cross/test_report_browser.py",
    'pip install ".[test]" && cargo test --workspace && python -m pytest': "the test command itself (.ci/run)",
    'pip install ".[docs]" && mkdocs build --strict': "tests/cross/test_docs.py",
    "rotorfault ftc-report --out report/": "tests/cli/test_cli.py (every scenario) and tests/cli/test_formats.py",
    "rotorfault lanzon-report --out DIR [--force] [--quick] [--runs N]": "tests/cli/test_formats.py (--quick --runs 2)",
    "rotorfault vpp-report --out DIR [--quick] [--force]": "tests/cli/test_formats.py (--quick), tests/papers/test_wang_flights.py",
    "maturin build --release --out dist/": "tests/cross/test_wheel.py",
    "rotorfault campaign campaign.toml --out runs/ --dask tcp://host:8786": "needs a running cluster: the same code path as --dask local:2 above",
    "rotorfault campaign --suite deciding --runs N [--out DIR] [--dask ...]": "tests/studies/test_deciding.py (a one-run-per-cell campaign through the CLI)",
    "rotorfault campaign --suite deciding --runs 1000 --out DIR": "about 10 minutes: benches/deciding_campaign.py; the CLI path is tests/studies/test_deciding.py's",
    "rotorfault campaign --suite deciding --sensing mocap": "about 7 minutes at 1,000 runs per cell: the CLI path on sensors is tests/studies/test_deciding.py's (one run per cell, --sensing mocap)",
    "rotorfault campaign --tune [--quick]": "about a minute even with --quick: tests/studies/test_campaign.py runs tune() on a small campaign",
}
#: A small campaign file for the README's `rotorfault campaign campaign.toml` lines.
CAMPAIGN_TOML = "runs = 6\nchunk_size = 3\nduration_s = 8.0\n"


def readme_text() -> str:
    """The README with its line breaks and indentation folded to single spaces."""
    return " ".join(README.read_text(encoding="utf-8").split())


@pytest.mark.parametrize(("shown", "run", "status"), COMMANDS, ids=[f"{i}" for i in range(len(COMMANDS))])
def test_readme_command_runs(shown: str, run: str | None, status: int, executed: tuple[Path, list[dict[str, Any]], str],
                             monkeypatch: pytest.MonkeyPatch) -> None:
    assert " ".join(shown.split()) in readme_text(), f"README no longer shows {shown!r}"
    work, _, _ = executed  # the directory the README's blocks ran in: vehicle.params is there
    monkeypatch.chdir(work)
    (work / "campaign.toml").write_text(CAMPAIGN_TOML)
    args = shlex.split(run or shown)
    assert args[0] == "rotorfault"
    result = CliRunner().invoke(cli, args[1:])
    assert result.exit_code == status, (args, result.output, result.exception)


def test_readme_commands_run_elsewhere_are_shown() -> None:
    text = readme_text()
    for shown, where in RUN_ELSEWHERE.items():
        assert shown in text, f"README no longer shows {shown!r}"
        for path in re.findall(r"(?:tests|\.ci)/[\w/.]+\w", where):
            assert (ROOT / path).exists(), (shown, path)


def test_every_readme_command_is_tested() -> None:
    """Every command the README shows in backticks or a shell block is in :data:`COMMANDS` or
    :data:`RUN_ELSEWHERE`, so a new one cannot go untested."""
    text = README.read_text(encoding="utf-8")
    shown = {" ".join(c.split()) for c in re.findall(r"`(rotorfault [^`]+)`", text)}
    for block in re.findall(r"```(?:bash|sh|text)\n(.*?)```", text, flags=re.S):
        shown |= {" ".join(line.split("#")[0].split()) for line in block.splitlines() if line.startswith("rotorfault ")}
    covered = [" ".join(c.split()) for c, _, _ in COMMANDS] + list(RUN_ELSEWHERE)
    untested = sorted(c for c in shown if not any(c in k or k in c for k in covered))
    assert not untested, untested


def test_readme_terminal_output_is_what_the_command_prints() -> None:
    """The "What you get" block: the command's table now, token by token (the README shows the
    terminal's box drawing; piped output is plain text with the same cells)."""
    text = README.read_text(encoding="utf-8")
    block = re.search(r"```text\n\$ (rotorfault failures [^\n]+)\n(.*?)```", text, flags=re.S)
    assert block is not None
    command, shown = block.group(1), block.group(2)
    boxes = re.compile(r"[\u2500-\u257f]")
    result = CliRunner().invoke(cli, shlex.split(command)[1:])
    assert result.exit_code == 0, result.output
    assert boxes.sub(" ", shown).split() == result.output.split()


def test_readme_design_search_and_wang_tables() -> None:
    """The numbers the README prints in its prose and tables that come from quick computations:
    the design search's results and Wang's trim, speed ranges and fixed-pitch comparison, each at
    the digits printed. (The flights' tables are compared by the paper tests: tests/control/
    test_ftc.py, tests/papers/, tests/cross/test_normal_numbers.py.)"""
    import rotorfault as rf
    from rotorfault import vpp
    from rotorfault.papers import wang

    text = readme_text()

    def shown(phrase: str) -> None:
        assert phrase in text, f"README no longer says {phrase!r}"

    hexa = rf.design_search(rf.Airframe.preset("hexa-pnpnpn")).to_pandas().set_index("spins")
    shown("best **PPNPNN** (Du's PPNNPN mirrored): ACAI 1.1295, controllable after 4 of 6 single failures, 3 of 15 double; "
          "PNPNPN: 1.4861, ACAI 0 after every single failure (Du Table II), 0 of 6. Giving up yaw, every assignment survives all 6.")
    assert hexa.index[0] == "PPNPNN" and round(hexa.loc["PPNPNN", "acai_facet_margin"], 4) == 1.1295
    assert (hexa.loc["PPNPNN", "controllable_single"], hexa.loc["PPNPNN", "controllable_double"]) == (4, 3)
    assert round(hexa.loc["PNPNPN", "acai_facet_margin"], 4) == 1.4861 and hexa.loc["PNPNPN", "controllable_single"] == 0
    assert (hexa["controllable_single_give_up_yaw"] == 6).all()

    octo = rf.Airframe.preset("octo-x")
    ranked = rf.design_search(octo).to_pandas()
    shown("best **PNPNPNPN**: all 8 single failures (worst ACAI 1.0461) and all 28 double failures (worst 0.1586) "
          "stay controllable; next PPNNPPNN (8/8, 24/28). With 0.2 m arms PPNNPPNN ranks first (worst single 0.8804).")
    best, second = ranked.iloc[0], ranked.iloc[1]
    assert best["spins"] == "PNPNPNPN" and (best["controllable_single"], best["controllable_double"]) == (8, 28)
    assert (round(best["worst_single_acai_facet_margin"], 4), round(best["worst_double_acai_facet_margin"], 4)) == (1.0461, 0.1586)
    assert second["spins"] == "PPNNPPNN" and (second["controllable_single"], second["controllable_double"]) == (8, 24)
    short = rf.design_search(octo, parameter="arm_length_m", values=[0.2]).to_pandas()
    assert short.iloc[0]["spins"] == "PPNNPPNN" and round(short.iloc[0]["worst_single_acai_facet_margin"], 4) == 0.8804

    vehicle = vpp.preset("wang")
    trim = vpp.trim(vehicle, failed=(1,), speeds={3: 9000})
    shown("| omega_2*, alpha_2* at omega_3 = 9000 | 6355, 0.2476 | 6355.12, 0.24760 |")
    assert (round(float(trim.command[2]), 2), round(float(trim.command[3]), 5)) == (6355.12, 0.24760)
    speeds = vpp.feasible_speeds(vehicle, failed=(1,))
    shown("| feasible omega_2 | [6201, 7067] | [6201.74, 7064.23]")
    shown("| feasible omega_3 | [8782, 10000] | [8783.85, 10000]")
    assert tuple(round(v, 2) for v in speeds.free_speed_range) == (6201.74, 7064.23)
    assert (round(speeds.fixed_speed_range[0], 2), round(speeds.fixed_speed_range[1])) == (8783.85, 10000)
    assert round(speeds.free_torque_range_nm[1], 4) == 2.0012

    cases = {(c.vehicle.split(" (")[0], c.failed): c for c in wang.fixed_pitch_comparison()}
    shown("| VPP (thrust in [-13, 13] N) | healthy | yes | 12 | yes | none | 2.9528 |")
    shown("| fixed pitch, standard layout | healthy | yes | 12 | yes | none | 0.7030 |")
    shown("| fixed pitch, standard layout | failed | no: 15.4 rad/s^2 of yaw left |")
    assert round(cases["VPP", ()].acai, 4) == 2.9528 and cases["VPP", ()].rank == 12 and cases["VPP", (1,)].rank == 12
    assert cases["VPP", (1,)].acai == -math.inf
    sec34 = [c for key, c in cases.items() if key[0].startswith("fixed pitch, Sec. 3.4")]
    assert sorted(c.rank for c in sec34) == [8, 10]
    standard = {key[1]: c for key, c in cases.items() if key[0].startswith("fixed pitch, standard")}
    assert round(standard[()].acai, 4) == 0.7030 and standard[()].rank == 12
    assert round(standard[(1,)].residual, 1) == 15.4 and standard[(1,)].rank is None
