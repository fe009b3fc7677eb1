//! Linear laws on the state vector `x` of [`crate::state::state_vector`]: an open-loop schedule,
//! state feedback `u = u_trim - K (x - x_trim)` and a discrete LTI controller.

use nalgebra::{DMatrix, DVector};

use super::{require_finite_matrix, require_shaped_finite, require_state_gain, Controller};
use crate::error::{require_all_finite, Result, RfError};
use crate::state::{state_error, state_vector, RigidBodyState, STATE_DIM};

/// A piecewise-constant schedule: row k of `commands` holds from `times_s[k]` until the next time
/// (the first row also before `times_s[0]`).
#[derive(Debug, Clone)]
pub struct OpenLoop {
    times_s: Vec<f64>,
    commands: DMatrix<f64>,
}

impl OpenLoop {
    /// `commands` is rows x command_count; `times_s` strictly increasing, one per row.
    pub fn new(times_s: Vec<f64>, commands: DMatrix<f64>) -> Result<Self> {
        if times_s.is_empty() || times_s.len() != commands.nrows() {
            return Err(RfError::shape(
                "times",
                format!(
                    "one time per command row ({} rows), at least one",
                    commands.nrows()
                ),
                times_s.len().to_string(),
            ));
        }
        require_all_finite("times", &times_s)?;
        require_finite_matrix("commands", &commands)?;
        if let Some(k) = times_s.windows(2).position(|w| w[1] <= w[0]) {
            return Err(RfError::invalid(
                format!("times[{}]", k + 1),
                "times must be strictly increasing",
            ));
        }
        Ok(OpenLoop { times_s, commands })
    }
}

impl Controller for OpenLoop {
    fn command_count(&self) -> usize {
        self.commands.ncols()
    }
    fn command(&mut self, t_s: f64, _measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        let row = self
            .times_s
            .partition_point(|&s| s <= t_s)
            .saturating_sub(1);
        for (c, o) in out.iter_mut().enumerate() {
            *o = self.commands[(row, c)];
        }
        Ok(())
    }
}

/// `u = u_trim - K (x - x_trim)` (e.g. K from `control.lqr` on a linearisation about the trim).
#[derive(Debug, Clone)]
pub struct LinearFeedback {
    x_trim: [f64; STATE_DIM],
    u_trim: DVector<f64>,
    gain: DMatrix<f64>,
}

impl LinearFeedback {
    /// `gain` is command_count x 12.
    pub fn new(x_trim: &[f64], u_trim: &[f64], gain: DMatrix<f64>) -> Result<Self> {
        let x_trim = trim_state(x_trim)?;
        require_state_gain(u_trim, &gain)?;
        Ok(LinearFeedback {
            x_trim,
            u_trim: DVector::from_column_slice(u_trim),
            gain,
        })
    }

    /// The trim's position (world NED), m: the set point the feedback holds.
    pub fn trim_position_m(&self) -> [f64; 3] {
        [self.x_trim[0], self.x_trim[1], self.x_trim[2]]
    }
}

fn trim_state(x_trim: &[f64]) -> Result<[f64; STATE_DIM]> {
    require_all_finite("x_trim", x_trim)?;
    x_trim.try_into().map_err(|_| {
        RfError::shape(
            "x_trim",
            format!("{STATE_DIM} entries"),
            x_trim.len().to_string(),
        )
    })
}

impl Controller for LinearFeedback {
    fn command_count(&self) -> usize {
        self.u_trim.len()
    }
    fn command(&mut self, _t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        let e = state_error(&state_vector(measured), &self.x_trim);
        for (i, o) in out.iter_mut().enumerate() {
            let feedback: f64 = (0..STATE_DIM).map(|j| self.gain[(i, j)] * e[j]).sum();
            *o = self.u_trim[i] - feedback;
        }
        Ok(())
    }
}

/// A discrete-time LTI controller at the control rate, driven by the state error
/// `e = x - x_trim`: `xi+ = A xi + B e`, `u = u_trim + C xi + D e`. Continuous designs are
/// discretised in Python (zero-order hold at the control period) before they get here.
#[derive(Debug, Clone)]
pub struct Lti {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    x_trim: [f64; STATE_DIM],
    u_trim: DVector<f64>,
    xi: DVector<f64>,
}

impl Lti {
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        x_trim: &[f64],
        u_trim: &[f64],
    ) -> Result<Self> {
        let x_trim = trim_state(x_trim)?;
        require_all_finite("u_trim", u_trim)?;
        let (n, nu) = (a.nrows(), u_trim.len());
        require_shaped_finite([
            ("A_K", &a, n, n),
            ("B_K", &b, n, STATE_DIM),
            ("C_K", &c, nu, n),
            ("D_K", &d, nu, STATE_DIM),
        ])?;
        Ok(Lti {
            xi: DVector::zeros(n),
            a,
            b,
            c,
            d,
            x_trim,
            u_trim: DVector::from_column_slice(u_trim),
        })
    }
}

impl Controller for Lti {
    fn command_count(&self) -> usize {
        self.u_trim.len()
    }
    fn command(&mut self, _t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        let e = DVector::from_column_slice(&state_error(&state_vector(measured), &self.x_trim));
        let u = &self.u_trim + &self.c * &self.xi + &self.d * &e;
        out.copy_from_slice(u.as_slice());
        self.xi = &self.a * &self.xi + &self.b * &e;
        Ok(())
    }
    fn reset(&mut self) {
        self.xi.fill(0.0);
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{UnitQuaternion, Vector3};

    use super::*;

    #[test]
    fn open_loop_holds_each_row() {
        let mut c = OpenLoop::new(
            vec![0.0, 1.0],
            DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 3.0, 4.0]),
        )
        .unwrap();
        let s = RigidBodyState::at_rest();
        let mut out = [0.0; 2];
        for (t, expected) in [
            (-1.0, [1.0, 2.0]),
            (0.5, [1.0, 2.0]),
            (1.0, [3.0, 4.0]),
            (9.0, [3.0, 4.0]),
        ] {
            c.command(t, &s, &mut out).unwrap();
            assert_eq!(out, expected, "t = {t}");
        }
        assert!(OpenLoop::new(vec![1.0, 1.0], DMatrix::zeros(2, 1)).is_err());
    }

    #[test]
    fn linear_feedback_and_its_lti_form_agree() {
        let gain = DMatrix::from_fn(4, STATE_DIM, |i, j| {
            0.1 * (i as f64 + 1.0) - 0.03 * j as f64
        });
        let x_trim = [0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0];
        let u_trim = [2.0; 4];
        let mut lqr = LinearFeedback::new(&x_trim, &u_trim, gain.clone()).unwrap();
        let mut lti = Lti::new(
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, STATE_DIM),
            DMatrix::zeros(4, 0),
            -gain,
            &x_trim,
            &u_trim,
        )
        .unwrap();
        let state = RigidBodyState {
            position_m: Vector3::new(0.1, -0.2, -0.8),
            velocity_m_s: Vector3::new(0.3, 0.0, 0.1),
            attitude: UnitQuaternion::from_euler_angles(0.05, -0.02, 0.3),
            omega_rad_s: Vector3::new(0.1, 0.2, -0.3),
        };
        let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
        lqr.command(0.0, &state, &mut a).unwrap();
        lti.command(0.0, &state, &mut b).unwrap();
        for i in 0..4 {
            assert!((a[i] - b[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn lti_state_evolves_and_resets() {
        // An integrator of the x-position error: xi+ = xi + e_x, u = xi.
        let mut b = DMatrix::zeros(1, STATE_DIM);
        b[(0, 0)] = 1.0;
        let mut lti = Lti::new(
            DMatrix::identity(1, 1),
            b,
            DMatrix::identity(1, 1),
            DMatrix::zeros(1, STATE_DIM),
            &[0.0; STATE_DIM],
            &[0.0],
        )
        .unwrap();
        let state = RigidBodyState {
            position_m: Vector3::new(2.0, 0.0, 0.0),
            ..RigidBodyState::at_rest()
        };
        let mut out = [0.0];
        for expected in [0.0, 2.0, 4.0] {
            lti.command(0.0, &state, &mut out).unwrap();
            assert_eq!(out[0], expected);
        }
        lti.reset();
        lti.command(0.0, &state, &mut out).unwrap();
        assert_eq!(out[0], 0.0);
        let err = Lti::new(
            DMatrix::identity(2, 2),
            DMatrix::zeros(1, STATE_DIM),
            DMatrix::zeros(1, 2),
            DMatrix::zeros(1, STATE_DIM),
            &[0.0; STATE_DIM],
            &[0.0],
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("B_K: expected 2 x 12"), "{err}");
    }
}
