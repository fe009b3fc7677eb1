//! The second-order low-pass filter `w^2 / (s^2 + 2 zeta w s + w^2)` of incremental controllers,
//! discretised exactly at the control period, with its value, rate and acceleration.
//!
//! INDI differentiates a filtered gyro signal to get the angular acceleration and applies the *same*
//! filter to the actuator feedback, so both are delayed alike (Smeur et al., JGCD 2016; Sun et al.,
//! T-RO 2020). The filter's state is `[y, y']`, so the derivative of the filtered signal is exact,
//! not a finite difference.
//!
//! # Discretisation (stated once)
//! Step-invariant (zero-order hold) with the input sampled at the end of the period, the rule of
//! Ke's first-order filter in [`crate::control::ke`]: `x_k = Phi x_(k-1) + Gamma u_k` with
//! `Phi = exp(A dt)`, `Gamma = int_0^dt exp(A s) ds B`. A step applied at sample 1 gives exactly the
//! continuous step response at every sample. The acceleration `y'' = w^2 (u_k - y) - 2 zeta w y'` is
//! the continuous filter's at the sample.

use nalgebra::Matrix3;

use crate::error::{require_finite, Result, RfError};

/// The discretised filter: coefficients only; each channel keeps its own `[value, rate]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrderLowPass {
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
    natural_frequency_rad_s: f64,
    damping: f64,
}

impl SecondOrderLowPass {
    /// `natural_frequency_rad_s` > 0, `damping` > 0, `dt_s` > 0, all finite; the names are the
    /// fields the errors carry (a gains struct passes its own).
    pub fn new(
        (frequency_field, natural_frequency_rad_s): (&str, f64),
        (damping_field, damping): (&str, f64),
        dt_s: f64,
    ) -> Result<Self> {
        for (field, value) in [
            (frequency_field, natural_frequency_rad_s),
            (damping_field, damping),
            ("dt_s", dt_s),
        ] {
            require_finite(field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        let w = natural_frequency_rad_s;
        // exp of [[A, B], [0, 0]] dt holds Phi (top left) and Gamma (top right).
        let augmented = Matrix3::new(
            0.0,
            1.0,
            0.0,
            -w * w,
            -2.0 * damping * w,
            w * w,
            0.0,
            0.0,
            0.0,
        ) * dt_s;
        let e = augmented.exp();
        Ok(SecondOrderLowPass {
            phi: [[e[(0, 0)], e[(0, 1)]], [e[(1, 0)], e[(1, 1)]]],
            gamma: [e[(0, 2)], e[(1, 2)]],
            natural_frequency_rad_s: w,
            damping,
        })
    }

    /// A channel state settled at `value` (zero rate): a filter started at its input.
    pub fn settled(value: f64) -> [f64; 2] {
        [value, 0.0]
    }

    /// One control period with input `input` (module docs); `state` is `[value, rate]`.
    #[inline]
    pub fn step(&self, state: &mut [f64; 2], input: f64) {
        let [y, v] = *state;
        state[0] = self.phi[0][0] * y + self.phi[0][1] * v + self.gamma[0] * input;
        state[1] = self.phi[1][0] * y + self.phi[1][1] * v + self.gamma[1] * input;
    }

    /// The filtered signal's second derivative at the sample, for the input of this period.
    #[inline]
    pub fn acceleration(&self, state: &[f64; 2], input: f64) -> f64 {
        let w = self.natural_frequency_rad_s;
        w * w * (input - state[0]) - 2.0 * self.damping * w * state[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The continuous unit-step response and its derivative (closed forms for every damping).
    fn step_response(w: f64, zeta: f64, t: f64) -> (f64, f64) {
        if (zeta - 1.0).abs() < 1e-12 {
            let e = (-w * t).exp();
            (1.0 - (1.0 + w * t) * e, w * w * t * e)
        } else if zeta < 1.0 {
            let root = (1.0 - zeta * zeta).sqrt();
            let wd = w * root;
            let e = (-zeta * w * t).exp();
            (
                1.0 - e * ((wd * t).cos() + zeta / root * (wd * t).sin()),
                w / root * e * (wd * t).sin(),
            )
        } else {
            // Two real poles p1, p2 < 0: y = 1 + (p2 e^(p1 t) - p1 e^(p2 t)) / (p1 - p2).
            let root = (zeta * zeta - 1.0).sqrt();
            let (p1, p2) = (-w * (zeta - root), -w * (zeta + root));
            let (e1, e2) = ((p1 * t).exp(), (p2 * t).exp());
            (
                1.0 + (p2 * e1 - p1 * e2) / (p1 - p2),
                p1 * p2 * (e1 - e2) / (p1 - p2),
            )
        }
    }

    #[test]
    fn step_response_matches_the_closed_form_at_every_sample() {
        let dt = 1.0 / 400.0;
        for (w, zeta) in [(50.0, 0.55), (50.0, 1.0), (20.0, 2.0), (300.0, 0.1)] {
            let filter = SecondOrderLowPass::new(("w", w), ("zeta", zeta), dt).unwrap();
            let mut state = SecondOrderLowPass::settled(0.0);
            for k in 1..=800 {
                filter.step(&mut state, 1.0);
                let (y, v) = step_response(w, zeta, k as f64 * dt);
                // The exponential of a 3 x 3 matrix: a few ulps of the unit step.
                assert!(
                    (state[0] - y).abs() < 1e-12,
                    "w {w} zeta {zeta} k {k}: {} vs {y}",
                    state[0]
                );
                assert!(
                    (state[1] - v).abs() < 1e-10 * w,
                    "w {w} zeta {zeta} k {k}: {} vs {v}",
                    state[1]
                );
                // y'' = derivative of y' (central difference of the closed form, step 1e-6 s).
                let h = 1e-6;
                let a = (step_response(w, zeta, k as f64 * dt + h).1
                    - step_response(w, zeta, k as f64 * dt - h).1)
                    / (2.0 * h);
                let got = filter.acceleration(&state, 1.0);
                assert!(
                    (got - a).abs() < 1e-5 * w * w,
                    "w {w} zeta {zeta} k {k}: {got} vs {a}"
                );
            }
        }
    }

    #[test]
    fn a_settled_filter_stays_settled_and_bad_parameters_are_named() {
        let filter = SecondOrderLowPass::new(("w", 50.0), ("zeta", 0.55), 0.0025).unwrap();
        let mut state = SecondOrderLowPass::settled(3.5);
        for _ in 0..100 {
            filter.step(&mut state, 3.5);
        }
        assert!(
            (state[0] - 3.5).abs() < 1e-13 && state[1].abs() < 1e-11,
            "{state:?}"
        );
        let err =
            SecondOrderLowPass::new(("gains.filter_damping", 50.0), ("z", 0.0), 0.01).unwrap_err();
        assert!(err.to_string().starts_with("z:"), "{err}");
        let err = SecondOrderLowPass::new(("gains.w", f64::NAN), ("z", 1.0), 0.01).unwrap_err();
        assert!(err.to_string().starts_with("gains.w:"), "{err}");
    }
}
