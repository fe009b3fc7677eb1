//! Controllers the simulator runs at its control rate (zero-order hold between updates).
//!
//! Design in Python, run in Rust: gains and controller matrices are computed in Python
//! (python-control, H-infinity synthesis) and handed to these built-ins, which run without the GIL.
//! A controller sees a time and a measured [`RigidBodyState`], never the simulator: this room
//! depends on `state` and `allocation`, not on `flight`.
//!
//! - [`linear`]: open loop, state feedback and discrete LTI laws on the state vector of
//!   [`crate::state::state_vector`].
//! - [`tracking`]: state feedback on a moving reference with a saturated error.
//! - [`allocated`]: a virtual-control law followed by constrained allocation.
//! - [`ke`]: Ke et al.'s uniform passive fault-tolerant controller.
//! - [`indi`]: incremental nonlinear dynamic inversion fault-tolerant control (Sun et al.), with
//!   the second-order [`filter`] it differentiates the gyro through.
//! - [`lanzon`]: Lanzon et al.'s spinning-quadrotor controller (robust feedback linearisation,
//!   H-infinity loop shaping, yaw-synchronised outer loop).
//! - [`relaxed_hover`]: linear feedback about a relaxed hover (Mueller and D'Andrea's cascade).
//! - [`switch`]: one controller before a known failure time, another after it.
//! - [`hover_handover`]: a hover LQR with integral action, handing its integrals over to the
//!   relaxed hover LQR at a known failure time.
//! - [`integral`]: the clamped rectangle-rule position-error integral the outer loops with
//!   integral action share.

use nalgebra::DMatrix;

use crate::cancel::Cancel;
use crate::error::{require_all_finite, Result, RfError};
use crate::state::{ControllerInput, RigidBodyState, STATE_DIM};

pub mod allocated;
pub mod filter;
pub mod hover_handover;
pub mod indi;
pub mod integral;
pub mod ke;
pub mod lanzon;
pub mod linear;
pub mod relaxed_hover;
pub mod switch;
pub mod tracking;

pub use allocated::Allocated;
pub use linear::{LinearFeedback, Lti, OpenLoop};
pub use tracking::TrackingFeedback;

/// Rejects a non-finite matrix entry, naming it `field[row, col]`.
pub(crate) fn require_finite_matrix(field: &str, m: &DMatrix<f64>) -> Result<()> {
    match m.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(RfError::invalid(
            format!("{field}[{}, {}]", i % m.nrows(), i / m.nrows()),
            format!("must be finite, got {}", m.as_slice()[i]),
        )),
    }
}

/// Each `(field, matrix, rows, cols)` in order: `rows x cols` (a shape error naming `field`),
/// then finite (`field[row, col]`): the check of a controller's matrices (`Lti`, Lanzon's
/// discrete controller).
pub(crate) fn require_shaped_finite<const N: usize>(
    matrices: [(&str, &DMatrix<f64>, usize, usize); N],
) -> Result<()> {
    for (field, m, rows, cols) in matrices {
        if m.shape() != (rows, cols) {
            return Err(RfError::shape(
                field,
                format!("{rows} x {cols}"),
                format!("{} x {}", m.nrows(), m.ncols()),
            ));
        }
        require_finite_matrix(field, m)?;
    }
    Ok(())
}

/// A static state feedback about a trim command: `u_trim` finite, `gain` finite and one row of
/// [`STATE_DIM`] states per command (`LinearFeedback`, `TrackingFeedback`).
pub(crate) fn require_state_gain(u_trim: &[f64], gain: &DMatrix<f64>) -> Result<()> {
    require_all_finite("u_trim", u_trim)?;
    require_finite_matrix("gain", gain)?;
    if gain.shape() != (u_trim.len(), STATE_DIM) {
        return Err(RfError::shape(
            "gain",
            format!("{} x {STATE_DIM} (commands x states)", u_trim.len()),
            format!("{} x {}", gain.nrows(), gain.ncols()),
        ));
    }
    Ok(())
}

/// A controller: from the measured state at time `t_s`, the actuator commands.
pub trait Controller: Send {
    /// Number of commands it writes (rotors x channels).
    fn command_count(&self) -> usize;
    /// Writes the commands for the measured state into `out` (length [`Controller::command_count`]).
    /// An error (only controllers that call out, such as a Python callable, can fail) ends the run.
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()>;
    /// [`Controller::command`] given everything measured this step: the state plus the raw samples
    /// of [`ControllerInput`] (gyro, accelerometer, rotor outputs). The simulator calls this one;
    /// by default it uses the state alone, so a controller that needs no samples implements
    /// [`Controller::command`] only.
    fn command_with(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        self.command(t_s, input.state, out)
    }
    /// Whether [`Controller::command_with`] reads the raw samples: the simulator computes them only
    /// for a controller that does (they cost a rotor evaluation per control step).
    fn reads_samples(&self) -> bool {
        false
    }
    /// Back to the initial internal state (called at the start of every run).
    fn reset(&mut self) {}
}

/// A boxed controller is a controller (so a [`switch::FailureTimeSwitch`] holds boxed or concrete
/// ones alike).
impl<C: Controller + ?Sized> Controller for Box<C> {
    fn command_count(&self) -> usize {
        (**self).command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        (**self).command(t_s, measured, out)
    }
    fn command_with(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        (**self).command_with(t_s, input, out)
    }
    fn reads_samples(&self) -> bool {
        (**self).reads_samples()
    }
    fn reset(&mut self) {
        (**self).reset()
    }
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

/// Runs a controller (from its reset state) on a recorded measured-state history: row k of the
/// result is what it commands at `times_s[k]` for `states[k]`. Nothing but the measurements reaches
/// it, so a controller that passes the same history through twice commands the same thing: the
/// check that a "passive" controller really sees no fault information.
/// `cancel` is checked before every step.
pub fn replay(
    controller: &mut dyn Controller,
    times_s: &[f64],
    states: &[RigidBodyState],
    cancel: &Cancel,
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
        cancel.check()?;
        controller.command(*t, state, &mut out[k * count..(k + 1) * count])?;
    }
    Ok(out)
}
