"""Flying on sensors (``rotorfault.Sensing``): the settings (defaults from the core, checked
fields named), the recorded estimate beside the truth, batches equal to single runs, and Ke's
paper scenarios flown on the truth and on motion capture side by side with their verdicts."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.papers import ke as ke_paper


@pytest.fixture(scope="module")
def quad() -> rf.Airframe:
    return rf.Airframe.preset("quad-x")


@pytest.fixture(scope="module")
def lqr(quad: rf.Airframe) -> rf.LinearFeedback:
    return rf.lqr_hover(rf.Simulator(quad), position=(0, 0, -10))


def test_defaults_come_from_the_core_and_fields_are_checked() -> None:
    s = rf.Sensing()
    assert (s.suite, s.imu, s.imu_rate_hz, s.position_rate_hz, s.seed) == ("mocap", "icm-42688-p", 500.0, None, 0)
    assert s.position_rate_in_effect_hz == 240.0
    assert rf.Sensing.SUITES == ["mocap", "gnss", "rtk"] and rf.Sensing.IMUS == ["icm-42688-p", "mpu-6000"]
    assert s.replace(seed=3) == rf.Sensing(seed=3) != s
    assert pickle.loads(pickle.dumps(rf.Sensing(suite="gnss", seed=5))) == rf.Sensing(suite="gnss", seed=5)
    assert rf.Sensing(suite="gnss").position_rate_in_effect_hz == 5.0
    assert s.gyro_range_rad_s is None and s.gyro_range_in_effect_rad_s == pytest.approx(np.radians(2000.0), rel=1e-15)
    wide = rf.Sensing(gyro_range_rad_s=70.0, seed=2)
    assert wide.gyro_range_in_effect_rad_s == 70.0
    assert pickle.loads(pickle.dumps(wide)) == wide and wide.replace(gyro_range_rad_s=None) == rf.Sensing(seed=2)
    for kwargs, error, message in [
        ({"suite": "vicon"}, ValueError, "^sensing.suite: expected one of mocap, gnss, rtk"),
        ({"suite": 1}, TypeError, "^sensing.suite: expected a string"),
        ({"imu": "bmi088"}, ValueError, "^sensing.imu: expected one of"),
        ({"imu_rate_hz": 0.0}, ValueError, "^sensing.imu_rate_hz: must be > 0"),
        ({"imu_rate_hz": float("nan")}, ValueError, "^sensing.imu_rate_hz"),
        ({"position_rate_hz": 1e5}, ValueError, "^sensing.position_rate_hz"),
        ({"seed": -1}, ValueError, r"^sensing.seed: must lie in \[0, 2\*\*64\)"),
        ({"seed": True}, TypeError, "^sensing.seed: expected an integer"),
        ({"gyro_range_rad_s": 0.0}, ValueError, "^sensing.gyro_range_rad_s: must be > 0"),
        ({"gyro_range_rad_s": float("inf")}, ValueError, "^sensing.gyro_range_rad_s"),
        ({"gyro_range_rad_s": 1001.0}, ValueError, "^sensing.gyro_range_rad_s: must be > 0 and at most 1000 rad/s"),
        ({"gyro_range_rad_s": "wide"}, TypeError, "^sensing.gyro_range_rad_s: expected a real number"),
    ]:
        with pytest.raises(error, match=message):
            rf.Sensing(**kwargs)


def test_noise_and_sensing_together_are_refused(quad: rf.Airframe) -> None:
    with pytest.raises(ValueError, match="^noise, sensing: a run flies on one of them"):
        rf.Simulator(quad, noise=rf.Noise(snr_db=15.0), sensing=rf.Sensing())
    with pytest.raises(TypeError, match="^sensing: expected rotorfault.Sensing"):
        rf.Simulator(quad, sensing="mocap")  # type: ignore[arg-type]


def test_the_run_records_the_estimate_beside_the_truth(quad: rf.Airframe, lqr: rf.LinearFeedback) -> None:
    """The hover LQR on mocap: the estimate it flew on is recorded per row, within the raw mocap
    fixes' 3-D noise (0.35 mm, 0.14 deg: a filter fusing the IMU must beat them) of the truth, and
    ``measured`` is that estimate. A truth run has no estimate and says so."""
    start = rf.State(position=(0, 0, -10))
    truth = rf.Simulator(quad).run(start, 3.0, controller=lqr)
    run = rf.Simulator(quad, sensing=rf.Sensing(seed=2)).run(start, 3.0, controller=lqr)
    assert truth.sensed == "truth" and truth.estimate is None and run.sensed == "mocap"
    assert rf.Simulator(quad, noise=rf.Noise(snr_db=30.0)).run(start, 0.1, controller=lqr).sensed == "paper-noise"
    with pytest.raises(ValueError, match="^estimate_position_error_m: the run flew on truth"):
        truth.estimate_position_error_m  # noqa: B018
    e = run.estimate
    assert e is not None
    n = len(run.t)
    assert e.position.shape == (n, 3) and e.quaternion.shape == (n, 4) and e.std.shape == (n, 15)
    np.testing.assert_array_equal(run.measured, e.vector)
    after = run.t >= 1.0
    position_rms = np.sqrt(np.mean(run.estimate_position_error_m[after] ** 2))
    attitude_rms = np.sqrt(np.mean(run.estimate_attitude_error_rad[after] ** 2))
    assert 0 < position_rms < np.sqrt(3) * 0.2e-3, position_rms
    assert 0 < attitude_rms < np.deg2rad(0.14), np.rad2deg(attitude_rms)
    # The filter's own 3-D position sigma is within a factor 2 of its error.
    sigma = np.sqrt(np.mean(np.sum(e.position_std_m[after] ** 2, axis=1)))
    assert 0.5 < position_rms / sigma < 2.0
    assert e.counts.imu_samples == 3 * 500 + 1 and e.counts.gyro_saturated_samples == 0
    assert not e.gyro_saturated.any()
    # Flying on the estimate moves the vehicle, a little: mm, not m.
    assert 0 < np.abs(run.position - truth.position).max() < 5e-3


def test_a_batch_flies_run_i_with_seed_plus_i(quad: rf.Airframe, lqr: rf.LinearFeedback) -> None:
    sim = rf.Simulator(quad, sensing=rf.Sensing(seed=11))
    starts = [rf.State(position=(0.0, 0.0, -10.0))] * 3
    batch = rf.simulate_batch(sim, starts, 0.5, controllers=lqr)
    chunked = rf.simulate_batch(sim, starts, 0.5, controllers=lqr, progress=True)
    for i, tr in enumerate(batch.trajectories):
        alone = rf.Simulator(quad, sensing=rf.Sensing(seed=11 + i)).run(starts[i], 0.5, controller=lqr)
        np.testing.assert_array_equal(tr.position, alone.position)
        np.testing.assert_array_equal(tr.measured, alone.measured)
        np.testing.assert_array_equal(chunked.trajectories[i].measured, alone.measured)
    assert not np.array_equal(batch.trajectories[0].measured, batch.trajectories[1].measured)


@pytest.mark.parametrize("name", ["fault-free", "one-failure", "two-adjacent"])
def test_ke_scenarios_with_truth_and_with_mocap(name: str) -> None:
    """Ke's uniform passive FTC (``ke-hil``) on its paper's scenarios, on the truth and on mocap:
    the verdict (the whole flight, :mod:`rotorfault.flight.outcomes`) is the same and the window's
    horizontal error moves by at most 2 % or 5 cm. Measured: fault-free holds position on both
    (0 and 18 mm); one failure and two adjacent are off station on both (14.6 / 14.5 m, 15.3 /
    15.2 m): Ke's slow position loop, not the sensors, decides them."""
    truth = ke_paper.run_scenario(name)
    sensed = ke_paper.run_scenario(name, sensing=rf.Sensing())
    assert sensed.trajectory.sensed == "mocap" and truth.trajectory.sensed == "truth"
    a, b = truth.metrics, sensed.metrics
    assert a.outcome == b.outcome, (a.outcome, b.outcome)
    assert a.window_horizontal_error_m is not None and b.window_horizontal_error_m is not None
    assert abs(a.window_horizontal_error_m - b.window_horizontal_error_m) < max(0.05, 0.02 * a.window_horizontal_error_m)


def test_the_report_table_sets_truth_and_sensors_side_by_side() -> None:
    """Ke's report table (:func:`rotorfault.papers.ke.sensing_table`): mocap keeps the fault-free
    hold; GNSS (metres of noise) loses it, and the table says "differs"."""
    truth = [ke_paper.run_scenario("fault-free")]
    mocap = ke_paper.sensing_table(truth, [ke_paper.run_scenario("fault-free", sensing=rf.Sensing())])
    gnss = ke_paper.sensing_table(truth, [ke_paper.run_scenario("fault-free", sensing=rf.Sensing(suite="gnss"))])
    assert "on mocap" in mocap.caption and "on gnss" in gnss.caption
    (row,) = mocap.rows
    assert row[:4] == ("fault-free", "holds", "holds", "same")
    assert 0 < float(row[5]) < 0.35 and 0 < float(row[6]) < 0.14
    (row,) = gnss.rows
    assert row[1] == "holds" and row[2] != "holds" and row[3] == "differs"


#: A ``SensingCounts`` pickled (protocol 4) by the release before fixes were thinned: six fields by
#: keyword (``pickle_protocol!``'s ``__getnewargs_ex__``), no ``thinned_measurements``.
OLD_COUNTS_PICKLE = (
    b"\x80\x04\x95\xbe\x00\x00\x00\x00\x00\x00\x00\x8c\x12rotorfault._rfcore\x94\x8c\rSensingCounts\x94\x93\x94)}\x94("
    b"\x8c\x0bimu_samples\x94M\x90\x01\x8c\x16gyro_saturated_samples\x94K\x01\x8c\x17accel_saturated_samples\x94K\x02"
    b"\x8c\x12fused_measurements\x94K\x1e\x8c\x15rejected_measurements\x94K\x03\x8c\x11late_measurements\x94K\x04u\x92\x94."
)


def test_counts_pickled_before_thinning_existed_load_with_none_thinned() -> None:
    """The field added later has the default its docstring gives (0: that release fused every
    fix); the fields a pickle carries are kept as they were; the new layout round-trips."""
    counts = pickle.loads(OLD_COUNTS_PICKLE)
    assert type(counts) is _rfcore.SensingCounts
    assert [getattr(counts, f) for f in counts.FIELDS] == [400, 1, 2, 30, 3, 4, 0]
    assert counts.FIELDS[-1] == "thinned_measurements"
    back = pickle.loads(pickle.dumps(counts))
    assert [getattr(back, f) for f in back.FIELDS] == [400, 1, 2, 30, 3, 4, 0]
    with pytest.raises(TypeError, match="late_measurements"):
        type(counts)(imu_samples=1, gyro_saturated_samples=0, accel_saturated_samples=0, fused_measurements=0,
                     rejected_measurements=0)  # the fields every release had stay required


def test_a_wider_gyro_range_stops_the_clamp_of_a_spin_past_the_parts_range() -> None:
    """INDI on the ke-quadcopter after two opposing rotors are lost spins at about 40 rad/s, past
    the ICM-42688-P's +-2000 deg/s (34.9 rad/s): the gyro clamps; with ``gyro_range_rad_s`` 70 it
    reads the spin, nothing else of the sensors changes (before the spin the two flights are the
    same, bit for bit), and the clamp's flags and counts say which flight clamped."""
    from rotorfault.control import ke

    pre = ke.preset("ke-hil")
    faults = [rf.RotorFault(1, 1.0), rf.RotorFault(3, 1.0)]
    law = rf.IndiController(pre.airframe, failures=faults, position=(0.0, 0.0, -10.0))
    start = rf.State(position=(0.0, 0.0, -10.0))
    runs = {}
    for name, sensing in (("part", rf.Sensing(seed=4)), ("wide", rf.Sensing(seed=4, gyro_range_rad_s=70.0))):
        runs[name] = pre.simulator(sensing=sensing).run(start, 16.0, controller=law, faults=faults)
    part, wide = runs["part"], runs["wide"]
    spin = np.abs(np.asarray(wide.omega)[np.asarray(wide.t) > 13.0, 2])
    assert spin.min() > 36.0 and spin.max() < 70.0, (spin.min(), spin.max())  # past the part's range, inside the wide one
    assert part.estimate.counts.gyro_saturated_samples > 1000 and np.asarray(part.estimate.gyro_saturated).any()
    assert wide.estimate.counts.gyro_saturated_samples == 0 and not np.asarray(wide.estimate.gyro_saturated).any()
    before = np.asarray(part.t) < 1.0
    np.testing.assert_array_equal(np.asarray(part.position)[before], np.asarray(wide.position)[before])
