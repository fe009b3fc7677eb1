"""``certify`` beside the static verdict: survivable by spinning (the best relaxed hover, Mueller
and D'Andrea), with its margin, spin rate and carrying rotors; the CLI's ``--spinning``."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli
from rotorfault.studies.certify import Certificate, RelaxedHoverVerdict, certify, certify_survival, rows_for_display, survives

#: Ke's vehicle's rotational damping (the ke-hil preset's): it sets the spin rate.
KE_DRAG = rf.Drag(rotational_n_m_s=2.8e-3)


@pytest.fixture(scope="module")
def ke_certificate() -> Certificate:
    return certify(rf.Airframe.preset("ke-quadcopter"), spinning=True, drag=KE_DRAG)


def test_a_quadrotor_without_a_rotor_survives_by_spinning(ke_certificate: Certificate) -> None:
    """Static hover is lost with any rotor (Du: ACAI 0 even with yaw given up) but each single
    failure has a spinning relaxed hover: rotor 1 lost spins at 15.22 rad/s on rotors 2, 3, 4 with
    6.04 N of headroom (README table); two opposite rotors lost spin level at k_mu m g / k_r."""
    cases = {c.failed: c for c in ke_certificate.cases}
    assert cases[()].hover == "all-axes" and cases[()].relaxed_hover == RelaxedHoverVerdict("static", 0.0, cases[()].relaxed_hover.thrust_margin_n, (1, 2, 3, 4), False)  # type: ignore[union-attr]
    one = cases[(1,)]
    assert one.hover == "no" and one.relaxed_hover is not None
    assert one.relaxed_hover.hover == "spinning" and one.relaxed_hover.carrying == (2, 3, 4)
    assert round(one.relaxed_hover.spin_rate_rad_s, 2) == 15.22 and round(one.relaxed_hover.thrust_margin_n, 2) == 6.04
    airframe = rf.Airframe.preset("ke-quadcopter")
    k_mu = abs(float(airframe.effectiveness_matrix()[3, 0]))
    level = cases[(1, 3)].relaxed_hover
    assert level is not None and level.hover == "spinning"
    assert level.spin_rate_rad_s == pytest.approx(k_mu * airframe.mass_kg * airframe.gravity_m_s2 / 2.8e-3, rel=1e-9)
    # Every verdict is the analysis' best for that failure set (the same numbers, not re-derived).
    for case in ke_certificate.cases:
        best = rf.relaxed_hover(airframe.with_failed_rotors(list(case.failed)), drag=KE_DRAG).best
        verdict = case.relaxed_hover
        assert verdict is not None
        if best is None:
            assert verdict.hover == "no" and math.isnan(verdict.spin_rate_rad_s) and verdict.carrying == ()
            assert verdict.solution is None
        else:
            assert (verdict.spin_rate_rad_s, verdict.thrust_margin_n, verdict.carrying) == (
                best.spin_rate_rad_s, best.thrust_margin_n, tuple(best.carrying))
            # The verdict carries the solution itself (what the relaxed hover LQR is designed on).
            assert verdict.solution is not None and list(verdict.solution.thrust_n) == list(best.thrust_n)
            assert list(verdict.solution.body_rate_rad_s) == list(best.body_rate_rad_s)
            assert [list(r) for r in verdict.solution.linear_a] == [list(r) for r in best.linear_a]
    assert ke_certificate.failing("single") and not ke_certificate.failing_spinning("single")
    headers, rows = rows_for_display(ke_certificate)
    assert headers[-1] == "relaxed hover"
    assert rows[1][0] == "1" and rows[1][-1] == "spinning 15.22 rad/s, margin 6.04 N, rotors 2, 3, 4"
    # Rotors 1 and 2 lost: two mirror spins (+-20.06 rad/s) with the same margin; the search
    # resolves their rates to ~1e-8, so which one the tie-break (the slower) names is not fixed.
    assert rows[5][0] == "1, 2" and rows[5][-1].replace("-20.06", "20.06") == (
        "spinning solution exists, not reachable from hover: 20.06 rad/s, margin 3.07 N, rotors 3, 4; tilt >= 126 deg before the "
        "18.19 rad/s spin, at most 2.33 rad/s by 90 deg (roll/yaw 9.89)")


def test_the_json_has_no_nan_and_the_static_certificate_is_unchanged(ke_certificate: Certificate) -> None:
    data = ke_certificate.to_dict()
    json.dumps(data, allow_nan=False)
    cases = {tuple(c["failed"]): c["relaxed_hover"] for c in data["cases"]}
    # The entry's evidence: infinity (the bound never reaches the tilt limit) as null.
    assert cases[(1,)]["entry_from_hover"]["reachable"] and cases[(1,)]["entry_from_hover"]["spin_rate_at_tilt_limit_rad_s"] is None
    assert not cases[(1, 2)]["entry_from_hover"]["reachable"] and cases[()]["entry_from_hover"] is None
    assert [c.failed for c in ke_certificate.failing_spinning("double")] == [(1, 2), (1, 4), (2, 3), (3, 4)]
    assert all("solution" not in c["relaxed_hover"] for c in data["cases"])
    assert ke_certificate.cases[1].relaxed_hover.solution is not None  # type: ignore[union-attr]  # kept on the object
    static = certify(rf.Airframe.preset("ke-quadcopter"))
    assert all(c.relaxed_hover is None for c in static.cases)
    assert [(c.failed, c.hover, c.acai) for c in static.cases] == [(c.failed, c.hover, c.acai) for c in ke_certificate.cases]
    with pytest.raises(ValueError, match="^spinning: "):
        static.failing_spinning("single")


def test_bad_input_is_refused_before_any_work() -> None:
    quad = rf.Airframe.preset("ke-quadcopter")
    with pytest.raises(TypeError, match="^spinning: "):
        certify(quad, spinning="yes")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="^settings, drag, actuator: "):
        certify(quad, drag=KE_DRAG)
    with pytest.raises(TypeError, match="^drag: "):
        certify(quad, spinning=True, drag=0.1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="^settings: rotational_drag_n_m_s given both"):
        certify(quad, spinning=True, settings=rf.RelaxedHoverSettings(rotational_drag_n_m_s=1e-3), drag=KE_DRAG)


def test_cli_spinning() -> None:
    runner = CliRunner()
    static = runner.invoke(cli, ["certify", "-a", "ke-quadcopter", "--require", "single", "--json", "-"])
    assert static.exit_code == 3, static.output
    # Every single failure survives by spinning; of the double ones, the two adjacent rotors have a
    # spin that cannot be entered from hover (tests/analysis/test_spin_entry.py): those fail.
    spun = runner.invoke(cli, ["certify", "-a", "ke-quadcopter", "--require", "double", "--spinning", "--rotational-drag", "2.8e-3",
                               "--json", "-"])
    assert spun.exit_code == 3, spun.output
    assert spun.stderr.strip() == ("certificate: FAILED: --require double --spinning: cannot hover nor enter a spin from hover with rotor(s) "
                                   + "; ".join(f"{p} (spinning solution exists, not reachable from hover)" for p in ("1, 2", "1, 4", "2, 3", "3, 4"))
                                   + " failed"), spun.stderr
    cases = {tuple(c["failed"]): c for c in json.loads(spun.stdout)["cases"]}
    one = cases[(1,)]
    assert one["hover"] == "no" and one["relaxed_hover"]["hover"] == "spinning" and one["relaxed_hover"]["carrying"] == [2, 3, 4]
    assert not cases[(1, 2)]["relaxed_hover"]["entry_from_hover"]["reachable"]
    wrong = runner.invoke(cli, ["certify", "-a", "ke-quadcopter", "--rotational-drag", "2.8e-3"])
    assert wrong.exit_code != 0 and "--rotational-drag" in wrong.output


def _x500_rotor_1_at(efficiency: float, rotational_drag_n_m_s: float, max_spin_rate_rad_s: float = 200.0) -> Any:
    from rotorfault.studies import deciding

    v = deciding.vehicle("px4-x500")
    settings = rf.RelaxedHoverSettings(rotational_drag_n_m_s=rotational_drag_n_m_s, max_spin_rate_rad_s=max_spin_rate_rad_s,
                                       thrust_coefficient_n_s2=deciding.nominal_actuator(v).thrust_coefficient_n_s2)
    airframe = v.airframe.with_efficiency([efficiency, 1.0, 1.0, 1.0])
    return v.airframe, certify_survival(airframe, settings=settings)


def test_giving_up_yaw_survives_by_a_steady_spin() -> None:
    """The PX4 x500 with rotor 1 at 40 %: Du's static hover exists only by giving up yaw. Damped
    (k_r = 0.01 N m s), the yaw moment left settles the vehicle in a steady spin: the relaxed hover
    about the thrust axis, its yaw balance n . tau(f) = k_r s checked here from the airframe's own
    effectiveness matrix (independent of the search), survivable. Undamped (the imported model,
    k_r = 0), n . tau(f) = 0 for every spin rate and the margin still grows with the spin: the full
    search's best spin is its limit, wherever the limit is put (200 or 400 rad/s). Rule 4: the rate
    is free, so the search is repeated with the limit at FREE_SPIN_RATE_LIMIT_SHARE of it and the
    member found there (50 or 100 rad/s, its yaw balance n . tau = 0 checked) is a steady spin a
    spin-rate loop holds: survivable (rule 3 called it not steady: refuted by the deciding
    campaign's flights)."""
    from rotorfault.studies.certify import FREE_SPIN_RATE_LIMIT_SHARE

    nominal, damped = _x500_rotor_1_at(0.4, 1e-2)
    assert damped.hover == "give-up-yaw" and damped.survival == "spinning"
    spin = damped.relaxed_hover
    assert spin is not None and spin.steady and spin.survivable and not spin.at_spin_rate_limit and not spin.spin_rate_free
    assert spin.solution is not None
    torque = np.asarray(nominal.effectiveness_matrix())[1:4] @ np.asarray(spin.solution.thrust_n)
    yaw_about_axis = float(np.asarray(spin.solution.spin_axis) @ torque)
    assert yaw_about_axis == pytest.approx(1e-2 * spin.spin_rate_rad_s, rel=1e-9)
    assert survives("give-up-yaw", spin)
    for limit in (200.0, 400.0):
        _, undamped = _x500_rotor_1_at(0.4, 0.0, limit)
        assert undamped.hover == "give-up-yaw" and undamped.survival == "spinning"
        free = undamped.relaxed_hover
        assert free is not None and free.hover == "spinning" and free.spin_rate_free and not free.damped
        assert abs(free.spin_rate_rad_s) == pytest.approx(FREE_SPIN_RATE_LIMIT_SHARE * limit, rel=1e-6)
        assert free.steady and free.reachable_from_hover and survives("give-up-yaw", free)
        assert free.solution is not None
        torque = np.asarray(nominal.effectiveness_matrix())[1:4] @ np.asarray(free.solution.thrust_n)
        assert abs(float(np.asarray(free.solution.spin_axis) @ torque)) < 1e-9 * float(np.max(np.abs(torque)))


def test_an_undamped_spin_at_the_search_limit_is_taken_from_below(monkeypatch: pytest.MonkeyPatch) -> None:
    """Rule 4 on the deciding campaign's x500 draws (seed 0, one rotor in hover). Run 959: without
    rotational damping the full search's best spin stops at 198.22 rad/s of its 200 rad/s limit
    (within SPIN_RATE_LIMIT_MARGIN: rule 3 called it not steady, not survivable); run 281: static
    hover only by giving up yaw, best spin 199.99999997 rad/s (rule 3: not survivable). INDI holds
    such draws at 4-43 rad/s (median 19, the campaign's 101 contradictions). Now the search is
    repeated at a quarter of the limit (50 rad/s) and finds a spinning member there: spinning,
    steady, ``spin_rate_free``. Where the lower search finds nothing, rule 3's answer stands
    (simulated: not survivable). A damped hexacopter's spin as close to the limit (hexa-ppnnpn,
    run 245, -197.4 rad/s) is pinned by k_r: no second search, the same verdict."""
    import importlib

    from rotorfault.studies import deciding as D

    C = importlib.import_module("rotorfault.studies.certify")  # the module (the package exports the function by its name)

    suite = D.DecidingCampaign(certify=False)
    cells = {(c.vehicle, c.fault_class): c for c in suite.cells}

    def verdict(vehicle: str, index: int) -> Any:
        airframe, actuator, drag = suite.draw(cells[(vehicle, "one-rotor-hover")], index).failed_vehicle(D.vehicle(vehicle))
        return certify_survival(airframe, drag=drag, actuator=actuator)

    lower = C.FREE_SPIN_RATE_LIMIT_SHARE * rf.RelaxedHoverSettings().max_spin_rate_rad_s
    assert lower == 50.0
    for index in (959, 281):
        x500 = verdict("px4-x500", index)
        spin = x500.relaxed_hover
        assert spin is not None and spin.hover == "spinning" and not spin.damped and spin.spin_rate_free
        assert 0.0 < abs(spin.spin_rate_rad_s) <= lower * (1 + 1e-9) and spin.thrust_margin_n > 0.0
        assert spin.entry_from_hover is not None and spin.entry_from_hover.reachable
        assert spin.steady and x500.survival == "spinning" and x500.hover == "give-up-yaw"
    # Where the lower search finds no spinning solution, rule 3's answer stands.
    monkeypatch.setattr(C, "_free_spin_verdict", lambda airframe, resolved: None)
    rule3 = verdict("px4-x500", 281)
    assert rule3.relaxed_hover is not None and not rule3.relaxed_hover.spin_rate_free
    assert abs(rule3.relaxed_hover.spin_rate_rad_s) > 0.95 * 200.0 and not rule3.relaxed_hover.steady
    assert rule3.survival == "not-survivable"
    monkeypatch.undo()
    # A damped vehicle: one search, the verdict rule 3 gave.
    calls = []
    search = C.relaxed_hover
    monkeypatch.setattr(C, "relaxed_hover", lambda *a, **k: calls.append(1) or search(*a, **k))
    hexa = verdict("hexa-ppnnpn", 245)
    assert len(calls) == 1
    spin = hexa.relaxed_hover
    assert spin is not None and spin.near_spin_rate_limit and spin.damped and not spin.spin_rate_free
    assert spin.spin_rate_rad_s == pytest.approx(-197.38993195638747, rel=1e-6) and hexa.survival == "spinning"


def test_certify_run_calls_an_undamped_x500_draw_held_by_indi_spinning() -> None:
    """The deciding campaign (1000 runs, seed 0), px4-x500 one rotor in hover, draw 281: certified
    not survivable under rule 3 (static hover only by giving up yaw, best spin 199.99999997 rad/s
    at the search limit) and held by INDI. Rule 4: spinning, at no more than the lowered limit."""
    from rotorfault.studies import deciding as D
    from rotorfault.studies.certify import FREE_SPIN_RATE_LIMIT_SHARE

    suite = D.DecidingCampaign(runs=1000, seed=0)
    cell = next(c for c in suite.cells if (c.vehicle, c.fault_class) == ("px4-x500", "one-rotor-hover"))
    v = D.certify_run(suite, cell, 281)
    assert v.certified == "spinning" and v.static_hover == "give-up-yaw"
    assert 0.0 < abs(v.spin_rate_rad_s) <= FREE_SPIN_RATE_LIMIT_SHARE * 200.0 * (1 + 1e-9)
