"""The airframe model: presets, TOML files, immutability, the effectiveness matrix."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import rotorfault as rf

EXPECTED_PRESETS = {
    "quad-x",
    "quad-plus",
    "hexa-pnpnpn",
    "hexa-ppnnpn",
    "octo-x",
    "ke-quadcopter",
    "lanzon-quadrotor",
}


def test_presets_ship_and_load() -> None:
    names = rf.Airframe.presets()
    assert EXPECTED_PRESETS <= set(names)
    for name in names:
        airframe = rf.Airframe.preset(name)
        assert airframe.name == name
        assert airframe.description
        assert airframe.rotor_count == len(airframe.arm_angle_rad)


def _quad(**overrides: object) -> rf.Airframe:
    kwargs: dict[str, object] = dict(
        arm_angle_rad=np.radians([45, 135, 225, 315]),
        arm_length_m=[0.2] * 4,
        spin=["cw", "ccw", "cw", "ccw"],
        max_thrust_n=[5.0] * 4,
        mass_kg=1.0,
        inertia_kg_m2=[0.01, 0.01, 0.02],
        drag_torque_ratio_m=0.05,
    )
    kwargs.update(overrides)
    return rf.Airframe(**kwargs)  # type: ignore[arg-type]


def test_constructor_defaults_and_matrix() -> None:
    quad = _quad()
    assert quad.gravity_m_s2 == 9.81
    assert np.array_equal(quad.min_thrust_n, np.zeros(4))
    assert np.array_equal(quad.efficiency, np.ones(4))
    assert quad.spin == ("cw", "ccw", "cw", "ccw")
    assert np.array_equal(quad.spin_sign, [-1, 1, -1, 1])
    b = quad.effectiveness_matrix()
    assert b.shape == (4, 4)
    phi = np.radians([45, 135, 225, 315])
    np.testing.assert_allclose(b[1], -0.2 * np.sin(phi), atol=1e-16)
    np.testing.assert_allclose(b[2], 0.2 * np.cos(phi), atol=1e-16)
    np.testing.assert_array_equal(b[3], 0.05 * np.array([-1, 1, -1, 1]))
    assert quad.hover_thrust_n == pytest.approx(9.81, rel=1e-15)


def test_spin_accepts_signs_and_words_equally() -> None:
    by_sign = _quad(spin=[-1, 1, -1, 1])
    by_word = _quad(spin=["clockwise", "anticlockwise", "CW", "counterclockwise"])
    np.testing.assert_array_equal(by_sign.effectiveness_matrix(), by_word.effectiveness_matrix())


def test_with_efficiency_returns_a_new_airframe_and_leaves_inputs_alone() -> None:
    quad = _quad()
    eta = np.array([1.0, 0.5, 1.0, 0.0])
    eta_before = eta.copy()
    degraded = quad.with_efficiency(eta)
    assert np.array_equal(eta, eta_before)
    assert np.array_equal(quad.efficiency, np.ones(4))
    assert np.array_equal(degraded.efficiency, eta)
    np.testing.assert_allclose(degraded.effectiveness_matrix(), quad.effectiveness_matrix() * eta, atol=0)
    assert np.array_equal(quad.with_failed_rotors([2, 4]).efficiency, [1, 0, 1, 0])


def test_property_arrays_are_read_only_copies() -> None:
    quad = _quad()
    arr = quad.max_thrust_n
    with pytest.raises(ValueError):
        arr[0] = 100.0
    assert quad.max_thrust_n is not arr


def test_user_arrays_are_not_mutated_or_aliased() -> None:
    angles = np.radians([45.0, 135.0, 225.0, 315.0])
    thrust = np.full(4, 5.0)
    quad = _quad(arm_angle_rad=angles, max_thrust_n=thrust)
    thrust[0] = 1.0  # the airframe keeps its own copy
    assert quad.max_thrust_n[0] == 5.0
    assert np.array_equal(angles, np.radians([45.0, 135.0, 225.0, 315.0]))


def test_negative_minimum_thrust_is_allowed() -> None:
    vpp = _quad(min_thrust_n=[-2.0] * 4)
    assert np.array_equal(vpp.min_thrust_n, [-2.0] * 4)
    # A reversible quad keeps authority in every direction around hover: more than unidirectional.
    assert rf.acai(vpp) > rf.acai(_quad())


def test_single_rotor_airframe_is_valid_but_not_controllable() -> None:
    mono = rf.Airframe([0.0], [0.0], ["cw"], [20.0], 1.0, [0.01, 0.01, 0.02], 0.05)
    report = rf.controllability(mono)
    assert report.effectiveness_rank == 1
    assert report.acai == -math.inf
    assert report.verdict == "uncontrollable: rank B_f deficient"


def test_toml_round_trip(tmp_path: Path) -> None:
    text = (Path(rf.__file__).parent / "presets" / "hexa-ppnnpn.toml").read_text()
    path = tmp_path / "mine.toml"
    path.write_text(text.replace('name = "hexa-ppnnpn"', 'name = "mine"'))
    mine = rf.Airframe.from_toml(path)
    assert mine.name == "mine"
    np.testing.assert_array_equal(
        mine.effectiveness_matrix(), rf.Airframe.preset("hexa-ppnnpn").effectiveness_matrix()
    )


def test_toml_radians_and_optional_fields() -> None:
    text = """
name = "bi"
mass_kg = 1
inertia_kg_m2 = [0.01, 0.01, 0.02]
drag_torque_ratio_m = 0.01
gravity_m_s2 = 3.71
[[rotor]]
arm_angle_rad = 1.5707963267948966
arm_length_m = 0.2
spin = "ccw"
max_thrust_n = 4
min_thrust_n = -1
efficiency = 0.5
"""
    a = rf.Airframe.from_toml_str(text)
    assert a.gravity_m_s2 == 3.71 and a.min_thrust_n[0] == -1.0 and a.efficiency[0] == 0.5
    assert a.arm_angle_rad[0] == pytest.approx(math.pi / 2, abs=1e-16)


def test_to_toml_pickle_and_equality_are_exact() -> None:
    import pickle

    for name in rf.Airframe.presets():
        preset = rf.Airframe.preset(name).with_efficiency(
            np.linspace(0.0, 1.0, rf.Airframe.preset(name).rotor_count)
        )
        again = rf.Airframe.from_toml_str(preset.to_toml())
        assert again == preset
        assert pickle.loads(pickle.dumps(preset)) == preset
        np.testing.assert_array_equal(again.effectiveness_matrix(), preset.effectiveness_matrix())
    assert rf.Airframe.preset("quad-x") != rf.Airframe.preset("quad-plus")
    assert rf.Airframe.preset("quad-x") != "quad-x"


def test_repr() -> None:
    assert repr(rf.Airframe.preset("quad-x")) == "Airframe('quad-x', 4 rotors, 1.535 kg)"
