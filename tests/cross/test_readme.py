"""The README's Python example runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib
import pytest

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_python_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)
    assert blocks, "README has a Python example"
    matplotlib.use("Agg")
    monkeypatch.chdir(tmp_path)
    for block in blocks:
        exec(compile(block, str(README), "exec"), {})
    assert (tmp_path / "fig4.png").stat().st_size > 10_000
    assert "hexa-pnpnpn" in capsys.readouterr().out


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
    ("# 0.16 mm after the first second", "sensed", "round(1e3 * float(run.estimate_position_error_m[400:].max()), 2)", 0.16, 0.005),
    ("# 'off-station' (see the findings below)", "preset", "ke_paper.run_scenario('one-failure').metrics.outcome", "off-station", 0),
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
    # The simulator's time grid, step-size guard and divergence detection (issue 18).
    ("# [0.  0.3 0.6 0.9 1. ]: ends at 1.0 s exactly", "limited", "[round(float(v), 12) for v in fall.t]", [0.0, 0.3, 0.6, 0.9, 1.0], 0),
    ("# [0.  0.3 0.6 0.9 1. ]: ends at 1.0 s exactly", "limited", "float(fall.t[-1])", 1.0, 0.0),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited", "lost.events[0].kind", "altitude-loss", 0),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited", "lost.events[0].time", 0.6389, 0.5e-4),
    ("# altitude-loss 0.6389 s = sqrt(2 x 2 m / g), not 0.65", "limited",
     "lost.events[0].time - math.sqrt(2 * 2.0 / quad.gravity_m_s2)", 0.0, 1e-12),
    ("# 1.7e-06 of the amplitude lost per step", "limited", "1 - abs(1 + h + h**2 / 2 + h**3 / 6 + h**4 / 24)", 1.7e-6, 0.05e-6),
    ("at `MAX_RATE_STEP = 0.25` it loses 1.7e-6 of the amplitude per step", "limited", "rf.MAX_RATE_STEP", 0.25, 0.0),
    ("# substeps: ... = 3.75 exceeds 0.25 ...: use substeps >= 15", "limited",
     "refused.startswith('substeps: ') and '= 3.75 exceeds 0.25' in refused and 'use substeps >= 15 ' in refused", True, 0),
]


def test_readme_claims_hold(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 21 item 6: every README claim of the kind "this snippet gives X" that runs in
    seconds is checked here, and the README still makes it (word for word)."""
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    monkeypatch.chdir(tmp_path)
    namespaces = []
    for block in blocks:
        namespace: dict[str, object] = {}
        exec(compile(block, str(README), "exec"), namespace)
        namespaces.append(namespace)
    for line, defines, expression, expected, tolerance in CLAIMS:
        assert line in text, f"README no longer says {line!r}"
        namespace = next(ns for ns in namespaces if defines in ns)
        value = eval(expression, namespace)  # noqa: S307 - the README's own code
        if isinstance(expected, float):
            assert abs(value - expected) <= tolerance, (expression, value)
        else:
            assert value == expected, (expression, value)
