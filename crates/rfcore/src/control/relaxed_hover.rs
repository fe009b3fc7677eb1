//! Linear feedback about a relaxed hover (Mueller and D'Andrea's cascade): an outer loop turns
//! the position error into the up direction the vehicle should spin about, and a gain `K`
//! (designed in Python on the analysis's linear model) holds the reduced attitude and altitude:
//!
//! `u = u_trim - K [e1.(n_B - n), e2.(n_B - n), omega - omega_0, z, w]`
//!
//! with `n_B = R^T u_des` the desired up direction seen from the body (`u_des` = up when the
//! vehicle is on its set point), `n, e1, e2` the solution's axis and tangent basis, `z, w` the
//! altitude error (up) and its rate. A spinning vehicle's centre of mass circles at the spin
//! rate; the outer loop steers the circle's centre, `p - R c_p` (velocity `v - R c_v`) with the
//! body-fixed offsets `c_p`, `c_v` of the periodic solution, so it does not chase the circle.
//! Time-invariant in body axes; yaw is not controlled (it turns with the spin).
//!
//! Integral action (`integral_gain_s3 > 0`): the outer loop adds `-k_i \int e dt` of the
//! centre's horizontal error, so a constant force (wind on the drag, a thrust error) leaves no
//! steady horizontal offset. Anti-windup: the integral is frozen while the wanted acceleration is
//! at its tilt limit, and its own share is kept within that limit.
//!
//! Altitude integral action (`altitude_integral_gain_s > 0`): the gain acts on
//! `z + k_z \int z dt` in place of `z`, so a weight the trim does not carry (a mass or thrust
//! coefficient error) leaves no steady altitude offset (without it: 1.15 m on the Lanzon
//! quadrotor 17 % heavier than its design). Anti-windup: the integral's share `k_z \int z dt` is
//! kept within [`ALTITUDE_INTEGRAL_LIMIT_M`].

use nalgebra::{DMatrix, DVector, Vector3};

use super::integral::PositionIntegral;
use super::{require_finite_matrix, Controller};
use crate::error::{require_all_finite, Result, RfError};
use crate::state::RigidBodyState;

/// States of the reduced model the gain acts on.
pub const REDUCED_STATES: usize = 7;
/// Largest share `k_z \int z dt` of the altitude integral, m: a mass 20 % above the design's
/// (the campaign's largest error) needs about 1.2 m (module docs); twice that, so the limit
/// only stops a wind-up (a long fall the loop cannot stop).
pub const ALTITUDE_INTEGRAL_LIMIT_M: f64 = 2.5;

/// The outer loop: desired horizontal acceleration `-k_p e - k_d v - k_i \int e dt` of the
/// circle's centre, limited to `g tan(max_tilt_rad)`, tilts the up direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxedHoverOuterLoop {
    /// `k_p`, 1/s^2.
    pub position_gain_s2: f64,
    /// `k_d`, 1/s.
    pub velocity_gain_s: f64,
    /// Largest tilt of the desired up direction, rad.
    pub max_tilt_rad: f64,
    /// `k_i`, 1/s^3: integral action on the centre's horizontal error (0: none, the default, so
    /// the designs flown so far are unchanged).
    pub integral_gain_s3: f64,
    /// `k_z`, 1/s: integral action on the altitude error (module docs; 0: none, the default).
    pub altitude_integral_gain_s: f64,
}

impl Default for RelaxedHoverOuterLoop {
    /// A loop well below the attitude loop's bandwidth: 0.5 rad/s natural frequency, damping 1.
    fn default() -> Self {
        RelaxedHoverOuterLoop {
            position_gain_s2: 0.25,
            velocity_gain_s: 1.0,
            max_tilt_rad: 0.2,
            integral_gain_s3: 0.0,
            altitude_integral_gain_s: 0.0,
        }
    }
}

impl RelaxedHoverOuterLoop {
    pub fn check(&self) -> Result<()> {
        for (field, value) in [
            ("outer_loop.position_gain_s2", self.position_gain_s2),
            ("outer_loop.velocity_gain_s", self.velocity_gain_s),
            ("outer_loop.integral_gain_s3", self.integral_gain_s3),
            (
                "outer_loop.altitude_integral_gain_s",
                self.altitude_integral_gain_s,
            ),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(RfError::invalid(
                    field,
                    format!("must be finite and >= 0, got {value}"),
                ));
            }
        }
        let t = self.max_tilt_rad;
        if !(t > 0.0 && t < std::f64::consts::FRAC_PI_2) {
            return Err(RfError::invalid(
                "outer_loop.max_tilt_rad",
                format!("must lie in (0, pi/2), got {t}"),
            ));
        }
        Ok(())
    }
}

/// The solution the feedback holds, in body axes.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxedHoverTrim {
    /// The up axis `n` (unit) and its tangent basis `e1`, `e2` (`(e1, e2, n)` right-handed).
    pub axis: [f64; 3],
    pub e1: [f64; 3],
    pub e2: [f64; 3],
    /// `omega_0 = s n`, rad/s.
    pub body_rate_rad_s: [f64; 3],
    /// Where the centre of mass sits relative to the circle's centre, and its velocity, both
    /// body axes (constant along the periodic solution), m and m/s.
    pub circle_offset_m: [f64; 3],
    pub circle_velocity_m_s: [f64; 3],
    pub gravity_m_s2: f64,
}

/// `u = u_trim - K x` about a relaxed hover, with the outer loop (module docs).
#[derive(Debug, Clone)]
pub struct RelaxedHoverFeedback {
    axis: Vector3<f64>,
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    body_rate: Vector3<f64>,
    circle_offset: Vector3<f64>,
    circle_velocity: Vector3<f64>,
    gravity: f64,
    u_trim: DVector<f64>,
    gain: DMatrix<f64>,
    position: Vector3<f64>,
    outer: RelaxedHoverOuterLoop,
    /// `\int e dt` of the centre's horizontal error (world north, east), m s.
    integral: PositionIntegral<2>,
    /// `\int z dt` of the altitude error (up), m s, stepped on `integral`'s time base.
    altitude_integral: PositionIntegral<1>,
}

impl RelaxedHoverFeedback {
    /// `gain`: commands x 7; `position_m`: the set point (world NED).
    pub fn new(
        trim: &RelaxedHoverTrim,
        u_trim: &[f64],
        gain: DMatrix<f64>,
        position_m: [f64; 3],
        outer: RelaxedHoverOuterLoop,
    ) -> Result<Self> {
        for (field, v) in [
            ("axis", &trim.axis),
            ("e1", &trim.e1),
            ("e2", &trim.e2),
            ("body_rate_rad_s", &trim.body_rate_rad_s),
            ("circle_offset_m", &trim.circle_offset_m),
            ("circle_velocity_m_s", &trim.circle_velocity_m_s),
            ("position_m", &position_m),
        ] {
            require_all_finite(field, v)?;
        }
        let (n, e1, e2) = (
            Vector3::from(trim.axis),
            Vector3::from(trim.e1),
            Vector3::from(trim.e2),
        );
        let frame = nalgebra::Matrix3::from_columns(&[e1, e2, n]);
        if (frame.transpose() * frame - nalgebra::Matrix3::identity()).amax() > 1e-9
            || frame.determinant() < 0.0
        {
            return Err(RfError::invalid(
                "axis",
                "(e1, e2, axis) must be a right-handed orthonormal frame",
            ));
        }
        if !(trim.gravity_m_s2.is_finite() && trim.gravity_m_s2 > 0.0) {
            return Err(RfError::invalid(
                "gravity_m_s2",
                format!("must be finite and > 0, got {}", trim.gravity_m_s2),
            ));
        }
        outer.check()?;
        require_all_finite("u_trim", u_trim)?;
        require_finite_matrix("gain", &gain)?;
        if gain.shape() != (u_trim.len(), REDUCED_STATES) {
            return Err(RfError::shape(
                "gain",
                format!(
                    "{} x {REDUCED_STATES} (commands x reduced states)",
                    u_trim.len()
                ),
                format!("{} x {}", gain.nrows(), gain.ncols()),
            ));
        }
        Ok(RelaxedHoverFeedback {
            axis: n,
            e1,
            e2,
            body_rate: Vector3::from(trim.body_rate_rad_s),
            circle_offset: Vector3::from(trim.circle_offset_m),
            circle_velocity: Vector3::from(trim.circle_velocity_m_s),
            gravity: trim.gravity_m_s2,
            u_trim: DVector::from_column_slice(u_trim),
            gain,
            position: Vector3::from(position_m),
            outer,
            integral: PositionIntegral::default(),
            altitude_integral: PositionIntegral::default(),
        })
    }

    /// The centre's horizontal error (m) and velocity (m/s) in world axes.
    fn centre_error(&self, measured: &RigidBodyState) -> (Vector3<f64>, Vector3<f64>) {
        let r = measured.attitude;
        let centre = measured.position_m - r * self.circle_offset - self.position;
        let velocity = measured.velocity_m_s - r * self.circle_velocity;
        (centre, velocity)
    }

    /// The wanted horizontal acceleration and whether it is at the tilt limit.
    fn wanted_accel(
        &self,
        centre: &Vector3<f64>,
        velocity: &Vector3<f64>,
    ) -> (nalgebra::Vector2<f64>, bool) {
        let o = &self.outer;
        let mut accel = -o.position_gain_s2 * centre.xy()
            - o.velocity_gain_s * velocity.xy()
            - o.integral_gain_s3 * nalgebra::Vector2::from(self.integral.sum_m_s());
        let limit = self.gravity * o.max_tilt_rad.tan();
        let saturated = accel.norm() > limit;
        if saturated {
            accel *= limit / accel.norm();
        }
        (accel, saturated)
    }

    /// Advances the integral to `t_s` (rectangle rule over the time since the last call; frozen
    /// while the wanted acceleration is at its limit, and its share kept within the limit).
    fn integrate(&mut self, t_s: f64, measured: &RigidBodyState) {
        let k_i = self.outer.integral_gain_s3;
        let k_z = self.outer.altitude_integral_gain_s;
        // One time base for both integrals (the horizontal one's); a frozen integral still moves it.
        let step = self.integral.advance(t_s);
        let (Some(dt), true) = (step, k_i > 0.0 || k_z > 0.0) else {
            return;
        };
        let (centre, velocity) = self.centre_error(measured);
        if !centre.iter().all(|v| v.is_finite()) {
            return;
        }
        if k_z > 0.0 {
            let limit = ALTITUDE_INTEGRAL_LIMIT_M / k_z;
            self.altitude_integral.add_clamped(dt, [-centre.z], [limit]);
        }
        if k_i == 0.0 || self.wanted_accel(&centre, &velocity).1 {
            return;
        }
        let limit = self.gravity * self.outer.max_tilt_rad.tan() / k_i;
        self.integral
            .add_norm_limited(dt, [centre.x, centre.y], limit);
    }

    /// Starts the integrals where a healthy loop flying until now left them (a bumpless hand-over,
    /// [`super::hover_handover`]): the altitude integral at `altitude_integral_m_s` (m s, up; its
    /// share kept within [`ALTITUDE_INTEGRAL_LIMIT_M`]), the horizontal one at
    /// `horizontal_integral_m_s` (m s, north and east: the circle centre's error integral, whose
    /// share `-k_i \int e dt` of the wanted acceleration is kept within the tilt limit). An
    /// integral whose gain is 0, or a non-finite start, stays 0. The next call only sets the
    /// integrals' time base.
    pub fn start_integrals(
        &mut self,
        altitude_integral_m_s: f64,
        horizontal_integral_m_s: nalgebra::Vector2<f64>,
    ) {
        self.reset();
        let k_z = self.outer.altitude_integral_gain_s;
        if k_z > 0.0 && altitude_integral_m_s.is_finite() {
            let limit = ALTITUDE_INTEGRAL_LIMIT_M / k_z;
            self.altitude_integral
                .set_sum_m_s([altitude_integral_m_s.clamp(-limit, limit)]);
        }
        let k_i = self.outer.integral_gain_s3;
        if k_i > 0.0 && horizontal_integral_m_s.iter().all(|v| v.is_finite()) {
            let mut integral = horizontal_integral_m_s;
            let limit = self.gravity * self.outer.max_tilt_rad.tan() / k_i;
            if integral.norm() > limit {
                integral *= limit / integral.norm();
            }
            self.integral.set_sum_m_s([integral.x, integral.y]);
        }
    }

    /// The circle centre's horizontal error integral, m s (north, east).
    pub fn horizontal_integral_m_s(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::from(self.integral.sum_m_s())
    }

    /// The reduced state `[a, b, dp, dq, dr, z, w]` the gain acts on (module docs).
    pub fn reduced_state(&self, measured: &RigidBodyState) -> [f64; REDUCED_STATES] {
        let r = measured.attitude;
        let (centre, velocity) = self.centre_error(measured);
        let (accel, _) = self.wanted_accel(&centre, &velocity);
        let up_wanted = Vector3::new(accel.x, accel.y, -self.gravity).normalize();
        let n_body = r.inverse() * up_wanted - self.axis;
        let rate = measured.omega_rad_s - self.body_rate;
        [
            self.e1.dot(&n_body),
            self.e2.dot(&n_body),
            rate.x,
            rate.y,
            rate.z,
            -centre.z + self.outer.altitude_integral_gain_s * self.altitude_integral.sum_m_s()[0],
            -velocity.z,
        ]
    }
}

impl Controller for RelaxedHoverFeedback {
    fn command_count(&self) -> usize {
        self.u_trim.len()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.integrate(t_s, measured);
        let x = self.reduced_state(measured);
        for (i, o) in out.iter_mut().enumerate() {
            let feedback: f64 = (0..REDUCED_STATES).map(|j| self.gain[(i, j)] * x[j]).sum();
            *o = self.u_trim[i] - feedback;
        }
        Ok(())
    }
    fn reset(&mut self) {
        self.integral.reset();
        self.altitude_integral.reset();
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::UnitQuaternion;

    use super::*;

    fn trim(axis: Vector3<f64>) -> RelaxedHoverTrim {
        let helper = if axis.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = helper.cross(&axis).normalize();
        let e2 = axis.cross(&e1);
        RelaxedHoverTrim {
            axis: axis.into(),
            e1: e1.into(),
            e2: e2.into(),
            body_rate_rad_s: (axis * 15.0).into(),
            circle_offset_m: [0.0; 3],
            circle_velocity_m_s: [0.0; 3],
            gravity_m_s2: 9.81,
        }
    }

    #[test]
    fn on_the_solution_the_reduced_state_is_zero_whatever_the_yaw() {
        let axis = Vector3::new(0.1, -0.2, -0.97).normalize();
        let c = RelaxedHoverFeedback::new(
            &trim(axis),
            &[1.0; 4],
            DMatrix::zeros(4, 7),
            [0.0; 3],
            Default::default(),
        )
        .unwrap();
        // An attitude whose inverse maps world up (NED -z) to the axis, then any turn about it.
        let align = UnitQuaternion::rotation_between(&axis, &Vector3::new(0.0, 0.0, -1.0)).unwrap();
        for yaw in [0.0, 1.0, 2.5] {
            let attitude =
                UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), yaw) * align;
            let state = RigidBodyState {
                attitude,
                omega_rad_s: axis * 15.0,
                ..RigidBodyState::at_rest()
            };
            let x = c.reduced_state(&state);
            assert!(x.iter().all(|v| v.abs() < 1e-12), "{x:?}");
        }
    }

    #[test]
    fn tilt_and_altitude_errors_drive_the_commands() {
        let axis = Vector3::new(0.0, 0.0, -1.0);
        let mut gain = DMatrix::zeros(1, 7);
        gain[(0, 5)] = 2.0; // altitude
        let mut c = RelaxedHoverFeedback::new(
            &trim(axis),
            &[3.0],
            gain,
            [0.0, 0.0, -10.0],
            Default::default(),
        )
        .unwrap();
        // 0.5 m below the set point (NED z = -9.5): z error -0.5 up, u = 3 - 2 (-0.5) = 4.
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, -9.5),
            omega_rad_s: axis * 15.0,
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        c.command(0.0, &state, &mut out).unwrap();
        assert!((out[0] - 4.0).abs() < 1e-12);
        // 1 m east of the set point: the wanted up tilts west (towards -east) by atan(k_p / g).
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 1.0, -10.0),
            ..state
        };
        let x = c.reduced_state(&state);
        let tilt = (x[0] * x[0] + x[1] * x[1]).sqrt();
        assert!(
            (tilt - (0.25f64 / 9.81).atan()).abs() < 1e-3 * tilt,
            "{x:?}"
        );
    }

    /// The integrals are the rule they had before they moved onto [`PositionIntegral`] (that
    /// code transcribed here), bit for bit, through irregular, repeated and backward times, the
    /// horizontal one frozen at the tilt limit and scaled back to its length limit, and the
    /// altitude one clamped: flights are unchanged.
    #[test]
    fn the_integrals_are_the_former_rule_bit_for_bit() {
        let axis = Vector3::new(0.0, 0.0, -1.0);
        let outer = RelaxedHoverOuterLoop {
            integral_gain_s3: 1.0,
            altitude_integral_gain_s: 2.0,
            ..Default::default()
        };
        let mut c =
            RelaxedHoverFeedback::new(&trim(axis), &[3.0], DMatrix::zeros(1, 7), [0.0; 3], outer)
                .unwrap();
        let (mut xy, mut z, mut last) = (nalgebra::Vector2::zeros(), 0.0f64, None::<f64>);
        let (mut frozen, mut scaled, mut clamped) = (0, 0, 0);
        let mut t = 0.0;
        for k in 0..4000 {
            t += [0.0025, 0.0, 0.004, -0.001, 0.0025][k % 5];
            let w = k as f64;
            let north = 10.0 * (w * 0.003).sin();
            // Every other 500 steps the velocity cancels the position's share of the wanted
            // acceleration: the integral then winds up to its length limit unsaturated.
            let cancel = -c.outer.position_gain_s2 / c.outer.velocity_gain_s * north;
            let state = RigidBodyState {
                position_m: Vector3::new(north, 0.8 * (w * 0.021).cos(), 1.0 + (w * 0.004).sin()),
                velocity_m_s: Vector3::new(
                    if (k / 500) % 2 == 0 {
                        cancel
                    } else {
                        (w * 0.03).cos()
                    },
                    0.0,
                    0.1,
                ),
                omega_rad_s: axis * 15.0,
                ..RigidBodyState::at_rest()
            };
            // The former rule, on the state before the step (the same integrals so far).
            let previous = last.replace(t);
            let (centre, velocity) = c.centre_error(&state);
            if let Some(previous) = previous {
                let dt = t - previous;
                if !(dt.is_nan() || dt <= 0.0) {
                    let limit = ALTITUDE_INTEGRAL_LIMIT_M / c.outer.altitude_integral_gain_s;
                    let before = z - dt * centre.z;
                    z = before.clamp(-limit, limit);
                    clamped += usize::from(z != before);
                    if c.wanted_accel(&centre, &velocity).1 {
                        frozen += 1;
                    } else {
                        xy += dt * centre.xy();
                        let limit =
                            c.gravity * c.outer.max_tilt_rad.tan() / c.outer.integral_gain_s3;
                        if xy.norm() > limit {
                            xy *= limit / xy.norm();
                            scaled += 1;
                        }
                    }
                }
            }
            c.integrate(t, &state);
            let now = c.integral.sum_m_s();
            assert_eq!(
                [now[0].to_bits(), now[1].to_bits()],
                [xy.x.to_bits(), xy.y.to_bits()],
                "step {k}"
            );
            let now = c.altitude_integral.sum_m_s()[0];
            assert_eq!(now.to_bits(), z.to_bits(), "step {k}");
        }
        assert!(
            frozen > 0 && scaled > 0 && clamped > 0,
            "{frozen} {scaled} {clamped}"
        );
    }

    #[test]
    fn the_integral_of_a_constant_error_tilts_further_and_winds_no_further_than_the_limit() {
        let axis = Vector3::new(0.0, 0.0, -1.0);
        let outer = RelaxedHoverOuterLoop {
            integral_gain_s3: 0.1,
            ..Default::default()
        };
        let mut c =
            RelaxedHoverFeedback::new(&trim(axis), &[3.0], DMatrix::zeros(1, 7), [0.0; 3], outer)
                .unwrap();
        // 0.1 m east, at rest: k_p e = 0.025 m/s^2, below the tilt limit (9.81 tan 0.2).
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.1, 0.0),
            omega_rad_s: axis * 15.0,
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for k in 0..=400 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        // After 1 s: integral 0.1 m s; accel -(0.25 x 0.1 + 0.1 x 0.1) = -0.035 m/s^2 east.
        let tilt = |x: [f64; 7]| (x[0] * x[0] + x[1] * x[1]).sqrt();
        // The reduced state is the chord's tangent part: the sine of the tilt.
        let want = 0.035 / 0.035f64.hypot(9.81);
        assert!(
            (tilt(c.reduced_state(&state)) - want).abs() < 1e-9,
            "{}",
            tilt(c.reduced_state(&state))
        );
        // Far off (saturated): the integral is frozen.
        let far = RigidBodyState {
            position_m: Vector3::new(0.0, 100.0, 0.0),
            ..state
        };
        let before = c.integral.sum_m_s();
        c.command(1.0025, &far, &mut out).unwrap();
        assert_eq!(c.integral.sum_m_s(), before);
        // reset: no integral, and the first call after it only sets the time base.
        c.reset();
        c.command(5.0, &state, &mut out).unwrap();
        assert_eq!(c.integral.sum_m_s(), [0.0, 0.0]);
    }

    #[test]
    fn the_altitude_integral_adds_to_the_altitude_state_and_winds_no_further_than_its_limit() {
        let axis = Vector3::new(0.0, 0.0, -1.0);
        let outer = RelaxedHoverOuterLoop {
            altitude_integral_gain_s: 0.5,
            ..Default::default()
        };
        let mut c =
            RelaxedHoverFeedback::new(&trim(axis), &[3.0], DMatrix::zeros(1, 7), [0.0; 3], outer)
                .unwrap();
        // 0.2 m below the set point (NED z = +0.2): altitude error z = -0.2 m.
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, 0.2),
            omega_rad_s: axis * 15.0,
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for k in 0..=400 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        // After 1 s: integral -0.2 m s, state z = -0.2 + 0.5 x -0.2 = -0.3 m.
        assert!((c.reduced_state(&state)[5] + 0.3).abs() < 1e-12);
        // Long below: the integral's share stops at the limit.
        for k in 401..=40_000 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        let share = c.reduced_state(&state)[5] + 0.2;
        assert!((share + ALTITUDE_INTEGRAL_LIMIT_M).abs() < 1e-12, "{share}");
        c.reset();
        c.command(200.0, &state, &mut out).unwrap();
        assert!((c.reduced_state(&state)[5] + 0.2).abs() < 1e-15);
    }

    #[test]
    fn bad_input_is_named() {
        let axis = Vector3::new(0.0, 0.0, -1.0);
        let err = RelaxedHoverFeedback::new(
            &trim(axis),
            &[1.0; 4],
            DMatrix::zeros(4, 6),
            [0.0; 3],
            Default::default(),
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("gain"), "{err}");
        let mut bad = trim(axis);
        bad.e1 = [1.0, 1.0, 0.0];
        let err = RelaxedHoverFeedback::new(
            &bad,
            &[1.0; 4],
            DMatrix::zeros(4, 7),
            [0.0; 3],
            Default::default(),
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("axis"), "{err}");
        let outer = RelaxedHoverOuterLoop {
            max_tilt_rad: 2.0,
            ..Default::default()
        };
        let err = RelaxedHoverFeedback::new(
            &trim(axis),
            &[1.0; 4],
            DMatrix::zeros(4, 7),
            [0.0; 3],
            outer,
        )
        .unwrap_err();
        assert!(
            err.to_string().starts_with("outer_loop.max_tilt_rad"),
            "{err}"
        );
    }
}
