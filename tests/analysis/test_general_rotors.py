"""General rotor geometry (positions and thrust axes, PX4 style), the 6 x m wrench matrix and the
full-wrench axes: planar presets unchanged, a tilted fully actuated hexacopter checked against an
independent convex hull."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import rotorfault as rf


def tilted_hexa(tilt_deg: float = 20.0) -> rf.Airframe:
    """Arms at 0, 60, ..., 300 deg, each rotor tilted about its arm, alternately left and right."""
    angle = np.radians(np.arange(6) * 60.0)
    tilt = np.radians(tilt_deg)
    position = 0.275 * np.stack([np.cos(angle), np.sin(angle), np.zeros(6)], axis=1)
    tangent = np.stack([-np.sin(angle), np.cos(angle), np.zeros(6)], axis=1)
    side = np.array([-1.0, 1.0] * 3)[:, None]  # tilt moments add to the drag torques
    axis = np.cos(tilt) * np.array([0.0, 0.0, -1.0]) + np.sin(tilt) * side * tangent
    return rf.Airframe.from_rotors(
        position_m=position, thrust_axis=axis, spin=["cw", "ccw"] * 3, max_thrust_n=[6.125] * 6,
        mass_kg=1.535, inertia_kg_m2=[0.0411, 0.0478, 0.0599], drag_torque_ratio_m=0.1,
        gravity_m_s2=9.80, name="tilted-hexa",
    )


def hull_distance(matrix: np.ndarray, lower: np.ndarray, upper: np.ndarray, g: np.ndarray) -> float:
    """Independent ACAI: the signed distance from g to the boundary of {B f : lower <= f <= upper}
    from scipy's convex hull of the images of the box's corners."""
    m = matrix.shape[1]
    corners = np.array([[upper[k] if (c >> k) & 1 else lower[k] for k in range(m)] for c in range(2**m)])
    hull = ConvexHull(corners @ matrix.T)
    return float(np.min(-(hull.equations[:, :-1] @ g + hull.equations[:, -1])))


@pytest.mark.parametrize("name", rf.Airframe.presets())
def test_planar_presets_keep_du_eq5_bit_for_bit(name: str) -> None:
    """The planar short form still computes Du's eq. (5) with the same operations (bitwise), and the
    general form of the same geometry gives the same ACAI and failure verdicts (to rounding)."""
    a = rf.Airframe.preset(name)
    assert a.is_planar
    r, phi = a.arm_length_m, a.arm_angle_rad
    expected = np.stack([np.ones(a.rotor_count), -r * np.sin(phi), r * np.cos(phi), a.spin_sign * a.drag_torque_ratio_m])
    expected = expected * a.efficiency
    assert np.array_equal(a.effectiveness_matrix(), expected)
    # The 6 x m matrix holds the same rows: -F_z is the thrust row, the torques are L, M, N.
    w = a.wrench_matrix()
    assert np.array_equal(-w[2], expected[0]) and np.array_equal(w[3:], expected[1:])
    assert np.array_equal(w[:2], np.zeros((2, a.rotor_count)))
    general = rf.Airframe.from_rotors(
        position_m=a.position_m, spin=a.spin, max_thrust_n=a.max_thrust_n, min_thrust_n=a.min_thrust_n,
        mass_kg=a.mass_kg, inertia_kg_m2=a.inertia_kg_m2, drag_torque_ratio_m=a.drag_torque_ratio_m,
        gravity_m_s2=a.gravity_m_s2,
    )
    assert not general.is_planar
    np.testing.assert_allclose(general.effectiveness_matrix(), expected, rtol=0, atol=1e-15)
    for yaw in (False, True):
        assert float(rf.acai(general, give_up_yaw=yaw)) == pytest.approx(float(rf.acai(a, give_up_yaw=yaw)), abs=1e-12)
    t1, t2 = rf.failure_table(a, max_failed=2), rf.failure_table(general, max_failed=2)
    assert [(c.controllable, c.controllable_give_up_yaw) for c in t1] == [(c.controllable, c.controllable_give_up_yaw) for c in t2]
    assert all(c.acai_wrench is None for c in t1)  # planar frames are not fully actuated


def test_tilted_hexa_is_fully_actuated_and_its_6d_acai_matches_a_convex_hull() -> None:
    hexa = tilted_hexa()
    w = hexa.wrench_matrix()
    assert w.shape == (6, 6) and np.linalg.matrix_rank(w) == 6 and hexa.is_fully_actuated
    value = rf.acai(hexa, axes="wrench")
    independent = hull_distance(w, hexa.min_thrust_n, hexa.max_thrust_n, hexa.hover_wrench_6d)
    assert value > 0 and value.hover == "inside"
    assert float(value) == pytest.approx(independent, rel=1e-9)
    report = rf.controllability(hexa, axes="wrench")
    assert report.controllable and report.virtual_control_dimension == 6 and report.controllability_rank == 12
    # One failed rotor leaves 5 columns: rank 5 < 6, no 6-D authority (-inf), as the table says.
    table = rf.failure_table(hexa, max_failed=1)
    assert table[0].acai_wrench == pytest.approx(independent, rel=1e-9)
    assert all(c.acai_wrench == -np.inf and c.controllable_wrench is False for c in table[1:])
    # Hover margin along the wrench's thrust direction: every rotor at full thrust, cos(20 deg) each.
    margin = rf.hover_thrust_margin(hexa, axes="wrench")
    assert margin.max_thrust_n == pytest.approx(6 * 6.125 * np.cos(np.radians(20.0)), rel=1e-7)


def test_tilted_hexa_6d_acai_with_degraded_rotor_against_the_hull() -> None:
    hexa = tilted_hexa(30.0).with_efficiency([1, 0.6, 1, 1, 0.8, 1])
    value = rf.acai(hexa, axes="wrench", formula="facet-margin")
    independent = hull_distance(hexa.wrench_matrix(), hexa.min_thrust_n, hexa.max_thrust_n, hexa.hover_wrench_6d)
    assert float(value) == pytest.approx(independent, rel=1e-9, abs=1e-12)


def test_allocation_of_the_full_wrench() -> None:
    hexa = tilted_hexa()
    target = hexa.hover_wrench_6d + np.array([1.0, -0.5, 0.0, 0.0, 0.0, 0.05])  # push sideways, level
    a = rf.allocate(hexa, target, axes="wrench")
    assert a.status == "optimal"
    np.testing.assert_allclose(hexa.wrench_matrix() @ a.commands, target, atol=1e-9)
    assert np.all(a.commands >= -1e-12) and np.all(a.commands <= 6.125 + 1e-12)
    with pytest.raises(ValueError, match="give_up_yaw: contradicts"):
        rf.acai(hexa, give_up_yaw=True, axes="wrench")
    with pytest.raises(ValueError, match="axes: must be one of"):
        rf.acai(hexa, axes="sideways")  # type: ignore[arg-type]


def test_general_toml_round_trip_and_schema() -> None:
    hexa = tilted_hexa()
    text = hexa.to_toml()
    assert "thrust_axis" in text and rf.Airframe.from_toml_str(text) == hexa
    mixed = rf.Airframe.from_toml_str(
        """
name = "mixed"
mass_kg = 1.0
inertia_kg_m2 = [0.01, 0.01, 0.02]
drag_torque_ratio_m = 0.02
[[rotor]]
arm_angle_deg = 45
arm_length_m = 0.2
spin = "cw"
max_thrust_n = 6
[[rotor]]
position_m = [-0.1414213562373095, 0.1414213562373095, -0.02]
spin = "ccw"
drag_torque_ratio_m = 0.03
max_thrust_n = 6
"""
    )
    assert not mixed.is_planar
    np.testing.assert_array_equal(mixed.thrust_axis[1], [0, 0, -1])
    np.testing.assert_array_equal(mixed.rotor_drag_torque_ratio_m, [0.02, 0.03])
    assert mixed.wrench_matrix()[5, 1] == 0.03


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"thrust_axis": [[0, 0, 0]] + [[0, 0, -1]] * 3}, r"thrust_axis\[0\] \(rotor 1\): must be a unit vector"),
        ({"thrust_axis": [[0, 0, -1]] * 3 + [[0, 0.1, -1]]}, r"thrust_axis\[3\] \(rotor 4\): must be a unit vector"),
        ({"position_m": [[0.2, 0, 0]] * 2 + [[-0.2, 0, 0], [0, 0.2, 0]], "spin": ["cw", "cw", "ccw", "ccw"]},
         r"position_m\[1\] \(rotor 2\): rotor 2 coincides with rotor 1"),
        ({"position_m": [[np.nan, 0, 0], [0.2, 0, 0], [-0.2, 0, 0], [0, 0.2, 0]]}, r"position_m\[0\]\[0\] \(rotor 1\): must be finite"),
        ({"rotor_drag_torque_ratio_m": [0.1, -0.1, 0.1, 0.1]}, r"rotor_drag_torque_ratio_m\[1\] \(rotor 2\): must be >= 0"),
        ({"position_m": [[0.2, 0, 0]] * 4 + [[0, 0, 0]]}, r"position_m, thrust_axis: position_m must be 4 x 3"),
    ],
)
def test_bad_general_rotors_are_named(change: dict[str, object], message: str) -> None:
    kwargs: dict[str, object] = {
        "position_m": [[0.2, 0, 0], [0, 0.2, 0], [-0.2, 0, 0], [0, -0.2, 0]],
        "spin": ["cw", "ccw", "cw", "ccw"], "max_thrust_n": [5.0] * 4, "mass_kg": 1.0,
        "inertia_kg_m2": [0.01, 0.01, 0.02], "drag_torque_ratio_m": 0.02,
    }
    kwargs.update(change)
    with pytest.raises(ValueError, match=message):
        rf.Airframe.from_rotors(**kwargs)  # type: ignore[arg-type]


def test_toml_with_both_forms_is_refused() -> None:
    with pytest.raises(ValueError, match="either the planar form .* or the general form"):
        rf.Airframe.from_toml_str(
            'name = "x"\nmass_kg = 1.0\ninertia_kg_m2 = [1.0, 1.0, 1.0]\ndrag_torque_ratio_m = 0.1\n'
            '[[rotor]]\narm_angle_deg = 0\narm_length_m = 0.2\nposition_m = [0.2, 0, 0]\nspin = "cw"\nmax_thrust_n = 5\n'
        )


def test_the_simulator_refuses_tilted_rotors_by_name() -> None:
    with pytest.raises(ValueError, match=r"thrust_axis\[0\] \(rotor 1\): the simulator models upright rotors only"):
        rf.Simulator(tilted_hexa(), dt_s=0.01)
