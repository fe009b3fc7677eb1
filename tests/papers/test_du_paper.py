"""Du, Quan, Yang, Cai (JGCD 2015): every number the paper prints, from the shipped presets.

Table values are printed to 4 decimals; we require agreement to half a unit in the last place
(TABLE_TOL = 0.5e-4).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotorfault as rf

TABLE_TOL = 0.5e-4


def test_table_i_parameters_and_eq17_matrix(pnpnpn: rf.Airframe) -> None:
    """Table I parameters, and B_f equals eq. (17) printed entry by entry."""
    assert pnpnpn.mass_kg == 1.535 and pnpnpn.gravity_m_s2 == 9.80
    assert np.array_equal(pnpnpn.inertia_kg_m2, [0.0411, 0.0478, 0.0599])
    assert np.all(pnpnpn.arm_length_m == 0.275) and np.all(pnpnpn.max_thrust_n == 6.125)
    eta = np.array([1.0, 0.9, 0.8, 0.7, 0.6, 0.5])
    r, k, s = 0.275, 0.1, math.sqrt(3) / 2
    e1, e2, e3, e4, e5, e6 = eta
    eq17 = np.array(
        [
            [e1, e2, e3, e4, e5, e6],
            [0, -s * e2 * r, -s * e3 * r, 0, s * e5 * r, s * e6 * r],
            [e1 * r, 0.5 * e2 * r, -0.5 * e3 * r, -e4 * r, -0.5 * e5 * r, 0.5 * e6 * r],
            [-e1 * k, e2 * k, -e3 * k, e4 * k, -e5 * k, e6 * k],
        ]
    )
    np.testing.assert_allclose(pnpnpn.with_efficiency(eta).effectiveness_matrix(), eq17, rtol=0, atol=1e-15)


def test_table_ii_pnpnpn(pnpnpn: rf.Airframe) -> None:
    healthy = rf.controllability(pnpnpn)
    assert healthy.controllability_rank == 8
    assert abs(healthy.acai - 1.4861) < TABLE_TOL
    assert healthy.controllable
    for rotor in range(1, 7):
        report = rf.controllability(pnpnpn.with_failed_rotors([rotor]))
        assert report.controllability_rank == 8
        assert report.acai == 0.0 and math.copysign(1.0, report.acai) == 1.0
        assert not report.controllable
        assert report.verdict == "uncontrollable: hover wrench on the boundary"


@pytest.mark.parametrize(
    ("rotor", "expected", "controllable"),
    [(1, 0.7221, True), (2, 0.4510, True), (3, 0.4510, True), (4, 0.7221, True), (5, 0.0, False), (6, 0.0, False)],
)
def test_table_iii_ppnnpn(ppnnpn: rf.Airframe, rotor: int, expected: float, controllable: bool) -> None:
    report = rf.controllability(ppnnpn.with_failed_rotors([rotor]))
    assert report.controllability_rank == 8
    assert abs(report.acai - expected) < TABLE_TOL
    assert report.controllable is controllable


def test_table_iii_healthy(ppnnpn: rf.Airframe) -> None:
    assert abs(rf.acai(ppnnpn) - 1.1295) < TABLE_TOL


def test_table_iii_zero_for_rotor_5_is_an_eq13_artifact(ppnnpn: rf.Airframe) -> None:
    """Eq. (13) prints 0, but the hover wrench is outside: the facet margin sees -0.2133.
    (tests/cross/test_independent.py confirms infeasibility by LP and the margin by a convex hull.)"""
    failed = ppnnpn.with_failed_rotors([5])
    assert rf.acai(failed) == 0.0
    assert abs(rf.acai(failed, formula="facet-margin") + 0.2133) < TABLE_TOL
    assert rf.controllability(failed).verdict == "uncontrollable: hover wrench outside the attainable set"


def test_failure_table_single_failures_reproduce_tables(ppnnpn: rf.Airframe) -> None:
    table = rf.failure_table(ppnnpn, max_failed=1)
    assert len(table) == 7
    acai = table.to_arrays()["acai"]
    np.testing.assert_allclose(acai, [1.1295, 0.7221, 0.4510, 0.4510, 0.7221, 0.0, 0.0], atol=TABLE_TOL)
    assert [row.controllable for row in table] == [True, True, True, True, True, False, False]
    text = str(table)
    assert text.count("0.0000*") == 2 and "eq. (13) prints 0 here" in text
    assert "0.0000*" not in str(rf.failure_table(rf.Airframe.preset("hexa-pnpnpn"), max_failed=1))


def test_fig4_region(pnpnpn: rf.Airframe) -> None:
    """Fig. 4: eta1, eta2, eta5 on a 0.04 grid. The healthy corner is controllable, any fully failed
    rotor is not (Table II), and the region is monotone: raising an efficiency never leaves it."""
    scan = rf.efficiency_scan(pnpnpn, rotors=(1, 2, 5), step=0.04)
    assert scan.points.shape == (17576, 3)
    ok = scan.controllable.reshape(26, 26, 26)
    assert ok[-1, -1, -1]
    assert not ok[0].any() and not ok[:, 0].any() and not ok[:, :, 0].any()
    for axis in range(3):
        assert np.all(np.diff(ok.astype(int), axis=axis) >= 0)
    # The paper's region is a proper subset of the cube: both sides are non-trivial.
    assert 0.05 < scan.controllable_fraction < 0.95
    # Consistent with single evaluations.
    i = 12345
    eta = np.ones(6)
    eta[[0, 1, 4]] = scan.points[i]
    assert rf.acai(pnpnpn, eta) == scan.acai[i]


def test_ke_preset_layout_makes_the_printed_yaw_row_right() -> None:
    """Ke's printed yaw row c[1, -1, 1, -1] with the rotor layout of Figs. 8, 16, 17 (1 front
    right, then clockwise): M has rank 4. (With Remark 2's printed angles it would have rank 3.)"""
    m = rf.Airframe.preset("ke-quadcopter").effectiveness_matrix()
    np.testing.assert_allclose(m[3], 0.0166 * np.array([1, -1, 1, -1]), atol=1e-15)
    assert np.linalg.matrix_rank(m) == 4
    s = 0.125 / np.sqrt(2)
    np.testing.assert_allclose(m[1], [-s, -s, s, s], atol=1e-15)  # roll: right rotors 1, 2
    np.testing.assert_allclose(m[2], [s, -s, -s, s], atol=1e-15)  # pitch: front rotors 1, 4


def test_lanzon_preset_matches_lanzon_eq2() -> None:
    """Lanzon eq. (2) (z-up body frame) converted to FRD: L = tau_p, M = -tau_q, N = -tau_r."""
    a = rf.Airframe.preset("lanzon-quadrotor")
    l, d = 0.255, 2.4e-3
    expected = np.array(
        [
            [1, 1, 1, 1],
            [0, -l, 0, l],  # tau_p = l (f4 - f2)
            [l, 0, -l, 0],  # -tau_q = -l (f3 - f1)
            [-d, d, -d, d],  # -tau_r = -d (f1 - f2 + f3 - f4)
        ]
    )
    np.testing.assert_allclose(a.effectiveness_matrix(), expected, atol=1e-15)
    assert a.mass_kg == 0.5 and np.all(a.max_thrust_n == 5.0)


def test_quadrotor_after_one_failure_only_spinning_is_left() -> None:
    """A quad-x that loses a rotor cannot hold yaw (3 columns cannot span 4 axes), and without
    yaw the opposite rotor must produce exactly zero thrust: G sits on the boundary (ACAI 0).
    A PNPNPN hexacopter, uncontrollable with yaw after one failure, keeps authority without it."""
    quad = rf.Airframe.preset("quad-x").with_failed_rotors([1])
    full = rf.controllability(quad)
    assert full.effectiveness_rank == 3 and full.acai == -math.inf and not full.controllable
    assert rf.acai(quad, give_up_yaw=True) == 0.0
    hexa = rf.Airframe.preset("hexa-pnpnpn").with_failed_rotors([1])
    assert rf.acai(hexa) == 0.0
    assert rf.acai(hexa, give_up_yaw=True) > 0.5
    assert rf.controllability(hexa, give_up_yaw=True).controllable


def test_printed_numbers_pass_and_flag_the_eq13_zeros() -> None:
    """papers.du.printed_numbers(): the rows the reproduce-all report shows, all within half a unit
    of the fourth decimal; exactly the two PPNNPN cases where eq. (13) prints 0 for an infeasible
    hover carry the note (Table II's zeros are on the boundary, not outside)."""
    from rotorfault.papers import du

    rows = du.printed_numbers()
    assert len(rows) == 14
    assert all(r.status == "pass" for r in rows), [r for r in rows if r.status != "pass"]
    noted = [r.quantity for r in rows if r.note]
    assert noted == ["ACAI eq13, hexa-ppnnpn, rotor 5 failed", "ACAI eq13, hexa-ppnnpn, rotor 6 failed"]
