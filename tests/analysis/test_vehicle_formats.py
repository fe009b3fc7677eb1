"""PX4 parameter files, RotorPy parameter dicts, ArduPilot frames and ``rotorfault certify``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli

DATA = Path(__file__).resolve().parents[1] / "data"


def test_px4_quad_x_matches_the_preset_up_to_numbering() -> None:
    px4 = rf.Airframe.from_px4_params(DATA / "px4-quad-x.params", gravity_m_s2=9.80)
    preset = rf.Airframe.preset("quad-x")
    assert px4.mass_kg == pytest.approx(preset.mass_kg, rel=1e-12)  # from MPC_THR_HOVER
    # PX4 motors 1 front right, 2 rear left, 3 front left, 4 rear right = preset rotors 1, 3, 4, 2.
    order = [0, 2, 3, 1]
    b_px4, b_preset = px4.effectiveness_matrix(), preset.effectiveness_matrix()[:, order]
    np.testing.assert_allclose(b_px4[:3], b_preset[:3], rtol=0, atol=1e-15)
    # PX4 spins front right anticlockwise, the preset clockwise: the mirror-image quad-X.
    np.testing.assert_allclose(b_px4[3], -b_preset[3], rtol=0, atol=1e-15)
    assert float(rf.acai(px4)) == pytest.approx(float(rf.acai(preset)), abs=1e-12)


def test_px4_hexa_x_matches_the_planar_form() -> None:
    px4 = rf.Airframe.from_px4_params(DATA / "px4-hexa-x.params")
    angles = [90, 270, 330, 150, 30, 210]  # PX4 motors 1..6, from the nose towards the right
    planar = rf.Airframe(np.radians(angles), [0.5] * 6, ["cw", "ccw", "cw", "ccw", "ccw", "cw"], [6.5] * 6,
                         px4.mass_kg, px4.inertia_kg_m2, 0.05, gravity_m_s2=px4.gravity_m_s2)
    np.testing.assert_allclose(px4.effectiveness_matrix(), planar.effectiveness_matrix(), rtol=0, atol=1e-15)
    assert px4.hover_thrust_n == pytest.approx(0.5 * 6 * 6.5, rel=1e-12)  # MPC_THR_HOVER x full thrust


def test_px4_round_trip_is_exact(tmp_path: Path) -> None:
    a = rf.Airframe.from_px4_params(DATA / "px4-hexa-x.params")
    path = tmp_path / "again.params"
    path.write_text(a.to_px4_params())
    b = rf.Airframe.from_px4_params(path, name=a.name)
    assert b == a
    assert b.to_px4_params() == a.to_px4_params()


def test_px4_errors_name_the_parameter(tmp_path: Path) -> None:
    bad = tmp_path / "bad.params"
    bad.write_text("1\t1\tCA_ROTOR_COUNT\t1\t6\n1\t1\tCA_ROTOR0_AZ\t0\t9\n1\t1\tMPC_THR_HOVER\t0.5\t9\n")
    with pytest.raises(ValueError, match="CA_ROTOR0_AX/AY/AZ: the thrust axis of rotor 1 is zero"):
        rf.Airframe.from_px4_params(bad)
    bad.write_text("1\t1\tCA_ROTOR_COUNT\t1\t6\n")
    with pytest.raises(ValueError, match="mass_kg: PX4 parameters carry no vehicle mass"):
        rf.Airframe.from_px4_params(bad)


HUMMINGBIRD = {  # RotorPy's hummingbird_params (d = 0.043 m arms)
    "mass": 0.500, "Ixx": 3.65e-3, "Iyy": 3.68e-3, "Izz": 7.03e-3, "Ixy": 0.0, "Iyz": 0.0, "Ixz": 0.0,
    "num_rotors": 4,
    "rotor_pos": {
        "r1": 0.043 * np.array([0.70710678118, 0.70710678118, 0]),
        "r2": 0.043 * np.array([0.70710678118, -0.70710678118, 0]),
        "r3": 0.043 * np.array([-0.70710678118, -0.70710678118, 0]),
        "r4": 0.043 * np.array([-0.70710678118, 0.70710678118, 0]),
    },
    "rotor_directions": np.array([1, -1, 1, -1]),
    "rotor_speed_min": 0, "rotor_speed_max": 1500, "k_eta": 5.57e-06, "k_m": 1.36e-07,
}


def test_rotorpy_hummingbird() -> None:
    a = rf.Airframe.from_rotorpy(HUMMINGBIRD)
    # RotorPy: weight m g with g = 9.81; its allocation f_to_TM, converted FLU -> FRD.
    assert a.hover_thrust_n == pytest.approx(0.5 * 9.81, rel=1e-15)
    k = 1.36e-07 / 5.57e-06
    pos = np.array(list(HUMMINGBIRD["rotor_pos"].values()))  # type: ignore[union-attr]
    f_to_tm = np.vstack([np.ones(4), np.cross(pos, [0, 0, 1]).T[:2], k * HUMMINGBIRD["rotor_directions"]])
    np.testing.assert_allclose(a.effectiveness_matrix(), f_to_tm * np.array([[1], [1], [-1], [-1]]), atol=1e-15)
    assert a.max_thrust_n[0] == pytest.approx(5.57e-06 * 1500**2)
    back = rf.Airframe.from_rotorpy(a.to_rotorpy())
    np.testing.assert_allclose(back.effectiveness_matrix(), a.effectiveness_matrix(), rtol=1e-15, atol=1e-18)
    rotorpy = pytest.importorskip("rotorpy.vehicles.multirotor")
    params = pytest.importorskip("rotorpy.vehicles.hummingbird_params").quad_params
    # RotorPy's own Hummingbird dict (it carries keys ours does not need, e.g. the motor lag
    # tau_m): the hover thrust RotorPy computes equals ours from the same dict.
    vehicle = rotorpy.Multirotor(params)
    assert rf.Airframe.from_rotorpy(params).hover_thrust_n == pytest.approx(vehicle.mass * vehicle.g, rel=1e-12)


def test_ardupilot_frames() -> None:
    kwargs = {"arm_length_m": 0.275, "max_thrust_n": 6.125, "mass_kg": 1.535,
              "inertia_kg_m2": [0.0411, 0.0478, 0.0599], "drag_torque_ratio_m": 0.1, "gravity_m_s2": 9.80}
    quad = rf.Airframe.ardupilot("quad", "x", **kwargs)
    assert quad.name == "ardupilot-quad-x"
    # ArduPilot quad X: motor 1 front right CCW, 2 rear left CCW, 3 front left CW, 4 rear right CW.
    np.testing.assert_allclose(np.degrees(quad.arm_angle_rad), [45, 225, 315, 135])
    assert quad.spin == ("ccw", "ccw", "cw", "cw")
    assert float(rf.acai(rf.Airframe.ardupilot(2, 0, **kwargs))) == pytest.approx(float(rf.acai(rf.Airframe.preset("hexa-pnpnpn"))), abs=1e-12)
    with pytest.raises(ValueError, match="frame_class, frame_type: 1/7 is not supported"):
        rf.Airframe.ardupilot(1, 7, **kwargs)


def test_certify_cli(tmp_path: Path) -> None:
    runner = CliRunner()
    hexa = DATA / "px4-hexa-x.params"
    result = runner.invoke(cli, ["certify", "--airframe", str(hexa), "--require", "single"])
    assert result.exit_code == 0, result.output
    out = tmp_path / "cert.json"
    result = runner.invoke(cli, ["certify", "-a", "hexa-pnpnpn", "--require", "single", "--json", str(out)])
    assert result.exit_code == 0, result.output  # every single failure: hover by spinning (Du Table II)
    data = json.loads(out.read_text())
    single = [c for c in data["cases"] if len(c["failed"]) == 1]
    assert all(c["hover"] == "give-up-yaw" and c["drop_axes"] == ["yaw"] for c in single)
    result = runner.invoke(cli, ["certify", "-a", "quad-x", "--require", "double", "--json", "-"])
    assert result.exit_code == 3  # two adjacent rotors lost: no hover at all
    data = json.loads(result.stdout)
    assert data["cases"][0]["hover"] == "all-axes" and data["cases"][0]["thrust_to_weight"] == pytest.approx(24.5 / 15.043)
