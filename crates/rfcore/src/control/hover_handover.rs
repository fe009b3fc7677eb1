//! Integral action in the healthy hover and a bumpless hand-over to the relaxed hover LQR.
//!
//! [`IntegralHover`]: a hover state feedback (an LQR, [`LinearFeedback`]) with integral action on
//! the position error, `u = u_lqr - K_I \int (p - p_set) dt` (`K_I` designed in Python with the
//! feedback, an LQR on the model augmented by the integral: LQI). Without it a vehicle heavier or
//! weaker than its design sits below its set point in proportion to the weight its trim does not
//! carry (the Lanzon quadrotor 14 % heavier with 10 % weaker rotors: 5-6 m after 4 s), and a
//! constant wind leaves it off station. Anti-windup: each axis's integral kept within its limit.
//!
//! [`RelaxedHoverHandover`]: [`IntegralHover`] until a known failure time, the relaxed hover LQR
//! from the first control step at or after it, whose integrals are started where the healthy
//! loop left its own (bumpless): the altitude integral at `altitude_ratio` times the healthy
//! altitude integral (the ratio of the two loops' vertical accelerations per unit of integral,
//! computed in Python from the two designs: the same weight the trims do not carry), the
//! horizontal integral at `horizontal_ratio` times the healthy horizontal integral (2 x 2, from
//! Python: the relaxed hover's integral giving the steady acceleration the healthy loop's integral
//! holds against a constant horizontal force: the wind it learnt). Without it the relaxed hover
//! starts from zero integrals and winds them up while climbing back, overshooting the set point.
//! Only what the integrals learnt is carried over, not the vehicle's tilt: at a failure in
//! forward flight the tilt is the healthy loop braking (1.2-2.6 m/s^2 on the Lanzon quadrotor at
//! 2 m/s), and started from it the relaxed hover kept braking after it stopped and ended 3-3.7 m
//! off station (issue 30, 14 runs of the deciding campaign).

use nalgebra::{DMatrix, Matrix2, Vector3};

use super::integral::PositionIntegral;
use super::linear::LinearFeedback;
use super::relaxed_hover::RelaxedHoverFeedback;
use super::switch::{FailureTimeSwitch, HandOver};
use super::{require_finite_matrix, Controller};
use crate::error::{require_all_finite, Result, RfError};
use crate::state::RigidBodyState;

/// A hover LQR with integral action on the position error (module docs).
#[derive(Debug, Clone)]
pub struct IntegralHover {
    feedback: LinearFeedback,
    /// `K_I`: commands x 3 (north, east, down), command units per m s.
    integral_gain: DMatrix<f64>,
    setpoint_m: Vector3<f64>,
    /// Largest `|\int e dt|` per axis, m s.
    limit_m_s: [f64; 3],
    integral: PositionIntegral<3>,
}

impl IntegralHover {
    /// `integral_gain`: commands x 3; `setpoint_m`: the feedback's trim position (world NED);
    /// `limit_m_s`: each axis's integral limit (finite, > 0).
    pub fn new(
        feedback: LinearFeedback,
        integral_gain: DMatrix<f64>,
        setpoint_m: [f64; 3],
        limit_m_s: [f64; 3],
    ) -> Result<Self> {
        require_finite_matrix("integral_gain", &integral_gain)?;
        require_all_finite("setpoint_m", &setpoint_m)?;
        if integral_gain.shape() != (feedback.command_count(), 3) {
            return Err(RfError::shape(
                "integral_gain",
                format!(
                    "{} x 3 (commands x north, east, down)",
                    feedback.command_count()
                ),
                format!("{} x {}", integral_gain.nrows(), integral_gain.ncols()),
            ));
        }
        if let Some(v) = limit_m_s.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(RfError::invalid(
                "integral_limit_m_s",
                format!("each must be finite and > 0, got {v}"),
            ));
        }
        Ok(IntegralHover {
            feedback,
            integral_gain,
            setpoint_m: Vector3::from(setpoint_m),
            limit_m_s,
            integral: PositionIntegral::default(),
        })
    }

    /// `\int (p - p_set) dt` so far (world NED), m s.
    pub fn integral_m_s(&self) -> Vector3<f64> {
        Vector3::from(self.integral.sum_m_s())
    }

    /// Advances the integral to `t_s` (the shared rule of `control::integral`).
    fn integrate(&mut self, t_s: f64, measured: &RigidBodyState) {
        let error = measured.position_m - self.setpoint_m;
        self.integral
            .integrate_clamped(t_s, error.into(), self.limit_m_s);
    }
}

impl Controller for IntegralHover {
    fn command_count(&self) -> usize {
        self.feedback.command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.integrate(t_s, measured);
        self.feedback.command(t_s, measured, out)?;
        let integral_m_s = self.integral.sum_m_s();
        for (i, o) in out.iter_mut().enumerate() {
            *o -= (0..3)
                .map(|k| self.integral_gain[(i, k)] * integral_m_s[k])
                .sum::<f64>();
        }
        Ok(())
    }
    fn reset(&mut self) {
        self.integral.reset();
    }
}

/// The hand-over at the failure: the relaxed hover's integrals started from the healthy loop's
/// (module docs).
#[derive(Debug, Clone, Copy)]
pub struct IntegralHandOver {
    /// The relaxed hover's altitude integral (m s, up) per healthy altitude integral (m s, down).
    altitude_ratio: f64,
    /// The relaxed hover's horizontal integral (m s, north and east) per healthy one (m s).
    horizontal_ratio: Matrix2<f64>,
}

impl HandOver<IntegralHover, RelaxedHoverFeedback> for IntegralHandOver {
    fn hand_over(&mut self, before: &IntegralHover, after: &mut RelaxedHoverFeedback) {
        let integral = before.integral_m_s();
        after.start_integrals(
            self.altitude_ratio * integral.z,
            self.horizontal_ratio * integral.xy(),
        );
    }
}

/// [`IntegralHover`] until `failure_time_s`, then the relaxed hover LQR with its integrals started
/// from the healthy loop's: the failure-time switch with [`IntegralHandOver`].
pub type RelaxedHoverHandover =
    FailureTimeSwitch<IntegralHover, RelaxedHoverFeedback, IntegralHandOver>;

/// The [`RelaxedHoverHandover`] (the switch's own checks: `failure_time_s` finite and >= 0, the
/// same command count; `altitude_ratio` and `horizontal_ratio` (rows north, east) finite, named
/// `handover_altitude_ratio` / `handover_horizontal_ratio`, the keywords that give them).
pub fn relaxed_hover_handover(
    before: IntegralHover,
    after: RelaxedHoverFeedback,
    failure_time_s: f64,
    altitude_ratio: f64,
    horizontal_ratio: [[f64; 2]; 2],
) -> Result<RelaxedHoverHandover> {
    if !altitude_ratio.is_finite() {
        return Err(RfError::invalid(
            "handover_altitude_ratio",
            format!("must be finite, got {altitude_ratio}"),
        ));
    }
    require_all_finite("handover_horizontal_ratio", horizontal_ratio.as_flattened())?;
    let [[nn, ne], [en, ee]] = horizontal_ratio;
    FailureTimeSwitch::with_hand_over(
        before,
        after,
        failure_time_s,
        IntegralHandOver {
            altitude_ratio,
            horizontal_ratio: Matrix2::new(nn, ne, en, ee),
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hover(gain_z: f64) -> IntegralHover {
        let feedback = LinearFeedback::new(&[0.0; 12], &[1.0], DMatrix::zeros(1, 12)).unwrap();
        let gain = DMatrix::from_row_slice(1, 3, &[0.0, 0.0, gain_z]);
        IntegralHover::new(feedback, gain, [0.0; 3], [1.0, 1.0, 2.0]).unwrap()
    }

    #[test]
    fn a_constant_error_integrates_into_the_command_up_to_the_limit() {
        let mut c = hover(-0.5);
        // 0.4 m below the set point (NED z = +0.4) for 1 s: integral 0.4 m s, u = 1 + 0.5 x 0.4.
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, 0.4),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for k in 0..=400 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        assert!((out[0] - 1.2).abs() < 1e-12, "{}", out[0]);
        for k in 401..=4000 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        assert!((c.integral_m_s().z - 2.0).abs() < 1e-12);
        c.reset();
        c.command(20.0, &state, &mut out).unwrap();
        assert_eq!(out[0], 1.0);
    }

    #[test]
    fn the_relaxed_hover_starts_with_the_healthy_integral_times_the_ratio() {
        let after = relaxed_with(crate::control::relaxed_hover::RelaxedHoverOuterLoop {
            altitude_integral_gain_s: 0.5,
            integral_gain_s3: 0.3,
            ..Default::default()
        });
        let mut c = relaxed_hover_handover(hover(-0.5), after, 1.0, -0.25, [[0.0; 2]; 2]).unwrap();
        // 0.4 m below for 1 s before the failure: healthy integral 0.4 m s (down).
        let state = RigidBodyState {
            position_m: Vector3::new(0.0, 0.0, 0.4),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for k in 0..400 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        assert!((c.before().integral_m_s().z - 0.399).abs() < 1e-12);
        // At the failure, level: the relaxed altitude integral is -0.25 x 0.399 m s (up), so
        // u = 3 - 2 (z + 0.5 I) = 3 - 2 (-0.4 - 0.5 x 0.0998) and no horizontal integral.
        c.command(1.0, &state, &mut out).unwrap();
        let want = 3.0 - 2.0 * (-0.4 + 0.5 * -0.25 * 0.399);
        assert!((out[0] - want).abs() < 1e-12, "{} {want}", out[0]);
        c.reset();
        c.command(1.0, &state, &mut out).unwrap();
        assert!((out[0] - (3.0 - 2.0 * -0.4)).abs() < 1e-12, "{}", out[0]);
    }

    /// A relaxed hover (spin about body -z, up at rest) with an altitude gain only, its outer loop
    /// the default with a horizontal integral.
    fn relaxed() -> RelaxedHoverFeedback {
        relaxed_with(crate::control::relaxed_hover::RelaxedHoverOuterLoop {
            integral_gain_s3: 0.3,
            ..Default::default()
        })
    }

    /// [`relaxed`] with the outer loop `outer`.
    fn relaxed_with(
        outer: crate::control::relaxed_hover::RelaxedHoverOuterLoop,
    ) -> RelaxedHoverFeedback {
        use crate::control::relaxed_hover::RelaxedHoverTrim;
        let trim = RelaxedHoverTrim {
            axis: [0.0, 0.0, -1.0],
            e1: [0.0, 1.0, 0.0],
            e2: [1.0, 0.0, 0.0],
            body_rate_rad_s: [0.0, 0.0, -15.0],
            circle_offset_m: [0.0; 3],
            circle_velocity_m_s: [0.0; 3],
            gravity_m_s2: 9.81,
        };
        let mut gain = DMatrix::zeros(1, 7);
        gain[(0, 5)] = 2.0;
        RelaxedHoverFeedback::new(&trim, &[3.0], gain, [0.0; 3], outer).unwrap()
    }

    #[test]
    fn the_horizontal_integral_starts_at_the_ratio_times_the_healthy_one_and_pushes_back() {
        // 0.5 m north and 0.2 m east of the set point for 1 s before the failure, level: healthy
        // integral (0.49875, 0.1995) m s (399 steps of 2.5 ms after the first sets the time base).
        let ratio = [[1.2, 0.1], [-0.05, 1.3]];
        let mut c = relaxed_hover_handover(hover(0.0), relaxed(), 1.0, 0.0, ratio).unwrap();
        let state = RigidBodyState {
            position_m: Vector3::new(0.5, 0.2, 0.0),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for k in 0..=400 {
            c.command(k as f64 * 0.0025, &state, &mut out).unwrap();
        }
        let healthy = c.before().integral_m_s();
        assert!((healthy.x - 0.49875).abs() < 1e-12 && (healthy.y - 0.1995).abs() < 1e-12);
        let started = c.after().horizontal_integral_m_s();
        let want = (1.2 * 0.49875 + 0.1 * 0.1995, -0.05 * 0.49875 + 1.3 * 0.1995);
        assert!((started.x - want.0).abs() < 1e-12, "{started}");
        assert!((started.y - want.1).abs() < 1e-12, "{started}");
        // Its sign: north and east of the set point with positive integrals, the relaxed hover
        // wants to accelerate south and west, the integral's share adding to the position's:
        // a = -k_p e - k_i I (k_p 0.25 /s^2, k_i 0.3 /s^3), seen from the body as the up axis
        // tilted by (a_e, a_n) / |(a_n, a_e, -g)| along (e1, e2).
        let (a_n, a_e) = (-0.25 * 0.5 - 0.3 * want.0, -0.25 * 0.2 - 0.3 * want.1);
        let norm = (a_n * a_n + a_e * a_e + 9.81 * 9.81).sqrt();
        let x = c.after().reduced_state(&state);
        assert!(a_n < -0.25 * 0.5 && a_e < -0.25 * 0.2);
        assert!((x[0] - a_e / norm).abs() < 1e-12, "{x:?}");
        assert!((x[1] - a_n / norm).abs() < 1e-12, "{x:?}");
    }

    #[test]
    fn a_braking_tilt_at_the_hand_over_does_not_enter_the_horizontal_integral() {
        // A failure at the start of forward flight: 2 m/s north, pitched up 0.2 rad by the healthy
        // loop braking, its integrals still 0. The relaxed hover's integral must start at 0, not at
        // the braking acceleration (issue 30: it kept braking once stopped, 3-3.7 m off station).
        let mut c =
            relaxed_hover_handover(hover(0.0), relaxed(), 0.0, 0.0, [[1.2, 0.0], [0.0, 1.2]])
                .unwrap();
        let state = RigidBodyState {
            velocity_m_s: Vector3::new(2.0, 0.0, 0.0),
            attitude: nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.2, 0.0),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        c.command(0.0, &state, &mut out).unwrap();
        assert_eq!(
            c.after().horizontal_integral_m_s(),
            nalgebra::Vector2::zeros()
        );
    }

    #[test]
    fn bad_input_is_named() {
        let feedback = LinearFeedback::new(&[0.0; 12], &[1.0], DMatrix::zeros(1, 12)).unwrap();
        let err = IntegralHover::new(feedback.clone(), DMatrix::zeros(2, 3), [0.0; 3], [1.0; 3])
            .unwrap_err();
        assert!(err.to_string().starts_with("integral_gain"), "{err}");
        let err = IntegralHover::new(feedback, DMatrix::zeros(1, 3), [0.0; 3], [1.0, 0.0, 1.0])
            .unwrap_err();
        assert!(err.to_string().starts_with("integral_limit_m_s"), "{err}");
        let nan = [[f64::NAN, 0.0], [0.0, 1.0]];
        let err = relaxed_hover_handover(hover(0.0), relaxed(), 1.0, 0.0, nan).unwrap_err();
        assert!(err.to_string().starts_with("handover_horizontal_ratio"), "{err}");
        let err =
            relaxed_hover_handover(hover(0.0), relaxed(), 1.0, f64::NAN, [[0.0; 2]; 2]).unwrap_err();
        assert!(err.to_string().starts_with("handover_altitude_ratio"), "{err}");
    }

    /// The integral is the rule it had before it moved onto [`PositionIntegral`] (that code
    /// transcribed here), bit for bit, through irregular, repeated and backward times, a
    /// non-finite position skipped and each axis clamped at its limit, and so is the command it
    /// makes: flights are unchanged.
    #[test]
    fn the_integral_is_the_former_rule_bit_for_bit() {
        let feedback = LinearFeedback::new(&[0.0; 12], &[1.0], DMatrix::zeros(1, 12)).unwrap();
        let gain = DMatrix::from_row_slice(1, 3, &[0.3, -0.7, -0.5]);
        let setpoint = Vector3::new(0.5, -0.2, -1.0);
        let limit = Vector3::new(0.4, 0.1, 0.5);
        let mut c = IntegralHover::new(feedback, gain.clone(), setpoint.into(), limit.into())
            .unwrap();
        let (mut integral, mut integrated_to_s) = (Vector3::<f64>::zeros(), None::<f64>);
        let mut clamped = [0usize; 3];
        let (mut t, mut out) = (0.0, [0.0]);
        for k in 0..3000 {
            t += [0.0025, 0.0, 0.004, -0.001, 0.0025, 0.0031][k % 6];
            let w = k as f64;
            let mut position = Vector3::new(
                0.5 + 2.0 * (w * 0.004).sin(),
                -0.2 + 0.9 * (w * 0.011).cos(),
                -1.0 + 1.5 * (w * 0.002).sin(),
            );
            if k % 97 == 0 {
                position.y = f64::NAN;
            }
            let state = RigidBodyState {
                position_m: position,
                ..RigidBodyState::at_rest()
            };
            // The former rule.
            if let Some(previous) = integrated_to_s.replace(t) {
                let dt = t - previous;
                let error = position - setpoint;
                if !(dt.is_nan() || dt <= 0.0 || !error.iter().all(|v| v.is_finite())) {
                    integral += dt * error;
                    for a in 0..3 {
                        let before = integral[a];
                        integral[a] = before.clamp(-limit[a], limit[a]);
                        clamped[a] += usize::from(integral[a] != before);
                    }
                }
            }
            c.command(t, &state, &mut out).unwrap();
            let now = c.integral_m_s();
            for a in 0..3 {
                assert_eq!(now[a].to_bits(), integral[a].to_bits(), "step {k} axis {a}");
            }
            if k % 97 != 0 {
                // (The zero feedback of a NaN position is NaN: only the integral is compared.)
                let former = 1.0 - (0..3).map(|a| gain[(0, a)] * integral[a]).sum::<f64>();
                assert_eq!(out[0].to_bits(), former.to_bits(), "step {k}");
            }
        }
        assert!(clamped.iter().all(|&n| n > 0), "every axis reached its limit: {clamped:?}");
        c.reset();
        assert_eq!(c.integral_m_s(), Vector3::zeros());
    }
}
