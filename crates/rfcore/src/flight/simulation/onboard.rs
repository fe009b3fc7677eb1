//! One run's sensors and estimator ([`Onboard`]): what the vehicle measures and what its
//! estimator makes of it, fed from the truth between control steps ([`Tape`]).
//!
//! After each control period the simulator hands the period's nodes to [`Onboard::catch_up`],
//! which takes every sensor sample due up to the period's end, in time order, each at its own
//! time on its own clock (the truth there by the tape's Taylor extension), and feeds the
//! estimator: a position fix (and the magnetometer) when it arrives (after its latency), the IMU
//! samples as they come. At a control step the controller gets the estimate at the newest IMU
//! sample, carried to the control time ([`Onboard::estimate`]) and, if it reads samples, the bias-corrected gyro and
//! accelerometer samples and the rotor thrusts from rotor-speed feedback
//! ([`Onboard::rotor_thrust`]).
//!
//! Rotor-speed feedback to thrust: a fixed-pitch rotor with a thrust coefficient turns at
//! `omega = sqrt(f / k_f)`; the sensor (noise, DShot quantisation, latency) measures that speed and
//! the thrust is `k_f omega_m^2`. Without a coefficient (rotor speed not modelled, e.g. Ke's
//! vehicle) and for variable pitch (thrust depends on the pitch too) the sensor measures
//! `sqrt(|f|)` (`k_f = 1` N s^2): its rate, latency and relative noise (on the speed, so twice on
//! the thrust) apply, the DShot quantisation, which needs the true speed, does not. Before the
//! first reading arrives the controller gets none (`None`).

use nalgebra::Vector3;

use crate::cancel::Cancel;
use crate::error::Result;
use crate::flight::actuator::Actuators;
use crate::flight::estimation::{Estimate, Estimator, EstimatorSettings, FusionCounts, ERROR_DIM};
use crate::flight::sensors::{
    ImuSample, ImuTruth, MagnetometerSample, PositionSample, SensorSuite, SensorSuiteProfile,
};
use crate::flight::simulation::recording::{EstimateRow, SensingRecord};
use crate::flight::simulation::sensing::Sensing;
use crate::flight::simulation::tape::Tape;
use crate::flight::vehicle::Vehicle;
use crate::state::{ControllerInput, RigidBodyState};

/// Rotor-speed feedback converted to thrust (module docs).
#[derive(Debug, Clone)]
struct RotorFeedback {
    /// `k_f` of `f = k_f omega^2` (1 for the `sqrt(|f|)` reading).
    coefficient: f64,
    speeds: Vec<f64>,
    thrust_n: Vec<f64>,
    arrived: bool,
}

/// Which sensor takes the next sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Next {
    Imu,
    Position,
    Magnetometer,
    RotorSpeed,
}

/// What the estimator reads from the sensors, in the order it reads it.
#[derive(Debug, Clone, Copy)]
enum Reading {
    Imu(ImuSample),
    Position(PositionSample),
    Magnetometer(MagnetometerSample),
}

/// Readings taken before they are fed (bounds the buffer of a long control period).
const READINGS_PER_CHUNK: usize = 64;

/// One run's sensors and its estimator. In a group whose sensors and estimators fly in lanes
/// ([`crate::flight::simulation::onboard_lanes`]) the run's sensors sample here, one method per
/// sensor, on the group's schedule and from the group's tape; its own estimator and tape are not
/// used.
pub(crate) struct Onboard {
    name: &'static str,
    /// The profile the sensors were built from (the runs of a group in lanes share it).
    profile: SensorSuiteProfile,
    sensors: SensorSuite,
    estimator: Estimator,
    rotor: Option<RotorFeedback>,
    imu_samples: u64,
    gyro_saturated_samples: u64,
    accel_saturated_samples: u64,
    readings: Vec<Reading>,
}

impl Onboard {
    /// The sensors of `sensing` and their estimator, starting from the true initial state `x0`
    /// (an aligned start: the filter's initial uncertainty is its settings'), and the tape the
    /// integrator records for them (with rotor thrusts when `rotor_feedback`).
    pub(crate) fn new(
        sensing: &Sensing,
        x0: &RigidBodyState,
        actuators: &Actuators,
        rotor_feedback: bool,
    ) -> Result<(Self, Tape)> {
        let mut profile = sensing.profile();
        let coefficient = actuators.speed_thrust_coefficient();
        if coefficient.is_none() {
            profile.rotor_speed.pole_pairs = 0;
        }
        let rotors = actuators.rotor_count();
        let sensors = SensorSuite::new(&profile, rotors, sensing.seed)?;
        let estimator = Estimator::new(sensing.estimator(), x0)?;
        let rotor = rotor_feedback.then(|| RotorFeedback {
            coefficient: coefficient.unwrap_or(1.0),
            speeds: vec![0.0; rotors],
            thrust_n: vec![0.0; rotors],
            arrived: false,
        });
        let tape = Tape::new(if rotor_feedback { rotors } else { 0 });
        let onboard = Onboard {
            name: sensing.name(),
            profile,
            sensors,
            estimator,
            rotor,
            imu_samples: 0,
            gyro_saturated_samples: 0,
            accel_saturated_samples: 0,
            readings: Vec::with_capacity(READINGS_PER_CHUNK + 8),
        };
        Ok((onboard, tape))
    }

    /// The sensor due first at or before `t_end_s` and the time of its sample (ties: the one
    /// listed first here; the order of equal times does not matter to the estimator, which fuses
    /// by time of validity), with the rotor-speed sensor of `rotor` (this run's when it has rotor
    /// feedback; a group flown in lanes passes its first run with rotor feedback, whose clock
    /// every such run shares).
    pub(crate) fn next_due(&self, rotor: Option<&Onboard>, t_end_s: f64) -> Option<(Next, f64)> {
        let s = &self.sensors;
        let mut best: Option<(f64, Next)> = None;
        let mut consider = |due: bool, time: f64, which: Next| {
            if due && best.is_none_or(|(t, _)| time < t) {
                best = Some((time, which));
            }
        };
        consider(
            s.position.is_due(t_end_s),
            s.position.next_sample_time_s(),
            Next::Position,
        );
        if let Some(m) = &s.magnetometer {
            consider(
                m.is_due(t_end_s),
                m.next_sample_time_s(),
                Next::Magnetometer,
            );
        }
        if let Some(r) = rotor {
            let r = &r.sensors.rotor_speed;
            consider(r.is_due(t_end_s), r.next_sample_time_s(), Next::RotorSpeed);
        }
        consider(s.imu.is_due(t_end_s), s.imu.next_sample_time_s(), Next::Imu);
        best.map(|(t, which)| (which, t))
    }

    /// The time of the next sample of `which`.
    pub(crate) fn next_sample_time_s(&self, which: Next) -> f64 {
        let s = &self.sensors;
        match which {
            Next::Imu => s.imu.next_sample_time_s(),
            Next::Position => s.position.next_sample_time_s(),
            Next::Magnetometer => s
                .magnetometer
                .as_ref()
                .map_or(f64::INFINITY, |m| m.next_sample_time_s()),
            Next::RotorSpeed => s.rotor_speed.next_sample_time_s(),
        }
    }

    /// `true` when the run's controller reads rotor speeds (it has rotor feedback).
    pub(crate) fn reads_rotor_speeds(&self) -> bool {
        self.rotor.is_some()
    }

    /// The position source measures `truth` at its next sample time.
    pub(crate) fn sample_position(&mut self, truth: &RigidBodyState) {
        self.sensors.position.sample(truth);
    }

    /// The magnetometer's reading of `truth` at its next sample time (`None` without one).
    pub(crate) fn sample_magnetometer(
        &mut self,
        truth: &RigidBodyState,
    ) -> Option<MagnetometerSample> {
        self.sensors.magnetometer.as_mut().map(|m| m.sample(truth))
    }

    /// The rotor-speed sensor measures the speeds of the rotor thrusts `thrust_n` at its next
    /// sample time (module docs; nothing without rotor feedback).
    pub(crate) fn sample_rotor_speeds(
        &mut self,
        thrust_n: impl IntoIterator<Item = f64>,
    ) -> Result<()> {
        let Some(rotor) = self.rotor.as_mut() else {
            return Ok(());
        };
        for (w, f) in rotor.speeds.iter_mut().zip(thrust_n) {
            *w = (f.abs() / rotor.coefficient).sqrt().copysign(f);
        }
        self.sensors.rotor_speed.sample(&rotor.speeds)
    }

    /// The IMU's sample of `truth` at its next sample time, counted.
    pub(crate) fn sample_imu(&mut self, truth: &ImuTruth) -> ImuSample {
        let sample = self.sensors.imu.sample(truth);
        self.imu_samples += 1;
        self.gyro_saturated_samples += u64::from(sample.gyro_saturated);
        self.accel_saturated_samples += u64::from(sample.accel_saturated);
        sample
    }

    /// The oldest position fix that has arrived by `t_s` (call until `None`).
    pub(crate) fn poll_position(&mut self, t_s: f64) -> Option<PositionSample> {
        self.sensors.position.poll(t_s)
    }

    /// The rotor thrusts of the newest rotor-speed reading arrived by `t_s`, for the controller.
    pub(crate) fn take_rotor_reading(&mut self, t_s: f64) {
        if let Some(rotor) = self.rotor.as_mut() {
            if self.sensors.rotor_speed.poll(t_s) {
                rotor.arrived = true;
                for (f, &w) in rotor
                    .thrust_n
                    .iter_mut()
                    .zip(self.sensors.rotor_speed.latest())
                {
                    *f = rotor.coefficient * w * w.abs();
                }
            }
        }
    }

    /// `true` when a sensor takes a sample at a time in `[from_s, to_s)` (the span of a tape
    /// node: a sample there reads that node, so a node whose span no sample falls in is read by
    /// none and need not be written).
    pub(crate) fn samples_in(&self, from_s: f64, to_s: f64) -> bool {
        let s = &self.sensors;
        s.imu.clock().has_sample_in(from_s, to_s)
            || s.position.clock().has_sample_in(from_s, to_s)
            || s.magnetometer
                .as_ref()
                .is_some_and(|m| m.clock().has_sample_in(from_s, to_s))
            || (self.rotor.is_some() && s.rotor_speed.clock().has_sample_in(from_s, to_s))
    }

    /// `true` when a sensor takes a sample at or just after `t_s` that is due at `t_s` (it
    /// reads the node at `t_s`, the last of a control period).
    pub(crate) fn samples_due_at_or_after(&self, t_s: f64) -> bool {
        let s = &self.sensors;
        s.imu.clock().has_due_sample_at_or_after(t_s)
            || s.position.clock().has_due_sample_at_or_after(t_s)
            || s.magnetometer
                .as_ref()
                .is_some_and(|m| m.clock().has_due_sample_at_or_after(t_s))
            || (self.rotor.is_some() && s.rotor_speed.clock().has_due_sample_at_or_after(t_s))
    }

    /// Takes every sample due up to `t_end_s` from `tape` (module docs) and feeds the estimator
    /// with them in time order: the readings are taken in chunks ([`Onboard::take_samples`]),
    /// each fed before the next is taken.
    pub(crate) fn catch_up(
        &mut self,
        tape: &mut Tape,
        vehicle: &Vehicle,
        t_end_s: f64,
        cancel: &Cancel,
    ) -> Result<()> {
        let mut readings = std::mem::take(&mut self.readings);
        loop {
            readings.clear();
            let done = self.take_samples(tape, vehicle, t_end_s, cancel, &mut readings)?;
            for reading in &readings {
                match reading {
                    Reading::Imu(sample) => self.estimator.push_imu(sample)?,
                    Reading::Position(fix) => self.estimator.push_position(fix),
                    Reading::Magnetometer(sample) => self.estimator.push_magnetometer(sample),
                }
            }
            if done {
                break;
            }
        }
        self.readings = readings;
        Ok(())
    }

    /// Takes the samples due up to `t_end_s` from `tape`, in time order, each at its own time on
    /// its own clock, appending what the estimator reads to `readings` (a position fix when it
    /// arrives, the magnetometer, the IMU), stopping before the next sample once there are
    /// [`READINGS_PER_CHUNK`]; `true` when every sample up to `t_end_s` is taken (then the
    /// rotor-speed reading due by then is in place too). `cancel` is checked before each sample:
    /// a control period holds `dt_s x imu_rate_hz` IMU samples (a 100 s period at 32 kHz is 3.2
    /// million, about 5 s of filter steps), so the driver's check once per period alone did not
    /// bound the time to stop. A check is one atomic load beside the microseconds of a filter
    /// step.
    fn take_samples(
        &mut self,
        tape: &mut Tape,
        vehicle: &Vehicle,
        t_end_s: f64,
        cancel: &Cancel,
        readings: &mut Vec<Reading>,
    ) -> Result<bool> {
        let rotor = self.reads_rotor_speeds();
        // The group's schedule in lanes takes the same samples in the same order
        // (`OnboardLanes::catch_up`): a change here is a change there.
        while let Some((which, t)) = self.next_due(rotor.then_some(&*self), t_end_s) {
            if readings.len() >= READINGS_PER_CHUNK {
                return Ok(false);
            }
            cancel.check()?;
            match which {
                Next::Position => self.sample_position(&tape.state_at(vehicle, t)),
                Next::Magnetometer => {
                    if let Some(m) = self.sample_magnetometer(&tape.state_at(vehicle, t)) {
                        readings.push(Reading::Magnetometer(m));
                    }
                }
                Next::RotorSpeed => self.sample_rotor_speeds(tape.thrust_at(t).iter().copied())?,
                Next::Imu => {
                    while let Some(fix) = self.poll_position(t) {
                        readings.push(Reading::Position(fix));
                    }
                    readings.push(Reading::Imu(
                        self.sample_imu(&tape.imu_truth_at(vehicle, t)),
                    ));
                }
            }
        }
        while let Some(fix) = self.poll_position(t_end_s) {
            readings.push(Reading::Position(fix));
        }
        self.take_rotor_reading(t_end_s);
        Ok(true)
    }

    /// The estimate carried from the newest IMU sample to the control step at `t_s`
    /// ([`Estimate::carried`]).
    pub(crate) fn estimate(&self, t_s: f64) -> Estimate {
        self.estimator
            .estimate()
            .carried(self.estimator.settings().gravity_m_s2, t_s)
    }

    /// What the controller sees at a control step with `estimate`: the estimated state and, for a
    /// controller that reads samples, the bias-corrected gyro and accelerometer samples the
    /// estimate carries and the rotor thrusts from rotor-speed feedback (one rule for the scalar
    /// driver and the lanes).
    pub(crate) fn controller_input<'a>(
        &'a self,
        estimate: &'a Estimate,
        reads_samples: bool,
    ) -> ControllerInput<'a> {
        if reads_samples {
            ControllerInput {
                state: &estimate.state,
                gyro_rad_s: Some(estimate.gyro_rad_s),
                specific_force_m_s2: Some(estimate.accel_m_s2),
                rotor_thrust_n: self.rotor_thrust(),
            }
        } else {
            ControllerInput::state_only(&estimate.state)
        }
    }

    /// The rotor thrusts from the newest rotor-speed reading, N (`None` before the first or
    /// without rotor feedback).
    pub(crate) fn rotor_thrust(&self) -> Option<&[f64]> {
        self.rotor
            .as_ref()
            .filter(|r| r.arrived)
            .map(|r| &r.thrust_n[..])
    }

    /// The recorded row of `estimate` (the covariance's sigmas at the fusion horizon).
    pub(crate) fn row(&self, estimate: &Estimate) -> EstimateRow {
        let p = self.estimator.covariance();
        row(estimate, &std::array::from_fn(|i| p[(i, i)]))
    }

    /// The record a run starts with (rows to come).
    pub(crate) fn record(&self, rows: usize) -> SensingRecord {
        SensingRecord {
            name: self.name,
            rows: Vec::with_capacity(rows),
            imu_samples: 0,
            gyro_saturated_samples: 0,
            accel_saturated_samples: 0,
            fusion: Default::default(),
        }
    }

    /// The run's counts into `record`.
    pub(crate) fn finish(&self, record: &mut SensingRecord) {
        self.finish_with(record, self.estimator.counts());
    }

    /// The run's sample counts and the estimator's `fusion` counts into `record`.
    pub(crate) fn finish_with(&self, record: &mut SensingRecord, fusion: FusionCounts) {
        record.imu_samples = self.imu_samples;
        record.gyro_saturated_samples = self.gyro_saturated_samples;
        record.accel_saturated_samples = self.accel_saturated_samples;
        record.fusion = fusion;
    }

    /// The estimator settings of the run's sensors.
    pub(crate) fn estimator_settings(&self) -> &EstimatorSettings {
        self.estimator.settings()
    }

    /// The profile of the run's sensors.
    pub(crate) fn profile(&self) -> &SensorSuiteProfile {
        &self.profile
    }

    /// `true` when the run's position source may drop fixes at random (its schedule is then
    /// its own, not its group's).
    pub(crate) fn drops_fixes(&self) -> bool {
        self.sensors.position.profile().dropouts.is_some()
    }
}

/// The recorded row of `estimate` with the covariance's diagonal `variances`.
pub(crate) fn row(estimate: &Estimate, variances: &[f64; ERROR_DIM]) -> EstimateRow {
    EstimateRow {
        state: estimate.state,
        std: variances.map(|v| v.max(0.0).sqrt()),
        gyro_saturated: estimate.gyro_saturated,
        accel_saturated: estimate.accel_saturated,
    }
}

/// The row of a step without an estimate (a divergence row).
pub(crate) fn nan_row() -> EstimateRow {
    let nan = Vector3::repeat(f64::NAN);
    EstimateRow {
        state: RigidBodyState {
            position_m: nan,
            velocity_m_s: nan,
            attitude: nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
                f64::NAN,
                f64::NAN,
                f64::NAN,
                f64::NAN,
            )),
            omega_rad_s: nan,
        },
        std: [f64::NAN; ERROR_DIM],
        gyro_saturated: false,
        accel_saturated: false,
    }
}
