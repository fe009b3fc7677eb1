//! Controllers the simulator runs at its control rate (zero-order hold between updates).
//!
//! Design in Python, run in Rust: gains and controller matrices are computed in Python
//! (python-control, H-infinity synthesis) and handed to these built-ins, which run without the GIL.
//!
//! The full state vector used by [`LinearFeedback`] and [`DiscreteLti`] is
//! `x = [p (3, world NED, m), v (3, world, m/s), roll, pitch, yaw (rad, Z-Y-X), p, q, r (rad/s)]`;
//! yaw errors are wrapped to (-pi, pi].

use nalgebra::{DMatrix, DVector, UnitQuaternion, Vector3};

use crate::active_set::{ActiveSet, ActiveSetSolver};
use crate::actuator::{Actuators, RotorOutput};
use crate::error::{require_all_finite, Result, RfError};
use crate::rigid_body::RigidBodyState;
use crate::vehicle::Vehicle;

/// Length of the full state vector of [`state_vector`].
pub const STATE_DIM: usize = 12;

/// `[p, v, roll, pitch, yaw, omega]` of a state (module docs).
pub fn state_vector(state: &RigidBodyState) -> [f64; STATE_DIM] {
    let [roll, pitch, yaw] = state.euler_rad();
    let (p, v, w) = (state.position_m, state.velocity_m_s, state.omega_rad_s);
    [
        p.x, p.y, p.z, v.x, v.y, v.z, roll, pitch, yaw, w.x, w.y, w.z,
    ]
}

/// The state whose [`state_vector`] is `x` (attitude from the Z-Y-X Euler angles).
pub fn state_from_vector(x: &[f64; STATE_DIM]) -> RigidBodyState {
    RigidBodyState {
        position_m: Vector3::new(x[0], x[1], x[2]),
        velocity_m_s: Vector3::new(x[3], x[4], x[5]),
        attitude: UnitQuaternion::from_euler_angles(x[6], x[7], x[8]),
        omega_rad_s: Vector3::new(x[9], x[10], x[11]),
    }
}

/// Time derivative of the 12-element state vector (Euler-angle kinematics) for the rotor
/// outputs the actuators give right now: the model that linearisation for control design uses.
pub fn state_vector_derivative(
    vehicle: &Vehicle,
    actuators: &Actuators,
    health: &[f64],
    x: &[f64; STATE_DIM],
    wind_m_s: &Vector3<f64>,
) -> [f64; STATE_DIM] {
    let state = state_from_vector(x);
    let outputs: Vec<RotorOutput> = (0..vehicle.rotor_count())
        .map(|i| actuators.output(i, health[i]))
        .collect();
    let d = vehicle
        .body()
        .derivative(&state, &vehicle.wrench(&state, &outputs, wind_m_s));
    let (roll, pitch) = (x[6], x[7]);
    let (p, q, r) = (x[9], x[10], x[11]);
    let (sr, cr, tp, cp) = (roll.sin(), roll.cos(), pitch.tan(), pitch.cos());
    [
        d.position.x,
        d.position.y,
        d.position.z,
        d.velocity.x,
        d.velocity.y,
        d.velocity.z,
        p + (q * sr + r * cr) * tp,
        q * cr - r * sr,
        (q * sr + r * cr) / cp,
        d.omega.x,
        d.omega.y,
        d.omega.z,
    ]
}

/// Rejects a non-finite matrix entry, naming it `field[row, col]`.
fn require_finite_matrix(field: &str, m: &DMatrix<f64>) -> Result<()> {
    match m.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(RfError::invalid(
            format!("{field}[{}, {}]", i % m.nrows(), i / m.nrows()),
            format!("must be finite, got {}", m.as_slice()[i]),
        )),
    }
}

/// `x - x_trim` with the yaw difference wrapped to (-pi, pi].
pub fn state_error(x: &[f64; STATE_DIM], trim: &[f64; STATE_DIM]) -> [f64; STATE_DIM] {
    let mut e = [0.0; STATE_DIM];
    for i in 0..STATE_DIM {
        e[i] = x[i] - trim[i];
    }
    e[8] = wrap_angle(e[8]);
    e
}

fn wrap_angle(a: f64) -> f64 {
    let wrapped =
        (a + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI) - std::f64::consts::PI;
    if wrapped == -std::f64::consts::PI {
        std::f64::consts::PI
    } else {
        wrapped
    }
}

/// A controller: from the measured state at time `t_s`, the actuator commands.
pub trait Controller: Send {
    /// Number of commands it writes (rotors x channels).
    fn command_count(&self) -> usize;
    /// Writes the commands for the measured state into `out` (length [`Controller::command_count`]).
    /// An error (only controllers that call out, such as a Python callable, can fail) ends the run.
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()>;
    /// Back to the initial internal state (called at the start of every run).
    fn reset(&mut self) {}
}

/// Every rotor commanded to zero (`controller=None` in Python).
#[derive(Debug, Clone)]
pub struct ZeroCommand {
    pub count: usize,
}

impl Controller for ZeroCommand {
    fn command_count(&self) -> usize {
        self.count
    }
    fn command(&mut self, _t_s: f64, _measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        out.fill(0.0);
        Ok(())
    }
}

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
        require_all_finite("u_trim", u_trim)?;
        require_finite_matrix("gain", &gain)?;
        if gain.shape() != (u_trim.len(), STATE_DIM) {
            return Err(RfError::shape(
                "gain",
                format!("{} x {STATE_DIM} (commands x states)", u_trim.len()),
                format!("{} x {}", gain.nrows(), gain.ncols()),
            ));
        }
        Ok(LinearFeedback {
            x_trim,
            u_trim: DVector::from_column_slice(u_trim),
            gain,
        })
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
pub struct DiscreteLti {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    c: DMatrix<f64>,
    d: DMatrix<f64>,
    x_trim: [f64; STATE_DIM],
    u_trim: DVector<f64>,
    xi: DVector<f64>,
}

impl DiscreteLti {
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
        for (field, m, rows, cols) in [
            ("A_K", &a, n, n),
            ("B_K", &b, n, STATE_DIM),
            ("C_K", &c, nu, n),
            ("D_K", &d, nu, STATE_DIM),
        ] {
            if m.shape() != (rows, cols) {
                return Err(RfError::shape(
                    field,
                    format!("{rows} x {cols}"),
                    format!("{} x {}", m.nrows(), m.ncols()),
                ));
            }
            require_finite_matrix(field, m)?;
        }
        Ok(DiscreteLti {
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

impl Controller for DiscreteLti {
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

/// A virtual-control law followed by constrained allocation: `law` writes the virtual control
/// (e.g. thrust and three torques), the active-set solver turns it into rotor commands within
/// their bounds, warm-started from the previous control step's active set.
pub struct Allocated {
    law: Box<dyn Controller>,
    solver: ActiveSetSolver,
    active: ActiveSet,
    virtual_control: Vec<f64>,
}

impl Allocated {
    /// `law` must write as many commands as the allocation problem has rows.
    pub fn new(law: Box<dyn Controller>, solver: ActiveSetSolver) -> Result<Self> {
        let n = solver.problem().virtual_dimension();
        if law.command_count() != n {
            return Err(RfError::shape(
                "law",
                format!("{n} virtual-control outputs (rows of the allocation matrix)"),
                law.command_count().to_string(),
            ));
        }
        let m = solver.problem().actuator_count();
        Ok(Allocated {
            law,
            solver,
            active: ActiveSet::cold(m),
            virtual_control: vec![0.0; n],
        })
    }
}

impl Controller for Allocated {
    fn command_count(&self) -> usize {
        self.solver.problem().actuator_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.law.command(t_s, measured, &mut self.virtual_control)?;
        if self.virtual_control.iter().all(|v| v.is_finite()) {
            self.solver
                .solve_unchecked(&self.virtual_control, &mut self.active, out);
        } else {
            // Passed on as is, so the simulator reports a non-finite command at this step.
            out.fill(f64::NAN);
        }
        Ok(())
    }
    fn reset(&mut self) {
        self.law.reset();
        self.active = ActiveSet::cold(self.solver.problem().actuator_count());
    }
}

/// Runs a controller (from its reset state) on a recorded measured-state history: row k of the
/// result is what it commands at `times_s[k]` for `states[k]`. Nothing but the measurements reaches
/// it, so a controller that passes the same history through twice commands the same thing: the
/// check that a "passive" controller really sees no fault information.
pub fn replay(
    controller: &mut dyn Controller,
    times_s: &[f64],
    states: &[RigidBodyState],
) -> Result<Vec<f64>> {
    if times_s.len() != states.len() {
        return Err(RfError::shape(
            "states",
            format!("one per time ({})", times_s.len()),
            states.len().to_string(),
        ));
    }
    require_all_finite("times", times_s)?;
    let count = controller.command_count();
    let mut out = vec![0.0; count * times_s.len()];
    controller.reset();
    for (k, (t, state)) in times_s.iter().zip(states).enumerate() {
        controller.command(*t, state, &mut out[k * count..(k + 1) * count])?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn yaw_error_is_wrapped() {
        assert!((wrap_angle(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-15);
        assert!((wrap_angle(-0.1) + 0.1).abs() < 1e-15);
        let mut x = [0.0; STATE_DIM];
        x[8] = 3.1;
        let mut trim = [0.0; STATE_DIM];
        trim[8] = -3.1;
        assert!((state_error(&x, &trim)[8] - (6.2 - 2.0 * std::f64::consts::PI)).abs() < 1e-12);
    }

    #[test]
    fn state_vector_round_trips_and_euler_rates_match_the_quaternion() {
        use crate::actuator::{FixedPitch, Lag};
        use crate::airframe::Airframe;
        use crate::vehicle::Aerodynamics;
        let x = [
            1.0, -2.0, -3.0, 0.5, 0.1, -0.2, 0.1, -0.2, 0.7, 0.3, -0.4, 1.1,
        ];
        let back = state_vector(&state_from_vector(&x));
        for i in 0..STATE_DIM {
            assert!((back[i] - x[i]).abs() < 1e-14, "{i}");
        }
        // Euler rates from the kinematics agree with a finite difference of the quaternion flow.
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../python/rotorfault/presets/quad-x.toml"
        ))
        .unwrap();
        let airframe = Airframe::from_toml_str(&text, "quad-x").unwrap();
        let vehicle = Vehicle::new(&airframe, Aerodynamics::default()).unwrap();
        let mut actuators =
            Actuators::FixedPitch(FixedPitch::new(&airframe, Lag::none(), 0.0).unwrap());
        actuators.settle(&[4.0, 3.0, 4.5, 3.5]).unwrap();
        let dx = state_vector_derivative(&vehicle, &actuators, &[1.0; 4], &x, &Vector3::zeros());
        let h = 1e-6;
        let state = state_from_vector(&x);
        let outputs: Vec<RotorOutput> = (0..4).map(|i| actuators.output(i, 1.0)).collect();
        let next = vehicle.body().rk4_step(0.0, &state, h, |_, s| {
            vehicle.wrench(s, &outputs, &Vector3::zeros())
        });
        let prev = vehicle.body().rk4_step(0.0, &state, -h, |_, s| {
            vehicle.wrench(s, &outputs, &Vector3::zeros())
        });
        let (xn, xp) = (state_vector(&next), state_vector(&prev));
        for i in 0..STATE_DIM {
            let numeric = (xn[i] - xp[i]) / (2.0 * h);
            assert!(
                (numeric - dx[i]).abs() < 1e-6 * (1.0 + dx[i].abs()),
                "{i}: {numeric} vs {}",
                dx[i]
            );
        }
    }

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
        let mut lti = DiscreteLti::new(
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
        let mut lti = DiscreteLti::new(
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
        let err = DiscreteLti::new(
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
