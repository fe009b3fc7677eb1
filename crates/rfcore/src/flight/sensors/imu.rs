//! The inertial measurement unit: a three-axis gyroscope and a three-axis accelerometer, each
//! with white noise, a bias random walk, a turn-on bias, scale-factor error, axis misalignment
//! (cross-axis sensitivity) and range saturation, sampled together at the IMU's rate. The
//! accelerometer measures specific force (acceleration minus gravity) at the IMU's mounting
//! point; rotor-induced vibration is modelled as band-limited noise on it ([`Vibration`], off
//! in the datasheet profiles: it belongs to the airframe, not the part).
//!
//! Per axis and sample k (period T = 1 / rate):
//!
//! ```text
//! y_k = sat( (I + S + E) u_k + b_k + n_k )      n_k ~ N(0, N^2 / T)   (white, density N)
//! b_0 ~ N(0, sigma_on^2),  b_{k+1} = b_k + w_k,  w_k ~ N(0, B^2 T)    (random walk, density B)
//! ```
//!
//! with `u` the true body rate or specific force, `S = diag(s)`, `s_i ~ N(0, sigma_s^2)`,
//! `E` the off-diagonal cross-axis matrix, `E_ij ~ N(0, sigma_c^2)`, all drawn once per seed, and
//! `sat` the clamp to +/- range per axis (flagged). The white noise is that of a sensor whose
//! bandwidth is the Nyquist frequency (no on-chip low-pass filter): its Allan deviation is
//! `N / sqrt(tau)`, and the random walk adds `B sqrt(tau / 3)`.

use nalgebra::{Matrix3, Vector3};

use crate::error::{require_finite, require_non_negative, Result, RfError};
use crate::flight::random::Gaussian;
use crate::flight::sensors::clock::SampleClock;
use crate::flight::sensors::{require_positive, streams, DEG, G0_M_S2, TEMPERATURE_WALK};

/// Error model of the gyroscope (1-sigma figures, per axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroProfile {
    /// White noise (angle random walk) density, rad/s/sqrt(Hz).
    pub noise_density_rad_s_rt_hz: f64,
    /// Bias random walk (rate random walk) density, rad/s/sqrt(s).
    pub bias_walk_rad_s_rt_s: f64,
    /// Turn-on bias (zero-rate offset), drawn once per seed, rad/s.
    pub turn_on_bias_rad_s: f64,
    /// Scale-factor error, drawn once per seed and axis (0.005 = 0.5 %).
    pub scale_error: f64,
    /// Cross-axis sensitivity (misalignment), drawn once per seed and axis pair.
    pub cross_axis: f64,
    /// Saturation: the output is clamped to +/- this, rad/s.
    pub range_rad_s: f64,
}

/// Error model of the accelerometer (1-sigma figures, per axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelProfile {
    /// White noise (velocity random walk) density, m/s^2/sqrt(Hz).
    pub noise_density_m_s2_rt_hz: f64,
    /// Bias random walk density, m/s^2/sqrt(s).
    pub bias_walk_m_s2_rt_s: f64,
    /// Turn-on bias (zero-g offset), drawn once per seed, m/s^2.
    pub turn_on_bias_m_s2: f64,
    pub scale_error: f64,
    pub cross_axis: f64,
    /// Saturation: the output is clamped to +/- this, m/s^2.
    pub range_m_s2: f64,
    /// Rotor-induced vibration added to the specific force.
    pub vibration: Vibration,
}

/// Band-limited vibration noise, independent per axis: white noise through a second-order
/// resonator (an AR(2) process with poles `r e^{+/- j theta}`, `theta = 2 pi f / rate`,
/// `r = exp(-pi bandwidth / rate)`), scaled so its standard deviation is `rms_m_s2`. Its
/// spectrum peaks at `frequency_hz` with about `bandwidth_hz` between the half-power points.
/// `rms_m_s2 = 0` turns it off (the default: vibration depends on the airframe, its rotors and
/// their balance, not on the sensor part; set it from a flight log's accelerometer spectrum).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vibration {
    pub rms_m_s2: f64,
    pub frequency_hz: f64,
    pub bandwidth_hz: f64,
}

impl Vibration {
    pub fn off() -> Self {
        Vibration {
            rms_m_s2: 0.0,
            frequency_hz: 0.0,
            bandwidth_hz: 0.0,
        }
    }

    pub fn is_on(&self) -> bool {
        self.rms_m_s2 > 0.0
    }
}

/// An IMU part: both sensors, their common sample rate and where the IMU sits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuProfile {
    /// Output data rate at which gyroscope and accelerometer are both sampled, Hz.
    pub rate_hz: f64,
    pub gyro: GyroProfile,
    pub accel: AccelProfile,
    /// The IMU's position relative to the centre of mass, body axes (FRD), m. Off the centre of
    /// mass the accelerometer also measures `alpha x r + omega x (omega x r)`, which matters on a
    /// spinning vehicle (9 m/s^2 at 30 rad/s and 1 cm).
    pub position_m: Vector3<f64>,
}

impl ImuProfile {
    /// TDK InvenSense ICM-42688-P (datasheet DS-000347, Tables 1 and 2), at 1 kHz (an ODR both
    /// sensors support), +/- 2000 deg/s and +/- 16 g. Bias walks from the temperature
    /// coefficients (see [`TEMPERATURE_WALK`]).
    pub fn icm_42688_p() -> Self {
        ImuProfile {
            rate_hz: 1000.0,
            gyro: GyroProfile {
                noise_density_rad_s_rt_hz: 0.0028 * DEG,
                bias_walk_rad_s_rt_s: TEMPERATURE_WALK.walk(0.005 * DEG),
                turn_on_bias_rad_s: 0.5 * DEG,
                scale_error: 0.005,
                cross_axis: 0.0125,
                range_rad_s: 2000.0 * DEG,
            },
            accel: AccelProfile {
                // 65 ug/sqrt(Hz) on x and y, 70 on z: the larger for all three.
                noise_density_m_s2_rt_hz: 70e-6 * G0_M_S2,
                bias_walk_m_s2_rt_s: TEMPERATURE_WALK.walk(0.15e-3 * G0_M_S2),
                turn_on_bias_m_s2: 20e-3 * G0_M_S2,
                scale_error: 0.005,
                cross_axis: 0.01,
                range_m_s2: 16.0 * G0_M_S2,
                vibration: Vibration::off(),
            },
            position_m: Vector3::zeros(),
        }
    }

    /// InvenSense MPU-6000 (product specification PS-MPU-6000A-00 rev. 3.4, Tables 6.1 and
    /// 6.2), at 1 kHz (the accelerometer's highest ODR), +/- 2000 deg/s and +/- 16 g. The
    /// zero-g offset is +/- 50 mg on x and y and +/- 80 mg on z: 80 mg for all three.
    pub fn mpu_6000() -> Self {
        ImuProfile {
            rate_hz: 1000.0,
            gyro: GyroProfile {
                noise_density_rad_s_rt_hz: 0.005 * DEG,
                // ZRO variation +/- 20 deg/s over -40..+85 C: 0.16 deg/s/K.
                bias_walk_rad_s_rt_s: TEMPERATURE_WALK.walk(20.0 / 125.0 * DEG),
                turn_on_bias_rad_s: 20.0 * DEG,
                scale_error: 0.03,
                cross_axis: 0.02,
                range_rad_s: 2000.0 * DEG,
            },
            accel: AccelProfile {
                noise_density_m_s2_rt_hz: 400e-6 * G0_M_S2,
                // Zero-g change +/- 35 mg (x, y) over 0..70 C: 0.5 mg/K.
                bias_walk_m_s2_rt_s: TEMPERATURE_WALK.walk(35e-3 / 70.0 * G0_M_S2),
                turn_on_bias_m_s2: 80e-3 * G0_M_S2,
                scale_error: 0.03,
                cross_axis: 0.02,
                range_m_s2: 16.0 * G0_M_S2,
                vibration: Vibration::off(),
            },
            position_m: Vector3::zeros(),
        }
    }

    /// Every rule, naming the field (`imu.gyro.noise_density_rad_s_rt_hz`, ...).
    pub fn check(&self) -> Result<()> {
        require_positive("imu.rate_hz", self.rate_hz)?;
        let (g, a) = (&self.gyro, &self.accel);
        let non_negative = [
            (
                "imu.gyro.noise_density_rad_s_rt_hz",
                g.noise_density_rad_s_rt_hz,
            ),
            ("imu.gyro.bias_walk_rad_s_rt_s", g.bias_walk_rad_s_rt_s),
            ("imu.gyro.turn_on_bias_rad_s", g.turn_on_bias_rad_s),
            ("imu.gyro.scale_error", g.scale_error),
            ("imu.gyro.cross_axis", g.cross_axis),
            (
                "imu.accel.noise_density_m_s2_rt_hz",
                a.noise_density_m_s2_rt_hz,
            ),
            ("imu.accel.bias_walk_m_s2_rt_s", a.bias_walk_m_s2_rt_s),
            ("imu.accel.turn_on_bias_m_s2", a.turn_on_bias_m_s2),
            ("imu.accel.scale_error", a.scale_error),
            ("imu.accel.cross_axis", a.cross_axis),
            ("imu.accel.vibration.rms_m_s2", a.vibration.rms_m_s2),
        ];
        for (field, value) in non_negative {
            require_non_negative(field, value)?;
        }
        require_positive("imu.gyro.range_rad_s", g.range_rad_s)?;
        require_positive("imu.accel.range_m_s2", a.range_m_s2)?;
        let v = &a.vibration;
        if v.is_on() {
            require_positive("imu.accel.vibration.frequency_hz", v.frequency_hz)?;
            require_positive("imu.accel.vibration.bandwidth_hz", v.bandwidth_hz)?;
            let nyquist = 0.5 * self.rate_hz;
            if v.frequency_hz + 0.5 * v.bandwidth_hz >= nyquist {
                return Err(RfError::invalid(
                    "imu.accel.vibration.frequency_hz",
                    format!(
                        "frequency + bandwidth / 2 must be below the Nyquist frequency \
                         rate_hz / 2 = {nyquist} Hz, got {} + {} / 2",
                        v.frequency_hz, v.bandwidth_hz
                    ),
                ));
            }
        }
        for (i, &x) in self.position_m.iter().enumerate() {
            require_finite(&format!("imu.position_m[{i}]"), x)?;
        }
        Ok(())
    }
}

/// The ICM-42688-P.
impl Default for ImuProfile {
    fn default() -> Self {
        ImuProfile::icm_42688_p()
    }
}

/// What the simulator hands the IMU at a sample time (body axes, at the centre of mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuTruth {
    pub omega_rad_s: Vector3<f64>,
    /// Body angular acceleration, rad/s^2 (only used when the IMU is off the centre of mass).
    pub angular_acceleration_rad_s2: Vector3<f64>,
    /// Specific force at the centre of mass: `R^T (a - g)` with `a` the world acceleration, m/s^2.
    pub specific_force_m_s2: Vector3<f64>,
}

/// One IMU output sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuSample {
    pub time_s: f64,
    pub gyro_rad_s: Vector3<f64>,
    pub accel_m_s2: Vector3<f64>,
    /// Some gyroscope axis hit its range (the output is clamped there).
    pub gyro_saturated: bool,
    pub accel_saturated: bool,
}

/// One sensor's draws and state: the error matrix `I + S + E`, the bias, the noise scales.
#[derive(Debug, Clone)]
struct Triad {
    transform: Matrix3<f64>,
    bias: Vector3<f64>,
    white_std: f64,
    walk_std: f64,
    range: f64,
}

impl Triad {
    /// Draws the turn-on bias, the scale errors and the cross-axis terms from `gaussian`.
    fn draw(
        gaussian: &mut Gaussian,
        [density, walk, turn_on, scale, cross, range]: [f64; 6],
        period_s: f64,
    ) -> Self {
        let bias = gaussian.vector3() * turn_on;
        let mut transform = Matrix3::identity();
        for i in 0..3 {
            transform[(i, i)] += scale * gaussian.sample();
        }
        for i in 0..3 {
            for j in 0..3 {
                if i != j {
                    transform[(i, j)] = cross * gaussian.sample();
                }
            }
        }
        Triad {
            transform,
            bias,
            white_std: density / period_s.sqrt(),
            walk_std: walk * period_s.sqrt(),
            range,
        }
    }

    /// The measurement of `truth` (plus `extra`), then the bias steps on; `true` if clamped.
    fn measure(
        &mut self,
        gaussian: &mut Gaussian,
        truth: &Vector3<f64>,
        extra: &Vector3<f64>,
    ) -> (Vector3<f64>, bool) {
        let mut y =
            self.transform * truth + self.bias + extra + gaussian.vector3() * self.white_std;
        if self.walk_std > 0.0 {
            self.bias += gaussian.vector3() * self.walk_std;
        }
        let mut saturated = false;
        for v in y.iter_mut() {
            if v.abs() > self.range {
                *v = self.range.copysign(*v);
                saturated = true;
            }
        }
        (y, saturated)
    }
}

/// The AR(2) resonator of [`Vibration`], one per axis, started in its stationary distribution.
#[derive(Debug, Clone)]
pub(crate) struct Resonator {
    a1: f64,
    a2: f64,
    drive_std: f64,
    last: Vector3<f64>,
    before_last: Vector3<f64>,
}

impl Resonator {
    pub(crate) fn new(v: &Vibration, rate_hz: f64, gaussian: &mut Gaussian) -> Self {
        let theta = 2.0 * std::f64::consts::PI * v.frequency_hz / rate_hz;
        let r = (-std::f64::consts::PI * v.bandwidth_hz / rate_hz).exp();
        let (a1, a2) = (2.0 * r * theta.cos(), -r * r);
        // Stationary variance of x_k = a1 x_{k-1} + a2 x_{k-2} + e_k per unit drive variance
        // (Box and Jenkins, eq. 3.2.27).
        let gain = (1.0 - a2) / ((1.0 + a2) * ((1.0 - a2).powi(2) - a1 * a1));
        let var = v.rms_m_s2 * v.rms_m_s2;
        let rho1 = a1 / (1.0 - a2);
        let last = gaussian.vector3() * var.sqrt();
        let before_last = last * rho1 + gaussian.vector3() * (var * (1.0 - rho1 * rho1)).sqrt();
        Resonator {
            a1,
            a2,
            drive_std: (var / gain).sqrt(),
            last,
            before_last,
        }
    }

    pub(crate) fn next(&mut self, gaussian: &mut Gaussian) -> Vector3<f64> {
        let x =
            self.last * self.a1 + self.before_last * self.a2 + gaussian.vector3() * self.drive_std;
        self.before_last = self.last;
        self.last = x;
        x
    }

    /// Lag-1 and lag-2 autocorrelations of the stationary process (Yule-Walker).
    #[cfg(test)]
    pub(crate) fn autocorrelations(&self) -> (f64, f64) {
        let rho1 = self.a1 / (1.0 - self.a2);
        (rho1, self.a1 * rho1 + self.a2)
    }
}

/// A seeded IMU.
#[derive(Debug, Clone)]
pub struct Imu {
    profile: ImuProfile,
    clock: SampleClock,
    gyro: Triad,
    accel: Triad,
    vibration: Option<Resonator>,
    gyro_noise: Gaussian,
    accel_noise: Gaussian,
    saturated_samples: u64,
}

impl Imu {
    /// The IMU of run `seed` (its gyroscope and accelerometer draw from their own streams).
    pub fn new(profile: ImuProfile, seed: u64) -> Result<Self> {
        profile.check()?;
        let period = 1.0 / profile.rate_hz;
        let mut gyro_noise = Gaussian::stream(seed, streams::GYRO);
        let mut accel_noise = Gaussian::stream(seed, streams::ACCEL);
        let g = &profile.gyro;
        let gyro = Triad::draw(
            &mut gyro_noise,
            [
                g.noise_density_rad_s_rt_hz,
                g.bias_walk_rad_s_rt_s,
                g.turn_on_bias_rad_s,
                g.scale_error,
                g.cross_axis,
                g.range_rad_s,
            ],
            period,
        );
        let a = &profile.accel;
        let accel = Triad::draw(
            &mut accel_noise,
            [
                a.noise_density_m_s2_rt_hz,
                a.bias_walk_m_s2_rt_s,
                a.turn_on_bias_m_s2,
                a.scale_error,
                a.cross_axis,
                a.range_m_s2,
            ],
            period,
        );
        let vibration = a
            .vibration
            .is_on()
            .then(|| Resonator::new(&a.vibration, profile.rate_hz, &mut accel_noise));
        Ok(Imu {
            profile,
            clock: SampleClock::new(profile.rate_hz),
            gyro,
            accel,
            vibration,
            gyro_noise,
            accel_noise,
            saturated_samples: 0,
        })
    }

    pub fn profile(&self) -> &ImuProfile {
        &self.profile
    }

    /// Its sample clock (when its samples fall).
    pub fn clock(&self) -> &SampleClock {
        &self.clock
    }

    /// The time of the next sample; the simulator hands [`Imu::sample`] the truth there.
    pub fn next_sample_time_s(&self) -> f64 {
        self.clock.next_time_s()
    }

    pub fn is_due(&self, t_s: f64) -> bool {
        self.clock.is_due(t_s)
    }

    /// The sample at [`Imu::next_sample_time_s`] of the motion `truth`.
    pub fn sample(&mut self, truth: &ImuTruth) -> ImuSample {
        let time_s = self.clock.tick();
        let r = &self.profile.position_m;
        let w = &truth.omega_rad_s;
        let specific_force = truth.specific_force_m_s2
            + truth.angular_acceleration_rad_s2.cross(r)
            + w.cross(&w.cross(r));
        let vibration = match self.vibration.as_mut() {
            Some(v) => v.next(&mut self.accel_noise),
            None => Vector3::zeros(),
        };
        let (gyro_rad_s, gyro_saturated) =
            self.gyro
                .measure(&mut self.gyro_noise, w, &Vector3::zeros());
        let (accel_m_s2, accel_saturated) =
            self.accel
                .measure(&mut self.accel_noise, &specific_force, &vibration);
        if gyro_saturated || accel_saturated {
            self.saturated_samples += 1;
        }
        ImuSample {
            time_s,
            gyro_rad_s,
            accel_m_s2,
            gyro_saturated,
            accel_saturated,
        }
    }

    /// Samples so far with either sensor saturated.
    pub fn saturated_samples(&self) -> u64 {
        self.saturated_samples
    }

    /// The current gyroscope bias (turn-on plus walk), rad/s: the truth an estimator's bias
    /// estimate is scored against.
    pub fn gyro_bias_rad_s(&self) -> Vector3<f64> {
        self.gyro.bias
    }

    pub fn accel_bias_m_s2(&self) -> Vector3<f64> {
        self.accel.bias
    }

    /// The drawn `I + S + E` of the gyroscope and of the accelerometer.
    pub fn error_matrices(&self) -> (Matrix3<f64>, Matrix3<f64>) {
        (self.gyro.transform, self.accel.transform)
    }
}

#[cfg(test)]
#[path = "imu_tests.rs"]
mod tests;
