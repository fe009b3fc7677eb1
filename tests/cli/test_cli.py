"""The command line: rich tables on success, one-line errors (exit 1, no traceback) on bad input."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotorfault.papers import ke as ke_paper
from rotorfault.cli import cli


def run(*args: str) -> tuple[int, str, str]:
    result = CliRunner().invoke(cli, list(args), terminal_width=200)
    return result.exit_code, result.stdout, result.stderr


def test_airframes_lists_presets() -> None:
    code, out, _ = run("airframes")
    assert code == 0
    for name in ("hexa-pnpnpn", "hexa-ppnnpn", "quad-x", "ke-quadcopter", "lanzon-quadrotor"):
        assert name in out


def test_failures_main_job() -> None:
    code, out, _ = run("failures", "--airframe", "hexa-ppnnpn", "--max-failed", "2")
    assert code == 0
    for value in ("1.1295", "0.7221", "0.4510", "undefined"):
        assert value in out
    assert "8 of 22 cases controllable" in out
    # Rotor 5 or 6 failed: eq. (13) prints 0 but hover is infeasible; the table says so.
    assert "0.0000*" in out and "eq. (13) prints 0 here although hover is infeasible" in out


def test_acai_with_efficiency_and_give_up_yaw() -> None:
    code, out, _ = run("acai", "--airframe", "hexa-pnpnpn", "--efficiency", "0,1,1,1,1,1")
    assert code == 0 and "0.0000" in out and "hover wrench on the boundary" in out
    code, out, _ = run("acai", "-a", "hexa-pnpnpn", "--efficiency", "0,1,1,1,1,1", "--give-up-yaw")
    assert code == 0 and "thrust, roll, pitch" in out and "controllable" in out


def test_acai_accepts_a_toml_file(tmp_path: Path) -> None:
    import rotorfault as rf

    path = tmp_path / "frame.toml"
    path.write_text((Path(rf.__file__).parent / "presets" / "hexa-ppnnpn.toml").read_text())
    code, out, _ = run("acai", "--airframe", str(path))
    assert code == 0 and "1.1295" in out


def test_scan_writes_a_plot(tmp_path: Path) -> None:
    png = tmp_path / "fig4.png"
    code, out, _ = run("scan", "-a", "hexa-pnpnpn", "--rotors", "1,2,5", "--step", "0.1", "--plot", str(png))
    assert code == 0, out
    assert "1,331 points" in out
    assert png.stat().st_size > 10_000


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("acai", "--airframe", "hexa"), "preset: unknown airframe 'hexa'"),
        (("acai", "--airframe", "hexa-ppnnpn", "--efficiency", "1,1,2,1,1,1"), "efficiency[2] (rotor 3): must lie in [0, 1]"),
        (("acai", "--airframe", "hexa-ppnnpn", "--efficiency", "1,1"), "efficiency: expected 6 entries"),
        (("acai", "--airframe", "hexa-ppnnpn", "--efficiency", "1,x"), "efficiency: expected comma-separated numbers"),
        (("acai", "--airframe", "nan.toml"), "nan.toml"),
        (("failures", "--airframe", "quad-x", "--max-failed", "5"), "max_failed: must be between 0 and"),
        (("failures", "--airframe", "quad-x", "--max-failed", "-1"), "max_failed: must be >= 0"),
        (("scan", "--airframe", "quad-x", "--rotors", "1,9"), "rotors: rotor numbers run from 1 to 4"),
        (("scan", "--airframe", "hexa-pnpnpn", "--step", "0.3"), "step: must divide 1 evenly"),
    ],
)
def test_errors_are_one_line(args: tuple[str, ...], message: str) -> None:
    code, out, err = run(*args)
    assert code == 1
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err + out


def test_markup_in_a_name_is_printed_literally(tmp_path: Path) -> None:
    import rotorfault as rf

    text = (Path(rf.__file__).parent / "presets" / "quad-x.toml").read_text()
    path = tmp_path / "odd.toml"
    path.write_text(text.replace('name = "quad-x"', 'name = "[/bold] [red]odd"'))
    for command in ("acai", "failures"):
        code, out, err = run(command, "--airframe", str(path))
        assert code == 0, err
        assert "[/bold] [red]odd" in out


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("failures", "-a", "hexa-ppnnpn", "-k", "99999999999999999999999"), "max_failed: must be at most"),
        (("scan", "-a", "hexa-pnpnpn", "--rotors", "1,2", "--plot", "x.png"), "needs three swept rotors"),
        (("scan", "-a", "hexa-pnpnpn", "--rotors", "1,2,3,4", "--step", "0.001"), "exceed the in-memory limit"),
    ],
)
def test_more_errors_are_one_line(args: tuple[str, ...], message: str) -> None:
    code, out, err = run(*args)
    assert code == 1 and message in err and "Traceback" not in err + out
    assert len(err.strip().splitlines()) == 1


def test_bad_toml_file_is_one_line(tmp_path: Path) -> None:
    path = tmp_path / "broken.toml"
    path.write_text("name = 'x'\nmass_kg = 'heavy'\n")
    code, _, err = run("acai", "--airframe", str(path))
    assert code == 1 and "broken.toml" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("text", ["\x1e", "a = 1\u2028", "\x1b[2J = 1"])
def test_a_file_quoted_in_an_error_cannot_break_its_line(tmp_path: Path, text: str) -> None:
    """The TOML parser quotes the offending line; a record separator in it split the message
    for any reader using Python's line rule (long hostile run), and a terminal escape would act."""
    path = tmp_path / "broken.toml"
    path.write_text(text, encoding="utf-8")
    code, _, err = run("acai", "--airframe", str(path))
    assert code == 1 and err.startswith("Error: ") and len(err.strip().splitlines()) == 1, err
    assert "\x1b" not in err and "\x1e" not in err


def test_installed_console_script() -> None:
    script = Path(sys.executable).parent / "rotorfault"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "rotorfault"]
    done = subprocess.run(
        [*command, "failures", "--airframe", "hexa-ppnnpn", "--max-failed", "1"],
        capture_output=True, text=True, check=False, timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "0.7221" in done.stdout
    bad = subprocess.run([*command, "acai", "--airframe", "nope"], capture_output=True, text=True, check=False, timeout=120)
    assert bad.returncode == 1 and "Traceback" not in bad.stderr
    assert bad.stderr.strip().startswith("Error: preset: unknown airframe 'nope'")


EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "quad-x-rotor-failure.toml"


def test_simulate_example_scenario(tmp_path: Path) -> None:
    png = tmp_path / "run.png"
    code, out, err = run("simulate", str(EXAMPLE), "--plot", str(png))
    assert code == 0, err
    # The quad falls its 10 m and crashes at 2.76 s (without a ground: 13.7 m down, tilt at 3.05 s).
    assert "crashed at t = 2.75" in out and "hit the ground at" in out and "no divergence" not in out
    assert png.stat().st_size > 20_000


def test_simulate_hover_scenario_with_everything(tmp_path: Path) -> None:
    path = tmp_path / "hover.toml"
    path.write_text(
        'airframe = "quad-x"\nduration_s = 3.0\n[initial]\nposition_m = [0.0, 0.0, -5.0]\n'
        '[controller]\nkind = "lqr-hover"\n[drag]\nlinear_n_s_m = 0.1\n[wind]\nvelocity_m_s = [1.0, 0.0, 0.0]\n'
        "[noise]\nstd = [0.01, 0.01, 0.001, 0.001]\nseed = 2\n"
    )
    code, out, err = run("simulate", str(path))
    assert code == 0, err
    assert re.search(r"^verdict\s+holds$", out, re.M) and "no divergence" not in out


def test_simulate_calls_a_vehicle_that_falls_without_touching_the_ground_drifts(tmp_path: Path) -> None:
    """Issue 28: no controller, 10 m up, 1.38 s: it falls 9.3 m (0.5 g t^2) and the run ends before
    the ground. Never "no divergence": the verdict over the window says it drifts (not held)."""
    path = tmp_path / "fall.toml"
    path.write_text('airframe = "quad-x"\nduration_s = 1.38\n[controller]\nkind = "none"\n')
    code, out, err = run("simulate", str(path))
    assert code == 0, err
    assert "no divergence" not in out and "holds" not in out
    assert "drifts (window: 0.00 m off, 9.33 m" in out and "\ndrifts: airborne to the end" in out


def test_simulate_a_scenario_on_sensors(tmp_path: Path) -> None:
    """A [sensing] table flies the hover LQR on mocap and the estimator; the table says what the
    controller flew on and the estimate's error (sub-millimetre with the 0.2 mm mocap)."""
    path = tmp_path / "sensed.toml"
    path.write_text('airframe = "quad-x"\nduration_s = 2.0\n[sensing]\nsuite = "mocap"\nseed = 4\n')
    code, out, err = run("simulate", str(path))
    assert code == 0, err
    assert re.search(r"^verdict\s+holds$", out, re.M) and re.search(r"^flew on\s+mocap$", out, re.M), out
    rms_mm = float(re.search(r"position RMS\s*│?\s*([0-9.]+) mm", out).group(1))  # type: ignore[union-attr]
    assert 0 < rms_mm < 0.35, out


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('airframe = "quad-x"\n[sensing]\nsuite = "vicon"\n', "sensing.suite: expected one of mocap, gnss, rtk"),
        ('airframe = "quad-x"\n[sensing]\nrate = 1\n', "sensing: unknown key(s) rate"),
        ('airframe = "quad-x"\n[sensing]\n[noise]\nsnr_db = 15.0\n', "noise, sensing: a run flies on one of them"),
        ('airframe = "quad-x"\ncolour = 1\n', "unknown key(s) colour"),
        ('airframe = "quad-x"\n[controller]\nkind = "pid"\n', "controller.kind: must be one of"),
        ('airframe = "quad-x"\n[[fault]]\nrotor = 5\ntime_s = 1.0\n', "fault[0].rotor: rotor numbers run from 1 to 4, got 5"),
        ('airframe = "quad-x"\n[drag]\nlinear = 1.0\n', "drag: unknown key(s) linear"),
        ('airframe = "quad-x"\ndt_s = -1.0\n', "dt_s: must be > 0"),
        ("airframe = [", "scenario.toml: "),
        ("duration_s = 1.0\n", "airframe: required"),
        ('airframe = "quad-x"\nground_z_m = "low"\n', "ground_z_m: expected a real number"),
        ('airframe = "quad-x"\nground_z_m = nan\n', "ground_z_m: must be finite"),
        ('airframe = "quad-x"\nground = "no"\n', "ground: expected True or False"),
        ('airframe = "quad-x"\nground = false\nground_z_m = 1.0\n', "ground_z_m, ground: a ground height"),
        ('airframe = "quad-x"\n[initial]\nposition_m = [0.0, 0.0, 0.0]\n',
         "initial.position_m[2]: the run starts on or below the ground"),
    ],
)
def test_simulate_bad_scenarios_are_one_line(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    code, out, err = run("simulate", str(path))
    assert code == 1, out
    assert message in err and "Traceback" not in err + out
    assert len(err.strip().splitlines()) == 1


def test_ftc_report_writes_table_and_figures(tmp_path: Path) -> None:
    result = CliRunner().invoke(cli, ["ftc-report", "--out", str(tmp_path), "--laws", "feedforward,baseline"])
    assert result.exit_code == 0, result.output
    report = (tmp_path / "ftc-report.md").read_text()
    assert "| one-failure | feedforward | yes | drifts (window: " in report
    assert "| fault-free | feedforward | yes | holds |" in report
    assert "| one-failure | baseline | yes | diverged (tilt) at " in report
    # Fig. 7's pair falls the 10 m to the ground (issue #28: it used to fall 15.5 m and tilt).
    assert "| two-adjacent-front | feedforward | no | crashed at 12.34 s (" in report
    assert "- drifts: airborne to the end but neither holding nor circling" in report
    counted = {v: report.count(f"| {v}") for v in ("holds", "drifts", "circles", "crashed", "diverged")}
    assert f"Verdicts counted ({2 * len(ke_paper.scenarios())} flights): " + ", ".join(f"{v} {n}" for v, n in counted.items()) in report
    rows = (tmp_path / "ftc-report.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * len(ke_paper.scenarios())
    assert (tmp_path / "primary-axis.png").stat().st_size > 10_000
    assert (tmp_path / "one-failure.png").exists()


def test_ftc_report_bad_law_is_a_one_line_error(tmp_path: Path) -> None:
    result = CliRunner().invoke(cli, ["ftc-report", "--out", str(tmp_path), "--laws", "magic", "--no-figures"])
    assert result.exit_code == 1
    assert "law:" in result.output
