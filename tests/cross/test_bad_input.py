"""Bad input raises ValueError (values) or TypeError (types) naming the field and the rule: never a
panic, a NaN result or a silent clamp."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore

GOOD: dict[str, Any] = dict(
    arm_angle_rad=[0.0, 1.0, 2.0, 3.0],
    arm_length_m=[0.2] * 4,
    spin=[1, -1, 1, -1],
    max_thrust_n=[5.0] * 4,
    mass_kg=1.0,
    inertia_kg_m2=[0.01, 0.01, 0.02],
    drag_torque_ratio_m=0.05,
)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"arm_angle_rad": [0.0, np.nan, 2.0, 3.0]}, r"arm_angle_rad\[1\] \(rotor 2\): must be finite"),
        ({"arm_length_m": [0.2, 0.2, np.inf, 0.2]}, r"arm_length_m\[2\] \(rotor 3\): must be finite"),
        ({"arm_length_m": [0.2, -0.2, 0.2, 0.2]}, r"arm_length_m\[1\] \(rotor 2\): must be >= 0"),
        ({"max_thrust_n": [5.0, 5.0, 5.0, -np.inf]}, r"max_thrust_n\[3\]"),
        ({"min_thrust_n": [0.0, 6.0, 0.0, 0.0]}, r"min_thrust_n\[1\] \(rotor 2\): must not exceed max_thrust_n"),
        ({"efficiency": [1.0, 1.5, 1.0, 1.0]}, r"efficiency\[1\] \(rotor 2\): must lie in \[0, 1\]"),
        ({"efficiency": [1.0, -0.1, 1.0, 1.0]}, r"efficiency\[1\]"),
        ({"mass_kg": -1.0}, r"mass_kg: must be > 0"),
        ({"mass_kg": 0.0}, r"mass_kg: must be > 0"),
        ({"mass_kg": float("nan")}, r"mass_kg: must be finite"),
        ({"inertia_kg_m2": [0.01, -0.01, 0.02]}, r"inertia_kg_m2 \(Jy\): must be > 0"),
        ({"inertia_kg_m2": [0.01, 0.01]}, r"inertia_kg_m2: expected 3 entries"),
        ({"drag_torque_ratio_m": -0.1}, r"drag_torque_ratio_m: must be >= 0"),
        ({"gravity_m_s2": float("inf")}, r"gravity_m_s2: must be finite"),
        ({"arm_length_m": [0.2] * 3}, r"arm_length_m: expected 4 entries"),
        ({"spin": [1, -1, 0.5, -1]}, r"spin\[2\] \(rotor 3\): must be \+1"),
        ({"spin": ["cw", "ccw", "up", "cw"]}, r"spin\[2\] \(rotor 3\): must be 'cw'"),
        ({"arm_angle_rad": [[0.0, 1.0]]}, r"arm_angle_rad: expected a 1-D array"),
        ({"arm_angle_rad": []}, r"arm_angle_rad: at least one rotor"),
    ],
)
def test_constructor_values(override: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        rf.Airframe(**{**GOOD, **override})


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"mass_kg": "1.0"}, r"mass_kg: expected a real number"),
        ({"mass_kg": True}, r"mass_kg: expected a real number"),
        ({"max_thrust_n": ["a", "b", "c", "d"]}, r"max_thrust_n: expected real numbers"),
        ({"max_thrust_n": "5555"}, r"max_thrust_n: expected an array of numbers"),
        ({"arm_length_m": [0.2, None, 0.2, 0.2]}, r"arm_length_m: expected real numbers"),
        ({"arm_length_m": [0.2j] * 4}, r"arm_length_m: expected real numbers"),
        ({"spin": "cwcw"}, r"spin: expected one direction per rotor"),
        ({"spin": 5}, r"spin: expected a sequence"),
        ({"name": 3}, r"name: expected a string"),
    ],
)
def test_constructor_types(override: dict[str, Any], message: str) -> None:
    with pytest.raises(TypeError, match=message):
        rf.Airframe(**{**GOOD, **override})


def test_analysis_arguments(ppnnpn: rf.Airframe) -> None:
    with pytest.raises(ValueError, match=r"efficiency: expected 6 entries"):
        rf.acai(ppnnpn, [1.0] * 5)
    with pytest.raises(ValueError, match=r"efficiency\[0\] \(rotor 1\): must be finite"):
        rf.acai(ppnnpn, [np.nan] + [1.0] * 5)
    with pytest.raises(ValueError, match=r"efficiency\[5\] \(rotor 6\): must lie in \[0, 1\]"):
        rf.controllability(ppnnpn, [1.0] * 5 + [2.0])
    with pytest.raises(ValueError, match=r"efficiencies: expected 6 columns"):
        rf.acai_batch(ppnnpn, np.ones((3, 5)))
    with pytest.raises(ValueError, match=r"efficiencies\[2, 4\] \(rotor 5\): must be finite and lie in \[0, 1\]"):
        etas = np.ones((3, 6))
        etas[2, 4] = -0.5
        rf.acai_batch(ppnnpn, etas)
    with pytest.raises(ValueError, match=r"efficiencies: expected a 2-D array"):
        rf.acai_batch(ppnnpn, np.ones(6))
    with pytest.raises(ValueError, match=r"formula: must be \"eq13\" or \"facet-margin\""):
        rf.acai(ppnnpn, formula="exact")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"formula"):
        rf.acai(ppnnpn, formula=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"give_up_yaw: expected True or False"):
        rf.acai(ppnnpn, give_up_yaw="yes")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"airframe: expected rotorfault.Airframe"):
        rf.acai("hexa-ppnnpn")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"max_failed: must be between 0 and the number of rotors \(6\)"):
        rf.failure_table(ppnnpn, max_failed=7)
    with pytest.raises(ValueError, match=r"max_failed: must be >= 0"):
        rf.failure_table(ppnnpn, max_failed=-1)
    with pytest.raises(TypeError, match=r"max_failed: expected an integer"):
        rf.failure_table(ppnnpn, max_failed=1.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"rotors: rotor numbers run from 1 to 6, got 0"):
        ppnnpn.with_failed_rotors([0])


def test_overflowing_numbers_are_value_errors(ppnnpn: rf.Airframe) -> None:
    with pytest.raises(ValueError, match=r"mass_kg: must be finite"):
        rf.Airframe(**{**GOOD, "mass_kg": 10**400})
    with pytest.raises(ValueError, match=r"max_failed: must be at most"):
        rf.failure_table(ppnnpn, max_failed=2**70)
    with pytest.raises(ValueError, match=r"f_min, f_max, g_vec: too large"):
        rf.acai_from_matrix(np.eye(2), [-1e308, -1e308], [1e308, 1e308], [0, 0])
    # Counts beyond 64 bits or below 0: one conversion in the bindings, a ValueError naming the field.
    for field in ("substeps", "record_every"):
        for value in (10**33, -1):
            with pytest.raises(ValueError, match=rf"^{field}: must be a count"):
                _rfcore.SimulationConfig(**{field: value})
    with pytest.raises(ValueError, match=r"^max_iterations: must be a count"):
        _rfcore.AllocationSettings(max_iterations=2**64)
    with pytest.raises(ValueError, match=r"^noise.seed: must be a count"):
        _rfcore.SensorNoise(relative_std=0.0, absolute_std=[0.0] * 12, seed=-1)
    # The campaign checks its step counts up front (found by the harness).
    with pytest.raises(ValueError, match=r"^substeps: must be at most"):
        rf.studies.Campaign(runs=1, substeps=10**33)
    # Large but representable magnitudes are computed, not rounded to zero.
    assert rf.acai_from_matrix(np.eye(2) * 1e300, [0, 0], [1, 1], [0.5e300, 0.5e300]) == pytest.approx(0.5e300, rel=1e-12)


def test_huge_problems_are_refused_quickly() -> None:
    with pytest.raises(ValueError, match=r"effectiveness_matrix: at most 12 rows"):
        rf.acai_from_matrix(np.ones((200_000, 1)), [0.0], [1.0], np.zeros(200_000))
    with pytest.raises(ValueError, match=r"effectiveness_matrix: .* facet groups, more than"):
        rf.acai_from_matrix(np.ones((12, 40)), np.zeros(40), np.ones(40), np.zeros(12))
    with pytest.raises(ValueError, match=r"step, rotors: .* exceed the in-memory limit"):
        rf.efficiency_scan(rf.Airframe.preset("hexa-pnpnpn"), rotors=(1, 2, 3, 4), step=0.001)


def test_report_and_acai_agree_near_degeneracy() -> None:
    """The rank of B_f in the report and the -inf of the ACAI come from one test."""
    for k_mu in (5e-10, 1e-9, 2e-9, 1e-8):
        hexa = rf.Airframe.preset("hexa-pnpnpn")
        a = rf.Airframe(hexa.arm_angle_rad, hexa.arm_length_m, hexa.spin_sign, hexa.max_thrust_n,
                        hexa.mass_kg, hexa.inertia_kg_m2, k_mu, gravity_m_s2=hexa.gravity_m_s2)
        report = rf.controllability(a)
        assert report.acai == rf.acai(a)
        assert (report.effectiveness_rank == 4) == (report.acai != -np.inf)
    big = rf.Airframe(**{**GOOD, "arm_length_m": [1e300] * 4})
    assert rf.controllability(big).acai == rf.acai(big)


def test_rotor_lists_name_the_field(ppnnpn: rf.Airframe, tmp_path: Path) -> None:
    with pytest.raises(TypeError, match=r"rotors: expected a sequence of 1-based rotor numbers"):
        ppnnpn.with_failed_rotors(3)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"rotors: expected a sequence"):
        rf.efficiency_scan(ppnnpn, rotors=3)  # type: ignore[arg-type]
    latin1 = tmp_path / "latin1.toml"
    latin1.write_bytes('name = "h\xe9xa"\n'.encode("latin-1"))
    with pytest.raises(ValueError, match=r"latin1.toml: not UTF-8 text"):
        rf.Airframe.from_toml(latin1)


def test_matrix_entry_point() -> None:
    b = np.eye(2)
    with pytest.raises(ValueError, match=r"f_min\[1\]: must not exceed f_max\[1\]"):
        rf.acai_from_matrix(b, [0, 3], [1, 2], [0, 0])
    with pytest.raises(ValueError, match=r"g_vec: expected 2 entries"):
        rf.acai_from_matrix(b, [0, 0], [1, 1], [0])
    with pytest.raises(ValueError, match=r"f_max: expected 2 entries"):
        rf.acai_from_matrix(b, [0, 0], [1, 1, 1], [0, 0])
    with pytest.raises(ValueError, match=r"effectiveness_matrix\[0, 1\]: must be finite"):
        rf.acai_from_matrix(np.array([[1.0, np.nan], [0.0, 1.0]]), [0, 0], [1, 1], [0, 0])
    with pytest.raises(ValueError, match=r"g_vec\[0\]: must be finite"):
        rf.acai_from_matrix(b, [0, 0], [1, 1], [np.inf, 0])
    with pytest.raises(ValueError, match=r"effectiveness_matrix: expected a 2-D array"):
        rf.acai_from_matrix(np.ones(3), [0, 0], [1, 1], [0, 0])
    with pytest.raises(ValueError, match=r"effectiveness_matrix: expected at least one row"):
        rf.acai_from_matrix(np.ones((0, 2)), [0, 0], [1, 1], [])


def test_non_contiguous_and_integer_inputs_work_and_stay_untouched(ppnnpn: rf.Airframe) -> None:
    etas = np.ones((4, 12))[:, ::2]  # a strided view
    assert not etas.flags.c_contiguous
    values = rf.acai_batch(ppnnpn, etas)
    assert np.all(values == rf.acai(ppnnpn))
    assert rf.acai(ppnnpn, [1, 1, 1, 1, 1, 1]) == rf.acai(ppnnpn)


def test_unknown_preset_and_bad_toml(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"preset: unknown airframe 'hexa'; available: .*hexa-ppnnpn"):
        rf.Airframe.preset("hexa")
    with pytest.raises(TypeError, match=r"preset: expected a preset name"):
        rf.Airframe.preset(3)  # type: ignore[arg-type]
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nmass_kg = 1.0\n')
    with pytest.raises(ValueError, match=r"bad.toml: .*missing field `inertia_kg_m2`"):
        rf.Airframe.from_toml(bad)
    bad.write_text("name = [unclosed\n")
    with pytest.raises(ValueError, match=r"bad.toml: "):
        rf.Airframe.from_toml(bad)
    text = (Path(rf.__file__).parent / "presets" / "quad-x.toml").read_text()
    bad.write_text(text.replace("mass_kg = 1.535", "mass_kg = -1.535"))
    with pytest.raises(ValueError, match=r"bad.toml: mass_kg: must be > 0"):
        rf.Airframe.from_toml(bad)
    bad.write_text(text.replace("max_thrust_n = 6.125", "max_thrust_n = 6.125\ncolour = 'red'", 1))
    with pytest.raises(ValueError, match=r"bad.toml: .*unknown field `colour`"):
        rf.Airframe.from_toml(bad)
    bad.write_text(text.replace("arm_angle_deg = 45", "arm_angle_deg = 45\narm_angle_rad = 0.7", 1))
    with pytest.raises(ValueError, match=r"bad.toml: \[\[rotor\]\] number 1: give exactly one of"):
        rf.Airframe.from_toml(bad)
    bad.write_text(text.replace('spin = "cw"', 'spin = "up"', 1))
    with pytest.raises(ValueError, match=r"bad.toml: \[\[rotor\]\] number 1.spin: must be"):
        rf.Airframe.from_toml(bad)
    with pytest.raises(FileNotFoundError):
        rf.Airframe.from_toml(tmp_path / "missing.toml")
