//! A failure-time switch: one controller flies the vehicle until a known failure time, another
//! from then on (passive fault-tolerant control with the failure and its time known in advance,
//! as a perfect fault detection would report them). The relaxed hover LQR uses it to fly the
//! healthy vehicle with the healthy-vehicle design (a hover LQR) and the failed one with the
//! relaxed hover design.

use super::Controller;
use crate::error::{Result, RfError};
use crate::state::{ControllerInput, RigidBodyState};

/// What the switch does once, at the first control step at or after the failure time, before
/// `after` commands: carry state over from `before` (a bumpless hand-over of integrals,
/// [`super::hover_handover`]).
pub trait HandOver<B, A>: Send {
    fn hand_over(&mut self, before: &B, after: &mut A);
}

/// No hand-over: `after` starts from its own initial state.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoHandOver;

impl<B, A> HandOver<B, A> for NoHandOver {
    fn hand_over(&mut self, _before: &B, _after: &mut A) {}
}

/// `before` commands while `t < failure_time_s`, `after` from the first control step at or after
/// it, `hand_over` run once between them.
#[derive(Debug, Clone)]
pub struct FailureTimeSwitch<B = Box<dyn Controller>, A = Box<dyn Controller>, H = NoHandOver> {
    before: B,
    after: A,
    hand_over: H,
    failure_time_s: f64,
    handed_over: bool,
}

impl FailureTimeSwitch {
    /// Both controllers must write the same number of commands; `failure_time_s` finite, >= 0.
    pub fn new(
        before: Box<dyn Controller>,
        after: Box<dyn Controller>,
        failure_time_s: f64,
    ) -> Result<Self> {
        Self::with_hand_over(before, after, failure_time_s, NoHandOver)
    }
}

impl<B: Controller, A: Controller, H: HandOver<B, A>> FailureTimeSwitch<B, A, H> {
    /// [`FailureTimeSwitch::new`] with `hand_over` run at the switch.
    pub fn with_hand_over(before: B, after: A, failure_time_s: f64, hand_over: H) -> Result<Self> {
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
            hand_over,
            failure_time_s,
            handed_over: false,
        })
    }

    /// The controller flying at `t_s` (handing over first at the switch).
    fn active(&mut self, t_s: f64) -> &mut dyn Controller {
        if t_s < self.failure_time_s {
            return &mut self.before;
        }
        if !self.handed_over {
            self.handed_over = true;
            self.hand_over.hand_over(&self.before, &mut self.after);
        }
        &mut self.after
    }

    pub fn before(&self) -> &B {
        &self.before
    }

    pub fn after(&self) -> &A {
        &self.after
    }
}

impl<B: Controller, A: Controller, H: HandOver<B, A>> Controller for FailureTimeSwitch<B, A, H> {
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
        self.handed_over = false;
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
        let mut c =
            FailureTimeSwitch::new(constant(&[1.0, 2.0]), constant(&[3.0, 4.0]), 0.5).unwrap();
        let state = RigidBodyState::at_rest();
        let mut out = [0.0; 2];
        c.command(0.4999, &state, &mut out).unwrap();
        assert_eq!(out, [1.0, 2.0]);
        c.command(0.5, &state, &mut out).unwrap();
        assert_eq!(out, [3.0, 4.0]);
    }

    /// Counts its hand-overs.
    struct Counting(usize);
    impl HandOver<OpenLoop, OpenLoop> for Counting {
        fn hand_over(&mut self, _before: &OpenLoop, _after: &mut OpenLoop) {
            self.0 += 1;
        }
    }

    #[test]
    fn hands_over_once_at_the_switch_and_again_after_a_reset() {
        let open = |v: f64| {
            OpenLoop::new(vec![0.0], nalgebra::DMatrix::from_row_slice(1, 1, &[v])).unwrap()
        };
        let mut c =
            FailureTimeSwitch::with_hand_over(open(1.0), open(3.0), 0.5, Counting(0)).unwrap();
        let state = RigidBodyState::at_rest();
        let mut out = [0.0];
        c.command(0.4999, &state, &mut out).unwrap();
        assert_eq!((out, c.hand_over.0), ([1.0], 0));
        for t in [0.5, 0.5025, 0.505] {
            c.command(t, &state, &mut out).unwrap();
        }
        assert_eq!((out, c.hand_over.0), ([3.0], 1));
        c.reset();
        c.command(0.6, &state, &mut out).unwrap();
        assert_eq!(c.hand_over.0, 2);
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
