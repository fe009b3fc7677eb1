"""Issue 27: the subnormal-mass airframe that hung every rank C(A, B) is refused up front, every
number the model divides by is a normal scale in the core's documented range (``rfcore::error``),
and no matrix reaching the rank's SVD can hang it (refused, or the SVD's iteration cap)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import rotorfault as rf

SUBNORMAL = 1e-310
QUAD = dict(
    arm_angle_rad=[0.0, 1.6, 3.1, 4.7],
    arm_length_m=[0.2] * 4,
    spin=["cw", "ccw", "cw", "ccw"],
    max_thrust_n=[5.0] * 4,
    mass_kg=1.0,
    inertia_kg_m2=[0.01, 0.01, 0.02],
    drag_torque_ratio_m=0.01,
)


def run_bounded(script: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess[str]:
    """``script`` in a fresh interpreter; a hang fails the test (the timeout) instead of hanging it."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True, timeout=timeout_s
    )


def test_the_issues_airframe_is_refused_before_any_work() -> None:
    """Issue 27's reproduction: mass 1e-310 was accepted as "> 0" and ``controllability`` then spun
    forever in the SVD. Run in a subprocess so that a regression fails on the timeout."""
    result = run_bounded(
        """
        import rotorfault as rf
        try:
            frame = rf.Airframe([0, 1.57, 3.14, 4.71], [0.2] * 4, ["cw", "ccw", "cw", "ccw"], [5.0] * 4,
                                1e-310, [0.01, 0.01, 0.02], 0.01)
        except ValueError as err:
            print("refused:", err)
        else:
            print("accepted; controllability:", rf.controllability(frame).verdict)
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("refused: mass_kg: must lie in [1e-15, 1e15] kg"), result.stdout
    assert "subnormal" in result.stdout


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"mass_kg": SUBNORMAL}, r"^mass_kg: must lie in \[1e-15, 1e15\] kg .* got 1e-310$"),
        ({"mass_kg": 1e300}, r"^mass_kg: must lie in"),
        ({"inertia_kg_m2": [0.01, SUBNORMAL, 0.02]}, r"^inertia_kg_m2 \(Jy\): must lie in"),
        ({"inertia_kg_m2": [0.01, 0.01, 1e200]}, r"^inertia_kg_m2 \(Jz\): must lie in"),
        ({"gravity_m_s2": 1e300}, r"^gravity_m_s2: must lie in"),
        ({"drag_torque_ratio_m": SUBNORMAL}, r"^drag_torque_ratio_m: must be 0 or a normal number"),
        ({"arm_length_m": [0.2, SUBNORMAL, 0.2, 0.2]}, r"^arm_length_m\[1\] \(rotor 2\): must be 0 or a normal"),
    ],
)
def test_subnormal_and_absurd_scales_are_named(override: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        rf.Airframe(**{**QUAD, **override})  # type: ignore[arg-type]


def test_general_rotors_and_every_room_check_their_scales() -> None:
    with pytest.raises(ValueError, match=r"^position_m\[0\]\[2\] \(rotor 1\): must be 0 or a normal"):
        rf.Airframe.from_rotors(
            position_m=[[0.2, 0.0, SUBNORMAL], [-0.2, 0.0, 0.0]], spin=["cw", "ccw"], max_thrust_n=[5.0, 5.0],
            mass_kg=1.0, inertia_kg_m2=[0.01, 0.01, 0.02], drag_torque_ratio_m=0.01,
        )
    quad = rf.Airframe(**QUAD)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^dt_s: must lie in \[1e-15, 1e15\] s"):
        rf.Simulator(quad, dt_s=SUBNORMAL)
    with pytest.raises(ValueError, match=r"^actuator.time_constant_s: must lie in"):
        rf.Simulator(quad, actuator=rf.FixedPitchActuator(time_constant_s=SUBNORMAL))
    with pytest.raises(ValueError, match=r"^substeps: must be at most 10000 RK4 steps per control period"):
        rf.Simulator(quad, substeps=10_001).run(duration_s=0.01)
    with pytest.raises(ValueError, match=r"^weights\[3\]: must be 0 or a normal"):
        rf.allocate(quad, [9.81, 0.0, 0.0, 0.0], weights=[1.0, 1.0, 1.0, SUBNORMAL])
    # 1.5e308 rounded to the power of two 2^1024 = inf inside the solver: zeros, "optimal".
    with pytest.raises(ValueError, match=r"^matrix\[0, 0\]: must be at most 1e300 in magnitude"):
        rf.allocate(np.eye(2) * 1.5e308, [1.0, 1.0], bounds=([0.0, 0.0], [1.0, 1.0]))
    # The values the papers and the tests use stay accepted: zero gravity, 1e300 m arms (only
    # multiplied; the analysis is unit-free), the J/m range of the rank tests.
    rf.Airframe(**{**QUAD, "gravity_m_s2": 0.0})  # type: ignore[arg-type]
    assert rf.acai(rf.Airframe(**{**QUAD, "arm_length_m": [1e300] * 4})) > 0  # type: ignore[arg-type]
    tiny = rf.Airframe(**{**QUAD, "inertia_kg_m2": [4.11e-14, 4.78e-14, 5.99e-14]})  # type: ignore[arg-type]
    assert rf.controllability(tiny).controllability_rank == 8


def test_no_matrix_reaching_the_rank_svd_hangs() -> None:
    """The scale-free rank refuses non-finite entries (the infinity a subnormal mass made) and stops
    its SVD at a cap; a matrix spanning 1e-304 to 1e225 (nalgebra's plain SVD returns NaN there) is
    answered. In a subprocess, so that a hang fails on the timeout."""
    result = run_bounded(
        """
        import numpy as np
        from rotorfault import _rfcore
        for value in (np.inf, -np.inf, np.nan):
            try:
                _rfcore.scale_free_rank(np.array([[1.0, value], [0.0, 1.0]]))
            except ValueError as err:
                print("refused:", err)
        # 6 x 5, column by column (crates/rfcore/tests/normal_numbers.rs has the same matrix).
        wide = np.array([
            1.161829837415431e-207, 0.0, 1.6803550910984164e54, -1.0524282807552993e-72,
            -1.1471596953926981e-268, 1.6990633455652647e41, 0.0, 1.933730627302472e-92,
            -1.1331111642180218e54, 0.0, 1.532153336555306e-298, -1.78184540133919e48,
            1.594378926553101e-304, -1.4357922522772844, 1.9394970457300728e-91, 0.0,
            -1.7065085465161032e-68, 1.0224993260382405e-188, 0.0, -1.174250188111994e78,
            1.2745911733012977e174, 0.0, -1.593381189214353e-189, 0.0, -1.8264127891840465e-187,
            -1.5134604041911137e-106, -1.5367119696165966e-286, -1.6150355860658365e225,
            -1463215131213285.5, 0.0,
        ]).reshape(5, 6).T.copy()
        print("rank:", _rfcore.scale_free_rank(wide))
        rng = np.random.default_rng(27)
        for _ in range(2000):
            shape = rng.integers(1, 13, size=2)
            exponents = rng.uniform(-300, 300, size=shape)
            matrix = np.where(rng.random(shape) < 0.3, 0.0, rng.standard_normal(shape) * 10.0**exponents)
            _rfcore.scale_free_rank(matrix)
        print("2000 random wide-range matrices answered")
        """
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[:3] == ["refused: matrix: must be finite"] * 3, lines
    assert lines[3].startswith("rank: ")
    assert lines[4] == "2000 random wide-range matrices answered"
