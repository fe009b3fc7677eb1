"""Old names keep working for one release, with a ``DeprecationWarning`` that names the new one
(pytest turns warnings into errors, so every test below asserts the warning it expects)."""

from __future__ import annotations

import importlib
import sys

import pytest

import rotorfault as rf

#: Old module -> (new module, a name it must still give, the object that name is now).
MOVED = {
    "rotorfault.airframe": ("rotorfault.analysis.airframe", "Airframe"),
    "rotorfault.certify": ("rotorfault.studies.certify", "certify"),
    "rotorfault.scan": ("rotorfault.studies.scan", "acai_scan"),
    "rotorfault.design": ("rotorfault.studies.design", "design_search"),
    "rotorfault.scenario": ("rotorfault.studies.scenario_file", "load_scenario"),
    "rotorfault.simulation": ("rotorfault.flight.simulator", "Simulator"),
    "rotorfault.controllability": ("rotorfault.analysis.controllability", "failure_table"),
    "rotorfault.campaign": ("rotorfault.studies.campaign", "run_campaign"),
}


@pytest.fixture(autouse=True)
def _package_attributes_restored() -> object:
    """A fresh import of an old name rebinds ``rotorfault.<name>``: put the package back as it was
    for the other tests."""
    before = dict(vars(rf))
    yield
    for name in set(vars(rf)) - set(before):
        delattr(rf, name)
    for name, value in before.items():
        setattr(rf, name, value)


def _fresh_import(name: str) -> object:
    sys.modules.pop(name, None)
    parent, _, child = name.rpartition(".")
    vars(sys.modules[parent]).pop(child, None)
    return importlib.import_module(name)


def test_importing_the_old_controllability_module_keeps_the_function_working() -> None:
    """``rotorfault.controllability`` was a module and the package's function at once; importing
    the old module name rebinds the package attribute to the module, which stays callable."""
    airframe = rf.Airframe.preset("hexa-ppnnpn")
    expected = rf.analysis.controllability(airframe)
    with pytest.warns(DeprecationWarning):
        _fresh_import("rotorfault.controllability")
    assert rf.controllability(airframe) == expected


@pytest.mark.parametrize("old", sorted(MOVED))
def test_a_moved_module_warns_and_gives_the_same_objects(old: str) -> None:
    new, name = MOVED[old]
    with pytest.warns(DeprecationWarning, match=rf"{old}.*deprecated.*rotorfault\.(analysis|studies|flight)"):
        module = _fresh_import(old)
    assert getattr(module, name) is getattr(importlib.import_module(new), name)


def test_old_module_attributes_of_the_package_warn() -> None:
    """``rf.scan`` was an attribute of the package (its submodule): it still is, with a warning."""
    sys.modules.pop("rotorfault.scan", None)
    vars(rf).pop("scan", None)
    with pytest.warns(DeprecationWarning, match="rotorfault.scan"):
        module = rf.scan  # type: ignore[attr-defined]
    assert module.acai_scan is rf.acai_scan


def test_the_old_private_names_of_the_moved_modules_still_resolve() -> None:
    """What a user might have reached for (``_ScanTask`` of the scan module, the campaign's
    chunk task, the simulator's ``Event``) resolves through the old names too."""
    with pytest.warns(DeprecationWarning):
        scan = _fresh_import("rotorfault.scan")
    with pytest.warns(DeprecationWarning):
        simulation = _fresh_import("rotorfault.simulation")
    with pytest.warns(DeprecationWarning):
        campaign = _fresh_import("rotorfault.campaign")
    with pytest.warns(DeprecationWarning, match=r"rotorfault\.Event is deprecated.*rotorfault\.Divergence"):
        from rotorfault.flight import Event
    from rotorfault.studies.campaign import _CampaignTask
    from rotorfault.studies.scan import _ScanTask
    from rotorfault.studies.tuning import tune

    assert scan._ScanTask is _ScanTask
    with pytest.warns(DeprecationWarning, match="rotorfault.Event"):
        assert simulation.Event is Event
    assert campaign._CampaignTask is _CampaignTask and campaign.tune is tune


def test_the_decisions_table_links_the_code_not_the_old_names() -> None:
    """Every file the README's decisions link to is where the decision is coded, not a module
    kept only for its old name."""
    from rotorfault.papers.decisions import DECISION_CODE

    old = {f"python/{name.replace('.', '/')}.py" for name in MOVED}
    stale = sorted({path for paths in DECISION_CODE.values() for path in paths if path in old})
    assert not stale, stale


def test_the_loop_shape_plot_is_the_designs_and_the_plotting_name_warns(tmp_path: object) -> None:
    # Plotting computes nothing (issue 26): the singular values come from control.robust, drawn by
    # plotting.frequency.plot_singular_values_db; the old plotting entry point warns and delegates.
    from pathlib import Path

    from rotorfault.control import lanzon
    from rotorfault.plotting import frequency

    out = Path(str(tmp_path))
    design = lanzon.design(lanzon.LanzonVehicle(), crossover_rad_s=30.0)
    with pytest.warns(DeprecationWarning, match=r"plot_loop_shape .*LanzonDesign\.plot_loop_shape"):
        old = frequency.plot_loop_shape(design, str(out / "old.png"))
    new = design.plot_loop_shape(str(out / "new.png"))
    assert old.axes[0].get_title() == new.axes[0].get_title() and (out / "old.png").is_file()
    assert [list(line.get_ydata()) for line in old.axes[0].lines] == [list(line.get_ydata()) for line in new.axes[0].lines]


def test_the_old_names_of_the_one_draw_record_warn() -> None:
    """``RunSpec`` (the campaign's) and ``RunDraw`` (the deciding campaign's) are one record,
    ``studies.sampling.RunDraw``: the old name and the deciding draw's ``pattern`` warn."""
    from rotorfault.studies import campaign, deciding, sampling

    assert deciding.RunDraw is sampling.RunDraw and campaign.RunDraw is sampling.RunDraw
    for module in (campaign, sampling):
        with pytest.warns(DeprecationWarning, match=r"RunSpec is deprecated.*sampling\.RunDraw"):
            assert module.RunSpec is sampling.RunDraw
    suite = deciding.DecidingCampaign(runs=2)
    d = suite.draw(suite.cells[0], 1)
    assert d == deciding.DecidingCampaign.draw_of(suite.seed, suite.cells[0], 1) and d.fault_time_s == d.fault_times_s[0]
    with pytest.warns(DeprecationWarning, match=r"RunDraw\.pattern is deprecated.*RunDraw\.failed"):
        assert d.pattern == d.failed
    assert isinstance(campaign.Campaign(runs=2).sample(0), sampling.RunDraw)
    # A RunSpec pickled before the one record had no duration: it loads with NaN, and its repr and
    # == work (they raised AttributeError).
    import math
    import pickle

    spec = campaign.Campaign(runs=2).sample(0)
    assert pickle.loads(pickle.dumps(spec)) == spec
    state = {k: v for k, v in vars(spec).items() if k != "duration_s"}
    old = sampling.RunDraw.__new__(sampling.RunDraw)
    old.__setstate__(state)
    assert math.isnan(old.duration_s) and old != spec and "duration_s=nan" in repr(old)


def test_the_lanzon_report_names_moved_to_its_report_module_warn() -> None:
    """Lanzon's report (``write_report``, ``report_section``, its tables) is
    ``papers.lanzon_report`` (issue 26: a paper module holds its parameters, scenarios, claims and
    studies): the old names in ``papers.lanzon`` warn and give the same objects."""
    from rotorfault.papers import lanzon, lanzon_report

    for name in ("write_report", "report_section", "report_rows", "three_way_table", "monte_carlo_table", "sensing_table"):
        with pytest.warns(DeprecationWarning, match=rf"papers\.lanzon\.{name} is deprecated.*papers\.lanzon_report\.{name}"):
            assert getattr(lanzon, name) is getattr(lanzon_report, name)


def test_the_removed_five_argument_holds_is_refused_naming_the_new_signature() -> None:
    """``deciding.holds(outcome, altitude, horizontal, growth, final spin)`` judged spin growth
    with a fixed allowance that no longer exists: no deprecation path can keep its answers (the
    rule now needs each run's settle time constant), so the old form is refused with a
    ``TypeError`` naming the new signature and the campaign's call, not Python's bare "missing
    arguments"; other calls that do not fit name the signature and Python's reason; an error
    from inside the rule is not rewritten."""
    import inspect

    from rotorfault.studies import deciding, deciding_hold

    assert deciding.holds is deciding_hold.holds
    old = (["holds-position"], [0.4], [1.0], [8.8], [63.0])
    told = (r"holds\(outcome, window_altitude_m, window_horizontal_m, window_spin_growth_rad_s, window_final_spin_rad_s\) "
            r"was removed: .*settle time constant.*; call holds\(outcome, .*window_final_spin_rad_s, settle_time_constant_s, "
            r"since_failure_s, span_s\) or rotorfault\.studies\.deciding\.judge_holds")
    with pytest.raises(TypeError, match=told):
        deciding.holds(*old)
    with pytest.raises(TypeError, match=told):
        deciding.holds(*old[:3], window_spin_growth_rad_s=old[3], window_final_spin_rad_s=old[4])
    with pytest.raises(TypeError, match=r"^holds\(outcome, .*, span_s\): missing a required argument: 'span_s'$"):
        deciding.holds(*old, [21.0], 15.0)
    with pytest.raises(TypeError) as inside:
        deciding.holds(*old, [21.0], 15.0, None)
    assert "holds(" not in str(inside.value)
    assert deciding.holds(*old, [21.0], 15.0, 5.0).tolist() == [True]
    assert list(inspect.signature(deciding.holds).parameters)[5:] == ["settle_time_constant_s", "since_failure_s", "span_s"]
