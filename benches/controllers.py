"""Every registered Rust controller (``rotorfault._rfcore.CONTROLLERS``, the registry of
``crates/rfcore-py/src/control/mod.rs``) closing the loop on a hovering quad-x at 400 Hz (4 RK4
substeps): control steps/s in a ``simulate_batch`` in Rust, against the same law as a Python
callback in the same run (``docs/adding-a-controller.md``, step 6).

The laws: ``open-loop`` holds the trim; ``linear-feedback`` is ``rf.lqr_hover``; ``lti`` the same
gain as a static LTI (``D = -K``); ``tracking-feedback`` the same gain on a constant reference
with a saturated error; ``allocated`` LQR on the virtual control followed by the active-set
allocation (the callback allocates through ``rf.Allocator.allocate``); ``relaxed-hover-feedback``
the LQR about quad-x's relaxed hover (static hover on a healthy frame), its reduced state and
outer loop recomputed in numpy by the callback. Ke's and Lanzon's
controllers and INDI fly their own vehicles in their own benches (``ftc_batch.py``, ``lanzon_batch.py``,
each against its law as a Python callback): :data:`OWN_BENCH` names them, and the script checks
that every registered controller is timed here or there.

    python benches/controllers.py [--quick] [--json PATH]
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import rotorfault as rf
from rotorfault.control import registry

HOVER = (0.0, 0.0, -10.0)
DT_S = 1.0 / 400.0
#: Registered controllers timed by their own bench, on their own vehicle.
OWN_BENCH = {"uniform-passive-ftc": "ftc_batch.py", "lanzon-controller": "lanzon_batch.py", "indi-controller": "ftc_batch.py"}


def laws(sim: rf.Simulator) -> dict[str, tuple[Any, Callable[[float, np.ndarray], np.ndarray]]]:
    """``name -> (controller, the same law as a Python callback)`` for the registered controllers
    not in :data:`OWN_BENCH`."""
    lqr = rf.lqr_hover(sim, position=HOVER)
    gain, x_trim, u_trim = np.asarray(lqr.gain), np.asarray(lqr.x_trim), np.asarray(lqr.u_trim)

    def feedback(t: float, x: np.ndarray) -> np.ndarray:
        return u_trim - gain @ (x - x_trim)

    limit = np.full(12, math.inf)
    limit[:3] = 1.0
    tracking = rf.TrackingFeedback.from_feedback(lqr, times_s=[0.0, 1.0], references=[x_trim, x_trim], error_limit=limit)

    def tracked(t: float, x: np.ndarray) -> np.ndarray:
        return u_trim - gain @ np.clip(x - x_trim, -limit, limit)

    lti = rf.Lti(np.zeros((0, 0)), np.zeros((0, 12)), np.zeros((4, 0)), -gain, x_trim, u_trim, dt_s=DT_S)
    allocated = rf.lqr_hover_allocated(sim, rf.Allocator(sim.airframe), position=HOVER)
    law, allocator = allocated.law, allocated.allocator
    v_gain, v_x, v_u = np.asarray(law.gain), np.asarray(law.x_trim), np.asarray(law.u_trim)

    def allocating(t: float, x: np.ndarray) -> np.ndarray:
        commands: np.ndarray = allocator.allocate(v_u - v_gain @ (x - v_x)).commands
        return commands

    relaxed, relaxed_law = _relaxed_hover_law(sim)

    return {
        "open-loop": (rf.OpenLoop.constant(u_trim), lambda t, x: u_trim),
        "linear-feedback": (lqr, feedback),
        "lti": (lti, feedback),
        "tracking-feedback": (tracking, tracked),
        "allocated": (allocated, allocating),
        "relaxed-hover-feedback": (relaxed, relaxed_law),
    }


def _relaxed_hover_law(sim: rf.Simulator) -> tuple[rf.RelaxedHoverFeedback, Callable[[float, np.ndarray], np.ndarray]]:
    """``RelaxedHoverFeedback`` about quad-x's best relaxed hover and its law in numpy (the
    reduced state of ``crates/rfcore/src/control/relaxed_hover.rs``)."""
    best = rf.relaxed_hover(sim.airframe).best
    assert best is not None
    controller = rf.RelaxedHoverFeedback(best, sim.airframe, position=HOVER)
    n, (e1, e2) = np.asarray(best.spin_axis), np.asarray(best.tangent_basis)
    rate0, offset, speed = np.asarray(best.body_rate_rad_s), controller.offsets.position_m, controller.offsets.velocity_m_s
    loop, g, gain, u_trim = controller.outer_loop, sim.airframe.gravity_m_s2, controller.gain, controller.u_trim
    limit, hover = g * math.tan(loop.max_tilt_rad), np.asarray(HOVER)

    def law(t: float, x: np.ndarray) -> np.ndarray:
        (cr, cp, cy), (sr, sp, sy) = np.cos(x[6:9]), np.sin(x[6:9])
        r = np.array([[cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy],
                      [cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy],
                      [-sp, sr * cp, cr * cp]])
        centre, velocity = x[0:3] - r @ offset - hover, x[3:6] - r @ speed
        accel = -loop.position_gain_s2 * centre[:2] - loop.velocity_gain_s * velocity[:2]
        size = float(np.hypot(*accel))
        if size > limit:
            accel *= limit / size
        wanted = np.array([accel[0], accel[1], -g])
        tilt = r.T @ (wanted / np.linalg.norm(wanted)) - n
        reduced = np.array([e1 @ tilt, e2 @ tilt, *(x[9:12] - rate0), -centre[2], -velocity[2]])
        return u_trim - gain @ reduced

    return controller, law


def main() -> None:
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from _results import add_json_option, figure, write

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer and shorter runs (a smoke test)")
    add_json_option(parser)
    args = parser.parse_args()
    quad = rf.Airframe.preset("quad-x")
    sim = rf.Simulator(quad, dt_s=DT_S, substeps=4)
    runs, duration = (16, 2.0) if args.quick else (256, 10.0)
    table = laws(sim)
    missing = [e.name for e in registry.entries() if e.name not in table and e.name not in OWN_BENCH]
    assert not missing, f"no bench for registered controllers {missing}"
    for name, script in OWN_BENCH.items():
        print(f"{name:20s} see benches/{script}")
    figures = []
    for name, (controller, callback) in table.items():
        x0s = [rf.State(position=HOVER) for _ in range(runs)]
        start = time.perf_counter()
        rf.simulate_batch(sim, x0s, duration, controllers=controller, record_every=400)
        rust = runs * duration / DT_S / (time.perf_counter() - start)
        start = time.perf_counter()
        sim.run(rf.State(position=HOVER), duration / 4, controller=callback)
        python = duration / 4 / DT_S / (time.perf_counter() - start)
        print(f"{name:20s} {rust:14,.0f} control steps/s in Rust, {python:12,.0f} as a Python callback: {rust / python:6.1f}x")
        figures.append(figure(f"{name}: closed loop in a batch", rust, "control steps/s", baseline="the same law as a Python callback",
                              baseline_value=python, ratio=rust / python))
    write(args.json_path, "controllers", "Every registered controller in a closed-loop batch", figures,
          reduced="--quick: 16 runs of 2 s" if args.quick else None)


if __name__ == "__main__":
    main()
