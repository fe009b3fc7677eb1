//! Cooperative cancellation of long calls: a token the caller holds ([`Cancel`]) and the core
//! polls, so a batch, a failure table or a long run stops within a bounded time of being asked
//! to (Ctrl-C in Python) and returns [`RfError::Interrupted`].
//!
//! The core knows nothing of signals (no pyo3 here). The bindings' one GIL helper runs the work on
//! a worker while the calling thread watches for Ctrl-C and calls [`Cancel::cancel`]; the work
//! checks the token in its loops:
//! - the ACAI batch every block of rows ([`rows_per_check`]: about a million table entries, ~1 ms),
//!   and the facet enumeration every [`GROUPS_PER_CHECK`] column groups;
//! - the failure table, allocation batches and replays once per item;
//! - a run once per control period (at most [`crate::flight::simulation::MAX_SUBSTEPS`] RK4
//!   steps), so `simulate`, `simulate_batch` and the campaign summaries inside their rayon pools;
//!   with sensing also before every sensor sample of the period (one estimator step, ~4 us: a
//!   period holds `dt_s x imu_rate_hz` of them, unbounded by the substep cap).
//!
//! A check is one relaxed atomic load (~1 ns), next to microseconds of work between checks.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::error::{Result, RfError};

/// Column groups of the facet enumeration between two checks (each costs 0.1-10 us).
pub const GROUPS_PER_CHECK: usize = 256;

/// Table entries (`groups x m` multiply-adds, about 1 ns each) the ACAI batch evaluates between
/// two checks: about 1 ms of work.
pub const ENTRIES_PER_CHECK: usize = 1 << 20;

/// Rows of an ACAI batch between two checks for a table of `entries_per_row` entries per row:
/// [`ENTRIES_PER_CHECK`] entries, at least one row.
pub fn rows_per_check(entries_per_row: usize) -> usize {
    (ENTRIES_PER_CHECK / entries_per_row.max(1)).max(1)
}

/// A cancellation token: cheap to clone (clones share one flag), set once by whoever holds it.
#[derive(Debug, Clone, Default)]
pub struct Cancel {
    flag: Arc<AtomicBool>,
}

impl Cancel {
    /// A token nobody has cancelled yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// A token for a call nobody can cancel (nobody else holds it).
    pub fn never() -> Self {
        Self::default()
    }

    /// Asks every holder's work to stop.
    pub fn cancel(&self) {
        self.flag.store(true, Ordering::Relaxed);
    }

    pub fn is_cancelled(&self) -> bool {
        self.flag.load(Ordering::Relaxed)
    }

    /// `Err(RfError::Interrupted)` once cancelled: the check every long loop makes.
    #[inline]
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(RfError::Interrupted)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag() {
        let token = Cancel::new();
        let held = token.clone();
        assert!(held.check().is_ok());
        token.cancel();
        assert!(held.is_cancelled());
        assert_eq!(held.check(), Err(RfError::Interrupted));
        assert!(Cancel::never().check().is_ok());
        assert_eq!(rows_per_check(0), ENTRIES_PER_CHECK);
        assert_eq!(rows_per_check(usize::MAX), 1);
    }
}
