"""Ctrl-C works everywhere (issue 27): a long Rust call, parallel (rayon) or not, stops on SIGINT
and raises ``KeyboardInterrupt``.

Each case runs in a subprocess that prints ``ready`` and then makes one call whose work is far
longer than the test waits (minutes of CPU: even on many cores it cannot end in the second before
the signal), receives SIGINT one second later and must exit with a ``KeyboardInterrupt`` raised
from inside that call. The only timing in the test is a generous bound on how long the child may
take to stop (it takes well under a second: the core checks its token about every millisecond of
work and the bindings look for the signal every 50 ms); reaching it fails the test instead of
hanging it. How a call is made interruptible is tested in Rust (``crates/rfcore/tests/
cancellation.rs``: a token set 100 ms into each long call stops it).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time

import pytest

PRELUDE = textwrap.dedent(
    """
    import signal
    import sys
    import numpy as np
    import rotorfault as rf

    # Python's own SIGINT handler even when this test runs in a background job, whose children
    # start with SIGINT ignored (POSIX shells without job control), so Python installs none.
    signal.signal(signal.SIGINT, signal.default_int_handler)

    def ring(m):
        angles = np.arange(m) * 2 * np.pi / m
        return rf.Airframe(angles, [0.3] * m, [1, -1] * (m // 2), [5.0] * m, 2.0, [0.05, 0.05, 0.09], 0.02)

    def ready():
        print("ready", flush=True)

    def interrupted_inside(call):
        try:
            call()
        except KeyboardInterrupt:
            print("interrupted inside the call", flush=True)
            raise
        print("finished", flush=True)
    """
)

#: One long call each; ``ring(52)`` has C(52, 3) = 22,100 facet groups: about 1 ms per ACAI.
CASES = {
    "acai_batch": """
        frame = ring(52)
        etas = np.ones((200_000, 52))
        ready()
        interrupted_inside(lambda: rf.acai_batch(frame, etas))
    """,
    "failure_table": """
        frame = ring(52)
        ready()
        interrupted_inside(lambda: rf.failure_table(frame, max_failed=3))
    """,
    "simulate_batch": """
        sim = rf.Simulator(rf.Airframe.preset("quad-x"), ground=False, limits=rf.DivergenceLimits(
            max_tilt_rad=np.inf, max_altitude_loss_m=np.inf, max_speed_m_s=np.inf, max_rate_rad_s=np.inf))
        ready()
        interrupted_inside(lambda: rf.simulate_batch(sim, [rf.State()] * 64, 24_000.0, record_every=10**9))
    """,
    "simulate_python_controller": """
        sim = rf.Simulator(rf.Airframe.preset("quad-x"), ground=False, limits=rf.DivergenceLimits(
            max_tilt_rad=np.inf, max_altitude_loss_m=np.inf, max_speed_m_s=np.inf, max_rate_rad_s=np.inf))
        ready()
        interrupted_inside(lambda: sim.run(duration_s=24_000.0, controller=lambda t, x: [0.0] * 4, record_every=10**9))
    """,
    # One control period of 10^5 s with sensors: 3.2e9 IMU samples and filter steps (hours) between
    # the simulator's once-per-period checks, so the sensors' loop must check on its own.
    "simulate_sensed_one_long_period": """
        sim = rf.Simulator(rf.Airframe.preset("quad-x"), ground=False, dt_s=1e5, substeps=10_000,
            sensing=rf.Sensing(imu_rate_hz=32_000.0), limits=rf.DivergenceLimits(
            max_tilt_rad=np.inf, max_altitude_loss_m=np.inf, max_speed_m_s=np.inf, max_rate_rad_s=np.inf))
        ready()
        interrupted_inside(lambda: sim.run(duration_s=1e5, controller=lambda t, x: [0.0] * 4))
    """,
    "allocation_batch": """
        frame = rf.Airframe.preset("ke-quadcopter")
        controls = np.tile([30.0, 0.5, -0.3, 0.2], (2_000_000, 1))
        ready()
        interrupted_inside(lambda: rf.allocate(frame, controls, method="clarabel"))
    """,
}

#: How long the child may take to stop after SIGINT before the test fails (it needs well under 1 s).
STOP_TIMEOUT_S = 60.0


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
@pytest.mark.parametrize("case", sorted(CASES))
def test_sigint_stops_a_long_rust_call(case: str) -> None:
    script = PRELUDE + textwrap.dedent(CASES[case])
    child = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout is not None
        line = child.stdout.readline()
        assert line.strip() == "ready", f"the child failed before its call: {line!r} {child.stderr.read() if child.stderr else ''}"
        time.sleep(1.0)
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=STOP_TIMEOUT_S)
    finally:
        if child.poll() is None:
            child.kill()
            child.communicate()
    assert "interrupted inside the call" in out, (out, err)
    assert "finished" not in out
    assert err.rstrip().splitlines()[-1].startswith("KeyboardInterrupt"), err
    assert child.returncode != 0
