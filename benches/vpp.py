"""VPP (Wang et al.) benchmarks, each against a baseline in the same run:

1. trim + linearisation + LQR design for one failure case (target < 50 ms), and the sweep of the
   feasible omega3 range per failed propeller;
2. the VPP closed loop (LQR, 1 kHz, RK4) in Rust, steps/s in a batch, against the same law as a
   Python callback.

    python benches/vpp.py [--quick]
"""

from __future__ import annotations

import sys
import time

import numpy as np

import rotorfault as rf
from rotorfault import vpp


def main(quick: bool) -> None:
    wang = vpp.preset()
    vpp.lqr(wang, vpp.trim(wang, failed=(1,)), dt_s=0.001)  # warm: scipy import
    t0 = time.perf_counter()
    n = 5 if quick else 20
    for _ in range(n):
        trim = vpp.trim(wang, failed=(1,), speeds={3: 9000.0}, position=(0, 0, -10))  # 10 m up
        feedback = vpp.lqr(wang, trim, dt_s=0.001)
    design = (time.perf_counter() - t0) / n
    print(f"trim + linearisation + LQR design, one failure case: {design * 1e3:.1f} ms (target < 50 ms)")
    print("feasible omega3-like range per failed propeller (fixed group speed range):")
    for failed in (1, 2, 3, 4):
        window = vpp.feasible_speeds(wang, failed=(failed,))
        print(f"  propeller {failed} failed: fixed {window.fixed_rotors} in "
              f"[{window.fixed_speed_range[0]:.1f}, {window.fixed_speed_range[1]:.1f}], free {window.free_rotors} in "
              f"[{window.free_speed_range[0]:.1f}, {window.free_speed_range[1]:.1f}]")

    base = wang.simulator(failed=(1,))
    sim = rf.Simulator(base.airframe, actuator=wang.actuator, drag=wang.drag, dt_s=0.001)
    duration = 2.0 if quick else 10.0
    runs = 8 if quick else 64
    x0s = [rf.State(position=(0.1 * k % 1.0, -0.2, -10.3)) for k in range(runs)]
    t0 = time.perf_counter()
    rf.simulate_batch(sim, x0s, duration, controllers=feedback, record_every=1000, progress=False)
    rust = runs * duration / 1e-3 / (time.perf_counter() - t0)
    gain, x_trim, u_trim = np.asarray(feedback.gain), np.asarray(feedback.x_trim), np.asarray(feedback.u_trim)

    def callback(t: float, x: np.ndarray) -> np.ndarray:
        return u_trim - gain @ (x - x_trim)

    t0 = time.perf_counter()
    sim.run(x0s[0], duration_s=duration / 4, controller=callback)
    python = duration / 4 / 1e-3 / (time.perf_counter() - t0)
    print(f"VPP closed loop (LQR, 1 kHz, RK4), batch of {runs}: {rust:,.0f} steps/s in Rust; "
          f"Python callback {python:,.0f} steps/s; ratio {rust / python:.1f}x (target >= 1,000,000 steps/s)")


if __name__ == "__main__":
    main("--quick" in sys.argv)
