//! Rotor faults on a schedule the controller never sees.
//!
//! A [`FaultSchedule`] holds the faults in time order and answers two questions for the
//! integrator: when is the next switch ([`FaultSchedule::next_time`]), and which faults are due
//! by a time ([`FaultSchedule::apply_due`]). The simulator ends every integration interval at the
//! next fault time, so a fault acts from exactly its time, not from the next substep boundary.

use crate::error::{require_finite, Result, RfError};

/// Rotor `rotor` (0-based) has efficiency `efficiency` from `time_s` on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RotorFault {
    pub rotor: usize,
    pub time_s: f64,
    pub efficiency: f64,
}

/// Validated faults in time order (stable: faults at the same time apply in input order, the
/// last one wins) and a cursor at the first one not yet applied.
#[derive(Debug, Clone, PartialEq)]
pub struct FaultSchedule {
    faults: Vec<RotorFault>,
    next: usize,
}

impl FaultSchedule {
    /// Checks rotor numbers (`< rotor_count`), finite times and efficiencies in [0, 1]; the
    /// faults may come in any order.
    pub fn new(faults: &[RotorFault], rotor_count: usize) -> Result<Self> {
        for (k, f) in faults.iter().enumerate() {
            if f.rotor >= rotor_count {
                return Err(RfError::invalid(
                    format!("faults[{k}].rotor"),
                    format!(
                        "rotor numbers run from 1 to {rotor_count}, got {}",
                        f.rotor + 1
                    ),
                ));
            }
            require_finite(&format!("faults[{k}].time"), f.time_s)?;
            require_finite(&format!("faults[{k}].efficiency"), f.efficiency)?;
            if !(0.0..=1.0).contains(&f.efficiency) {
                return Err(RfError::invalid(
                    format!("faults[{k}].efficiency"),
                    format!("must lie in [0, 1], got {}", f.efficiency),
                ));
            }
        }
        let mut faults = faults.to_vec();
        faults.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        Ok(FaultSchedule { faults, next: 0 })
    }

    /// Time of the first fault not yet applied.
    #[inline]
    pub fn next_time(&self) -> Option<f64> {
        self.faults.get(self.next).map(|f| f.time_s)
    }

    /// The end of an integration interval starting at `from_s` that should end at `to_s`:
    /// `to_s`, or the next fault time when it lies strictly inside.
    #[inline]
    pub fn interval_end(&self, from_s: f64, to_s: f64) -> f64 {
        match self.next_time() {
            Some(t) if t > from_s && t < to_s => t,
            _ => to_s,
        }
    }

    /// Applies to `efficiency` every pending fault with time `<= t_s`; `true` when any applied.
    #[inline]
    pub fn apply_due(&mut self, t_s: f64, efficiency: &mut [f64]) -> bool {
        let start = self.next;
        while let Some(f) = self.faults.get(self.next) {
            if f.time_s > t_s {
                break;
            }
            efficiency[f.rotor] = f.efficiency;
            self.next += 1;
        }
        self.next != start
    }

    /// Back to before the first fault.
    pub fn rewind(&mut self) {
        self.next = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fault(rotor: usize, time_s: f64, efficiency: f64) -> RotorFault {
        RotorFault {
            rotor,
            time_s,
            efficiency,
        }
    }

    #[test]
    fn faults_apply_in_time_order_and_split_intervals() {
        let mut s = FaultSchedule::new(
            &[
                fault(1, 0.3, 0.0),
                fault(0, 0.2501, 0.5),
                fault(0, 0.3, 0.25),
            ],
            2,
        )
        .unwrap();
        let mut efficiency = [1.0, 1.0];
        assert_eq!(s.next_time(), Some(0.2501));
        assert_eq!(s.interval_end(0.25, 0.30), 0.2501);
        assert_eq!(
            s.interval_end(0.2501, 0.30),
            0.30,
            "a fault at the start does not split"
        );
        assert!(!s.apply_due(0.25, &mut efficiency));
        assert!(s.apply_due(0.2501, &mut efficiency));
        assert_eq!(efficiency, [0.5, 1.0]);
        // A fault exactly at the end of an interval does not split it; it applies there.
        assert_eq!(s.interval_end(0.2501, 0.30), 0.30);
        assert!(s.apply_due(0.30, &mut efficiency));
        assert_eq!(efficiency, [0.25, 0.0]);
        assert_eq!(s.next_time(), None);
        s.rewind();
        assert_eq!(s.next_time(), Some(0.2501));
    }

    #[test]
    fn bad_faults_are_named() {
        let err = |f: RotorFault| FaultSchedule::new(&[f], 4).unwrap_err().to_string();
        assert!(err(fault(4, 1.0, 0.0))
            .starts_with("faults[0].rotor: rotor numbers run from 1 to 4, got 5"));
        assert!(err(fault(0, f64::NAN, 0.0)).starts_with("faults[0].time"));
        assert!(err(fault(0, 1.0, 1.5)).starts_with("faults[0].efficiency"));
    }
}
