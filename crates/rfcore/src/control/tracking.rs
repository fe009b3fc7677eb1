//! State feedback on a moving reference with a saturated error (reference shaping):
//! `u = u_trim - K sat(x - x_ref(t))`.
//!
//! A linear gain designed about hover answers a 5 m position step with a command no actuator
//! gives and a tilt far outside the linear model (Wang's scenario 2 diverges with a plain LQR);
//! clipping each error component to `error_limit[i]` turns a step into a bounded-speed approach,
//! inside the region the gain was designed for. The reference is a table: rows of 12 states at
//! non-decreasing times, linear between distinct times; a time given twice is a jump (the later
//! row holds from that time), so one table expresses both setpoint steps and a sampled path.

use nalgebra::{DMatrix, DVector};

use super::{require_finite_matrix, require_state_gain, Controller};
use crate::error::{require_all_finite, Result, RfError};
use crate::state::{state_error, state_vector, RigidBodyState, STATE_DIM};

/// `u = u_trim - K sat(x - x_ref(t))` (module docs).
#[derive(Debug, Clone)]
pub struct TrackingFeedback {
    u_trim: DVector<f64>,
    gain: DMatrix<f64>,
    times_s: Vec<f64>,
    references: Vec<[f64; STATE_DIM]>,
    error_limit: [f64; STATE_DIM],
}

impl TrackingFeedback {
    /// `gain`: commands x 12; `references`: one row of 12 states per entry of `times_s`
    /// (non-decreasing); `error_limit`: 12 entries > 0 (`inf`: no limit on that component).
    pub fn new(
        u_trim: &[f64],
        gain: DMatrix<f64>,
        times_s: Vec<f64>,
        references: DMatrix<f64>,
        error_limit: &[f64],
    ) -> Result<Self> {
        require_state_gain(u_trim, &gain)?;
        if times_s.is_empty() || references.shape() != (times_s.len(), STATE_DIM) {
            return Err(RfError::shape(
                "references",
                format!(
                    "one row of {STATE_DIM} states per time ({}), at least one",
                    times_s.len()
                ),
                format!("{} x {}", references.nrows(), references.ncols()),
            ));
        }
        require_all_finite("times_s", &times_s)?;
        require_finite_matrix("references", &references)?;
        if let Some(k) = times_s.windows(2).position(|w| w[1] < w[0]) {
            return Err(RfError::invalid(
                format!("times_s[{}]", k + 1),
                "times must be non-decreasing (a repeated time is a jump)",
            ));
        }
        let error_limit: [f64; STATE_DIM] = error_limit.try_into().map_err(|_| {
            RfError::shape(
                "error_limit",
                format!("{STATE_DIM} entries"),
                error_limit.len().to_string(),
            )
        })?;
        if let Some(i) = error_limit.iter().position(|v| v.is_nan() || *v <= 0.0) {
            return Err(RfError::invalid(
                format!("error_limit[{i}]"),
                format!("must be > 0 (inf for no limit), got {}", error_limit[i]),
            ));
        }
        let references = (0..references.nrows())
            .map(|r| std::array::from_fn(|c| references[(r, c)]))
            .collect();
        Ok(TrackingFeedback {
            u_trim: DVector::from_column_slice(u_trim),
            gain,
            times_s,
            references,
            error_limit,
        })
    }

    /// The reference at `t_s` (module docs: linear between distinct times, held outside).
    pub fn reference(&self, t_s: f64) -> [f64; STATE_DIM] {
        let after = self.times_s.partition_point(|&s| s <= t_s);
        if after == 0 {
            return self.references[0];
        }
        if after == self.times_s.len() {
            return self.references[after - 1];
        }
        let (t0, t1) = (self.times_s[after - 1], self.times_s[after]);
        let (r0, r1) = (&self.references[after - 1], &self.references[after]);
        let w = (t_s - t0) / (t1 - t0);
        std::array::from_fn(|i| r0[i] + w * (r1[i] - r0[i]))
    }
}

impl Controller for TrackingFeedback {
    fn command_count(&self) -> usize {
        self.u_trim.len()
    }
    fn command(&mut self, t_s: f64, measured: &RigidBodyState, out: &mut [f64]) -> Result<()> {
        let mut e = state_error(&state_vector(measured), &self.reference(t_s));
        for (v, limit) in e.iter_mut().zip(self.error_limit) {
            *v = v.clamp(-limit, limit);
        }
        for (i, o) in out.iter_mut().enumerate() {
            let feedback: f64 = (0..STATE_DIM).map(|j| self.gain[(i, j)] * e[j]).sum();
            *o = self.u_trim[i] - feedback;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;

    fn controller(limit: f64) -> TrackingFeedback {
        let mut refs = DMatrix::zeros(4, STATE_DIM);
        refs[(1, 0)] = 2.0; // ramp 0 -> 2 m over [0, 1] s
        refs[(2, 0)] = 2.0;
        refs[(3, 0)] = 5.0; // jump to 5 m at t = 3 s
        let mut gain = DMatrix::zeros(1, STATE_DIM);
        gain[(0, 0)] = 3.0;
        let mut error_limit = [f64::INFINITY; STATE_DIM];
        error_limit[0] = limit;
        TrackingFeedback::new(&[10.0], gain, vec![0.0, 1.0, 3.0, 3.0], refs, &error_limit).unwrap()
    }

    #[test]
    fn reference_is_linear_between_times_and_jumps_at_repeated_ones() {
        let c = controller(1.0);
        for (t, x) in [
            (-1.0, 0.0),
            (0.25, 0.5),
            (1.0, 2.0),
            (2.999, 2.0),
            (3.0, 5.0),
            (9.0, 5.0),
        ] {
            assert!((c.reference(t)[0] - x).abs() < 1e-12, "t = {t}");
        }
    }

    #[test]
    fn error_is_clipped_per_component() {
        // Hand computation: x = 0 at t = 3 s, reference 5 m: error -5 clipped to -1, u = 10 + 3.
        let mut c = controller(1.0);
        let mut out = [0.0];
        c.command(3.0, &RigidBodyState::at_rest(), &mut out)
            .unwrap();
        assert_eq!(out[0], 13.0);
        // Inside the limit it is plain state feedback: error -0.5 at t = 0.25 s, u = 11.5.
        c.command(0.25, &RigidBodyState::at_rest(), &mut out)
            .unwrap();
        assert!((out[0] - 11.5).abs() < 1e-12);
        // An unlimited component: no clipping (x = 7 m against 5 m, u = 10 - 6).
        let mut free = controller(f64::INFINITY);
        let mut s = RigidBodyState::at_rest();
        s.position_m = Vector3::new(7.0, 0.0, 0.0);
        free.command(4.0, &s, &mut out).unwrap();
        assert!((out[0] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn bad_input_names_the_field() {
        let gain = DMatrix::zeros(1, STATE_DIM);
        let refs = DMatrix::zeros(2, STATE_DIM);
        let lim = [1.0; STATE_DIM];
        let err = |r: Result<TrackingFeedback>| r.unwrap_err().to_string();
        assert!(err(TrackingFeedback::new(
            &[0.0],
            gain.clone(),
            vec![1.0, 0.0],
            refs.clone(),
            &lim
        ))
        .contains("times_s[1]"));
        assert!(err(TrackingFeedback::new(
            &[0.0],
            gain.clone(),
            vec![0.0],
            refs.clone(),
            &lim
        ))
        .contains("references"));
        assert!(err(TrackingFeedback::new(
            &[0.0, 1.0],
            gain.clone(),
            vec![0.0, 1.0],
            refs.clone(),
            &lim
        ))
        .contains("gain"));
        let mut bad = lim;
        bad[4] = 0.0;
        assert!(err(TrackingFeedback::new(
            &[0.0],
            gain.clone(),
            vec![0.0, 1.0],
            refs.clone(),
            &bad
        ))
        .contains("error_limit[4]"));
        assert!(err(TrackingFeedback::new(
            &[0.0],
            gain.clone(),
            vec![0.0, 1.0],
            refs.clone(),
            &lim[..3]
        ))
        .contains("error_limit"));
        let mut nan_refs = refs.clone();
        nan_refs[(1, 2)] = f64::NAN;
        assert!(err(TrackingFeedback::new(
            &[0.0],
            gain,
            vec![0.0, 1.0],
            nan_refs,
            &lim
        ))
        .contains("references[1, 2]"));
    }
}
