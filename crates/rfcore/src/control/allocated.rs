//! A virtual-control law followed by constrained allocation, in one controller.

use super::Controller;
use crate::allocation::active_set::{ActiveSet, ActiveSetSolver};
use crate::error::{Result, RfError};
use crate::state::RigidBodyState;

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
