"""The scoreboard counts only what it tests (issue 28): every row of Du's, Ke's and Wang's numbers
says what it is (reproduced, input, consistency), only reproduced rows are scored, and each scored
row can fail: break the thing it measures (the airframe geometry, the mass, the spin layout, the
N-matrix's health matrix, the trim's k coefficients, the VPP's pitch inputs) and the row must fail
(a passing row becomes "differs"; a row that already differs moves by more than its tolerance).
A row no break reaches would pass whatever the code does: that is a defect, and these tests name it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import vpp
from rotorfault.control import vpp as control_vpp
from rotorfault.papers import du as du_paper
from rotorfault.papers import ke as ke_paper
from rotorfault.papers import wang as wang_paper
from rotorfault.papers._numbers import PaperClaim, PaperNumber, score


def _airframe(name: str, **changes: Any) -> rf.Airframe:
    """Preset ``name`` rebuilt with ``changes`` (a planar airframe's fields)."""
    a = rf.Airframe.preset(name)
    fields: dict[str, Any] = dict(
        arm_angle_rad=a.arm_angle_rad, arm_length_m=a.arm_length_m, spin=list(a.spin), max_thrust_n=a.max_thrust_n,
        min_thrust_n=a.min_thrust_n, mass_kg=a.mass_kg, inertia_kg_m2=a.inertia_kg_m2,
        drag_torque_ratio_m=a.drag_torque_ratio_m, gravity_m_s2=a.gravity_m_s2,
    )
    fields.update(changes)
    return rf.Airframe(**fields)


def _rotated(name: str, rotor: int, degrees: float) -> rf.Airframe:
    angles = rf.Airframe.preset(name).arm_angle_rad.copy()
    angles[rotor - 1] += math.radians(degrees)
    return _airframe(name, arm_angle_rad=angles)


def _spins_swapped(name: str, first: int, second: int) -> rf.Airframe:
    spins = list(rf.Airframe.preset(name).spin)
    spins[first - 1], spins[second - 1] = spins[second - 1], spins[first - 1]
    return _airframe(name, spin=spins)


def _broken(base: list[PaperNumber], mutated: list[PaperNumber]) -> set[int]:
    """The scored rows a mutation breaks: a passing row now differs, a differing row moved by more
    than its tolerance (or became non-finite)."""
    out = set()
    for i, (b, m) in enumerate(zip(base, mutated, strict=True)):
        assert (b.quantity, b.kind) == (m.quantity, m.kind)
        if not b.scored:
            continue
        moved = not math.isfinite(m.ours) or abs(m.ours - b.ours) > b.tolerance
        if (b.status == "pass" and m.status == "differs") or (b.status == "differs" and moved):
            out.add(i)
    return out


def _every_scored_row_breaks(base: list[PaperNumber], mutations: dict[str, Callable[[], list[PaperNumber]]]) -> dict[str, set[int]]:
    broken = {name: _broken(base, run()) for name, run in mutations.items()}
    reached = set().union(*broken.values())
    unbroken = [base[i].quantity for i, n in enumerate(base) if n.scored and i not in reached]
    assert not unbroken, f"scored rows no break makes fail (they pass whatever the code does): {unbroken}"
    return broken


# -- kinds -----------------------------------------------------------------------------------------


def test_every_du_ke_wang_row_has_a_kind_and_only_reproduced_rows_are_scored() -> None:
    for rows in (du_paper.printed_numbers(), ke_paper.printed_numbers(), wang_paper.printed_numbers()):
        assert all(r.kind in ("reproduced", "input", "consistency") for r in rows), [r.quantity for r in rows if r.kind is None]
        board = score(rows)
        assert board["reproduced"] == sum(r.kind == "reproduced" for r in rows)
        assert board["passed"] + board["differs"] == board["reproduced"]
    wang = {r.quantity: r.kind for r in wang_paper.printed_numbers()}
    assert wang["highest feasible omega3 (speed bound)"] == "input"  # the paper's bound, not a result
    assert wang["highest feasible omega2 from eq. (14) without its k3 term (where 7067 comes from)"] == "consistency"
    assert score(wang_paper.printed_numbers()) == {
        "reproduced": 9, "passed": 6, "differs": 3, "input": 1, "consistency": 1, "unclassified": 0,
    }


def test_an_unclassified_row_is_shown_but_not_scored() -> None:
    rows = [PaperNumber("P", "T", "q", 1.0, 1.0, 0.1), PaperNumber("P", "T", "q2", 1.0, 1.0, 0.1, kind="input"),
            PaperNumber("P", "T", "q3", 1.0, 3.0, 0.1, kind="reproduced")]
    assert score(rows) == {"reproduced": 1, "passed": 0, "differs": 1, "input": 1, "consistency": 0, "unclassified": 1}
    assert rows[0].kind_label == "not classified" and not rows[0].scored
    with pytest.raises(ValueError, match="kind: must be one of reproduced, input, consistency"):
        PaperNumber("P", "T", "q", 1.0, 1.0, 0.1, kind="guessed")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="status: must be one of"):
        PaperClaim("P", "w", "c", "m", "holds", "maybe", "r")  # type: ignore[arg-type]


# -- Du: Tables II and III --------------------------------------------------------------------------


def test_each_du_row_fails_when_the_hexacopter_it_measures_is_broken() -> None:
    """Table I's vehicles broken one way at a time: an arm rotated by 10 degrees, 5 % more mass,
    a 20 % larger drag-torque ratio, two rotors' spins swapped. Table II's zeros (PNPNPN, any
    single failure) are structural (hover on a facet of the symmetric frame): they fail only
    when the frame's symmetry or spin layout is broken."""
    base = du_paper.printed_numbers()
    mutations: dict[str, Callable[[], list[PaperNumber]]] = {}
    for name in ("hexa-pnpnpn", "hexa-ppnnpn"):
        a = rf.Airframe.preset(name)
        mutations[f"{name}: rotor 1's arm +10 deg"] = lambda n=name: du_paper.printed_numbers({n: _rotated(n, 1, 10.0)})
        mutations[f"{name}: mass +5 %"] = lambda n=name, a=a: du_paper.printed_numbers({n: _airframe(n, mass_kg=1.05 * a.mass_kg)})
        mutations[f"{name}: k_mu x1.2"] = lambda n=name, a=a: du_paper.printed_numbers(
            {n: _airframe(n, drag_torque_ratio_m=1.2 * a.drag_torque_ratio_m)})
        for pair in ((1, 2), (4, 5)):
            mutations[f"{name}: spins of rotors {pair} swapped"] = lambda n=name, p=pair: du_paper.printed_numbers(
                {n: _spins_swapped(n, *p)})
    broken = _every_scored_row_breaks(base, mutations)
    quantity = {i: base[i].quantity for i in range(len(base))}
    # The mass is what Table III's single-failure rows measure (the hover wrench moves).
    assert {quantity[i] for i in broken["hexa-ppnnpn: mass +5 %"]} >= {
        f"ACAI eq13, hexa-ppnnpn, rotor {k} failed" for k in (1, 2, 3, 4)}


# -- Ke: Table II -----------------------------------------------------------------------------------


def test_each_ke_eigenvalue_fails_when_the_geometry_or_the_health_matrix_is_broken() -> None:
    """N = (E1 M) Lambda (E1 M)^+: rotor 1's arm rotated by 10 degrees or lengthened by 20 %
    breaks the geometry-dependent eigenvalues; each rotor's efficiency moved by its own small
    amount (0.05 + 0.02 (i - 1) towards 1, a health matrix other than the one the row names)
    breaks every row. The eigenvalues 1 and 0 of the repeated and zero efficiencies do not depend
    on the geometry at all (linear algebra: any M of rank 3), so only the health matrix can
    break them; they still measure that N is built from Lambda as Table II defines."""
    base = ke_paper.printed_numbers()
    frame = rf.Airframe.preset("ke-quadcopter")
    longer = frame.arm_length_m.copy()
    longer[0] *= 1.2

    def graded(efficiency: tuple[float, ...]) -> tuple[float, ...]:
        return tuple(0.9 * h + 0.05 + 0.02 * i * (1 - h) for i, h in enumerate(efficiency))

    broken = _every_scored_row_breaks(base, {
        "rotor 1's arm +10 deg": lambda: ke_paper.printed_numbers(_rotated("ke-quadcopter", 1, 10.0)),
        "rotor 1's arm x1.2": lambda: ke_paper.printed_numbers(_airframe("ke-quadcopter", arm_length_m=longer)),
        "health matrix graded": lambda: ke_paper.printed_numbers(health=graded),
    })
    assert len(broken["health matrix graded"]) == len(base) == 33
    geometric = {base[i].quantity for i in broken["rotor 1's arm +10 deg"]}
    assert "eig 1 of N, diag(0, 1, 1, 1)" in geometric  # the 0.25 (sorted first) comes from the frame
    assert "eig 3 of N, diag(0, 1, 1, 1)" not in geometric  # a 1 of Lambda's repeated 1s


# -- Wang: Sections 3.1, 3.3, 3.4 -------------------------------------------------------------------


def _vpp(**changes: Any) -> vpp.VppVehicle:
    wang = vpp.preset()
    a = wang.actuator
    fields: dict[str, Any] = dict(
        k=a.k, speed_bounds=a.speed_bounds, pitch_bounds=a.pitch_bounds, speed_to_rad_s=a.speed_to_rad_s,
        speed_time_constant_s=a.speed_time_constant_s, pitch_time_constant_s=a.pitch_time_constant_s,
    )
    frame = changes.pop("airframe", None)
    fields.update(changes)
    return dataclasses.replace(wang, actuator=rf.VariablePitchActuator(**fields), **({"airframe": frame} if frame else {}))


def test_each_wang_row_fails_when_the_trim_or_the_model_it_measures_is_broken(monkeypatch: pytest.MonkeyPatch) -> None:
    """Each k coefficient of eq. (3) moved, the mass 2 % up (the trim at omega_3 = 9000 still
    exists), a wider pitch bound; Sec. 3.4's layout replaced by the standard one (no hover at
    rest: the rank row reads nan); and the VPP's pitches taken away from the paper's inputs (what
    makes it rank 12: the fixed group's speed is held, so the shared speed alone is left)."""
    base = wang_paper.printed_numbers()
    k1, k2, k3, k4 = vpp.preset().actuator.k
    frame = vpp.preset().airframe
    heavier = _airframe("wang-vpp", mass_kg=1.02 * frame.mass_kg)
    original = control_vpp.linearize

    def without_pitch_inputs() -> list[PaperNumber]:
        with monkeypatch.context() as m:
            m.setattr(control_vpp, "linearize", lambda v, at, **kw: original(v, at, **{**kw, "pitch_fixed": True}))
            return wang_paper.printed_numbers()

    broken = _every_scored_row_breaks(base, {
        "k1 +5 %": lambda: wang_paper.printed_numbers(_vpp(k=(1.05 * k1, k2, k3, k4))),
        "k2 x1.5": lambda: wang_paper.printed_numbers(_vpp(k=(k1, 1.5 * k2, k3, k4))),
        "k3 x3": lambda: wang_paper.printed_numbers(_vpp(k=(k1, k2, 3 * k3, k4))),
        "k4 x2": lambda: wang_paper.printed_numbers(_vpp(k=(k1, k2, k3, 2 * k4))),
        "mass +2 %": lambda: wang_paper.printed_numbers(_vpp(airframe=heavier)),
        "pitch bound 0.27": lambda: wang_paper.printed_numbers(_vpp(pitch_bounds=(-0.27, 0.27))),
        "standard fixed-pitch layout": lambda: wang_paper.printed_numbers(fixed_pitch_airframe="wang-standard-fixed-pitch"),
        "VPP without pitch inputs": without_pitch_inputs,
    })
    quantity = {i: base[i].quantity for i in range(len(base))}
    assert {quantity[i] for i in broken["VPP without pitch inputs"]} == {
        "controllability rank, VPP, propeller 1 failed (the paper's inputs, omega_3 held)"}
    assert {quantity[i] for i in broken["standard fixed-pitch layout"]} == {"controllability rank, fixed pitch, propeller 1 failed"}


def test_the_7067_is_eq14_without_its_k3_term() -> None:
    """Sec. 3.1's upper omega_2 bound: eq. (14) as printed is 1 at 7064.2 (r(7067) = 1.0008 > 1);
    without its k3 term it is 1 at 7067.06, the printed 7067 (a consistency row, not scored)."""
    wang = vpp.preset()
    assert wang_paper.eq14_r(wang, 7067.0) == pytest.approx(1.0008, abs=5e-5)
    assert wang_paper.eq14_r(wang, 7067.06, k3_term=False) == pytest.approx(1.0, abs=1e-5)
    rows = {r.quantity: r for r in wang_paper.printed_numbers()}
    row = rows["highest feasible omega2 from eq. (14) without its k3 term (where 7067 comes from)"]
    assert row.status == "pass" and not row.scored and abs(row.ours - 7067.06) < 0.01
    assert "without its k3 term" in rows["highest feasible omega2 (r = 1)"].note
    assert "rounding" not in rows["highest feasible omega2 (r = 1)"].note
    # eq14_r is the trim's own torque balance: 2 tau(omega_2) = r at the exact feasible bound.
    window = vpp.feasible_speeds(wang, failed=(1,))
    assert wang_paper.eq14_r(wang, window.free_speed_range[1]) == pytest.approx(1.0, rel=1e-12)
    assert wang_paper.eq14_r(wang, window.free_speed_range[0]) == pytest.approx(window.free_torque_range_nm[0], rel=1e-12)
