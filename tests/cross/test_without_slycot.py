"""The slycot-hiding harness itself (tests/without_slycot.py)."""

from __future__ import annotations

from without_slycot import run_without_slycot


def test_slycot_is_hidden_in_the_subprocess() -> None:
    """In the subprocess ``import slycot`` fails and python-control knows it."""
    result = run_without_slycot(
        """
        import json
        try:
            import slycot  # noqa: F401
            found = True
        except ImportError:
            found = False
        print(json.dumps({"found": found}))
        """
    )
    assert result == {"found": False}


#: The designs issue 25 requires to be install-independent, as one JSON-able dict: the hover LQR
#: of a preset (direct and allocated), the VPP LQR of Wang's failed vehicle at the flights' 1 kHz,
#: the fixed-pitch comparison's outcome (its table and the LQR's refusal), and a discrete LQR.
DESIGNS = """
import numpy as np
import control as ct
import rotorfault as rf
from rotorfault import vpp
from rotorfault.control.riccati import design_lqr
from rotorfault.papers import wang


def designs():
    out = {}
    sim = rf.Simulator(rf.Airframe.preset("quad-x"))
    out["hover"] = rf.lqr_hover(sim, position=(0, 0, -10)).gain.tolist()
    allocated = rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe), position=(0, 0, -10))
    out["hover allocated"] = allocated.law.gain.tolist()
    w = vpp.preset()
    out["vpp"] = vpp.lqr(w, vpp.trim(w, failed=(1,), speeds={3: wang.OMEGA3}), dt_s=wang.DT_S).gain.tolist()
    out["comparison"] = wang.comparison_table()
    fixed = vpp.fixed_pitch(w)
    try:
        vpp.lqr(fixed, vpp.fixed_pitch_trim(fixed, failed=()), pitch_fixed=True)
        out["fixed-pitch refusal"] = "designed"
    except ValueError as error:
        out["fixed-pitch refusal"] = str(error)
    a = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.5, -0.2, 0.1]])
    b = np.array([[0.0], [0.0], [1.0]])
    held = ct.c2d(ct.ss(a, b, np.eye(3), np.zeros((3, 1))), 0.05)
    design = design_lqr(held, np.diag([10.0, 1.0, 0.1]), [[0.5]])
    out["discrete"] = design.gain.tolist()
    out["discrete riccati"] = design.riccati.tolist()
    return out
"""


def test_designs_are_the_same_without_slycot() -> None:
    """Issue 25: the same designs with slycot installed (this process) and hidden (a
    subprocess): every gain and Riccati solution to 1e-9 relative, every text identical."""
    import numpy as np

    namespace: dict[str, object] = {}
    exec(DESIGNS, namespace)  # noqa: S102 - the test's own code, run here and in the subprocess
    here = namespace["designs"]()  # type: ignore[operator]
    there = run_without_slycot(DESIGNS + "\nimport json\nprint(json.dumps(designs()))\n")
    assert set(here) == set(there)
    for key, value in here.items():
        if isinstance(value, str) or (isinstance(value, list) and value and isinstance(value[0], str)):
            assert value == there[key], key
        else:
            mine, theirs = np.array(value), np.array(there[key])
            assert mine.shape == theirs.shape, key
            assert np.max(np.abs(mine - theirs)) <= 1e-9 * np.max(np.abs(mine)), key
    assert here["fixed-pitch refusal"].startswith("stabilisability: ")
