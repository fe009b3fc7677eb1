//! A failure-time switch: one controller flies the vehicle until a known failure time, another
//! from then on (passive fault-tolerant control with the failure and its time known in advance,
//! as a perfect fault detection would report them). The relaxed hover LQR uses it to fly the
//! healthy vehicle with the healthy-vehicle design (a hover LQR) and the failed one with the
//! relaxed hover design.

use super::Controller;
use crate::error::{Result, RfError};
use crate::state::{ControllerInput, RigidBodyState};

/// `before` commands while `t < failure_time_s`, `after` from the first control step at or after it.
pub struct FailureTimeSwitch {
    before: Box<dyn Controller>,
    after: Box<dyn Controller>,
    failure_time_s: f64,
}

impl FailureTimeSwitch {
    /// Both controllers must write the same number of commands; `failure_time_s` finite, >= 0.
    pub fn new(
        before: Box<dyn Controller>,
        after: Box<dyn Controller>,
        failure_time_s: f64,
    ) -> Result<Self> {
        if !(failure_time_s.is_finite() && failure_time_s >= 0.0) {
            return Err(RfError::invalid(
                "failure_time_s",
                format!("must be finite and >= 0, got {failure_time_s}"),
            ));
        }
        if before.command_count() != after.command_count() {
            return Err(RfError::invalid(
                "before_failure",
                format!(
                    "writes {} commands, the controller after the failure {}",
                    before.command_count(),
                    after.command_count()
                ),
            ));
        }
        Ok(FailureTimeSwitch {
            before,
            after,
            failure_time_s,
        })
    }

    fn active(&mut self, t_s: f64) -> &mut dyn Controller {
        if t_s < self.failure_time_s {
            self.before.as_mut()
        } else {
            self.after.as_mut()
        }
    }
}

impl Controller for FailureTimeSwitch {
    fn command_count(&self) -> usize {
        self.after.command_count()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        self.active(t_s).command(t_s, measured, out)
    }
    fn command_with(
        &mut self,
        t_s: f64,
        input: &ControllerInput<'_>,
        out: &mut [f64],
    ) -> Result<()> {
        self.active(t_s).command_with(t_s, input, out)
    }
    fn reads_samples(&self) -> bool {
        self.before.reads_samples() || self.after.reads_samples()
    }
    fn reset(&mut self) {
        self.before.reset();
        self.after.reset();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::OpenLoop;

    fn constant(values: &[f64]) -> Box<dyn Controller> {
        let commands = nalgebra::DMatrix::from_row_slice(1, values.len(), values);
        Box::new(OpenLoop::new(vec![0.0], commands).unwrap())
    }

    #[test]
    fn switches_at_the_failure_time() {
        let mut c = FailureTimeSwitch::new(constant(&[1.0, 2.0]), constant(&[3.0, 4.0]), 0.5).unwrap();
        let state = RigidBodyState::at_rest();
        let mut out = [0.0; 2];
        c.command(0.4999, &state, &mut out).unwrap();
        assert_eq!(out, [1.0, 2.0]);
        c.command(0.5, &state, &mut out).unwrap();
        assert_eq!(out, [3.0, 4.0]);
    }

    #[test]
    fn bad_input_is_named() {
        let err = FailureTimeSwitch::new(constant(&[1.0]), constant(&[1.0]), f64::NAN)
            .err()
            .unwrap();
        assert!(err.to_string().starts_with("failure_time_s"), "{err}");
        let err = FailureTimeSwitch::new(constant(&[1.0]), constant(&[1.0, 2.0]), 1.0)
            .err()
            .unwrap();
        assert!(err.to_string().starts_with("before_failure"), "{err}");
    }
}
