//! The integral of a position error that the outer loops with integral action share (the
//! relaxed hover LQR's, Lanzon's PID outer loop; the hover LQI's is the same rule): the
//! rectangle rule over the time since the previous control call, with the sum limited after
//! each step (per axis, or by its length).
//!
//! One rule, written once: the time base starts at the first call (nothing is added then), a
//! call whose time does not advance (or is NaN) adds nothing, and a non-finite error adds
//! nothing (the integral never becomes NaN and is never saturated by a NaN or infinite reading;
//! the controller's own checks name the bad state). Steps are `sum + dt * error` in that order
//! and then the limit, so a controller moved onto this type flies bit for bit as before.

use nalgebra::SVector;

/// `\int e dt` (m s) of an `N`-component position error with its time base (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PositionIntegral<const N: usize> {
    sum_m_s: [f64; N],
    integrated_to_s: Option<f64>,
}

impl<const N: usize> Default for PositionIntegral<N> {
    fn default() -> Self {
        PositionIntegral {
            sum_m_s: [0.0; N],
            integrated_to_s: None,
        }
    }
}

impl<const N: usize> PositionIntegral<N> {
    /// The integral so far, m s.
    pub fn sum_m_s(&self) -> [f64; N] {
        self.sum_m_s
    }

    /// Zero, and no time base (the next call only sets it).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Starts from `sum_m_s` (a hand-over from another loop's integral; the caller limits it);
    /// the time base is unchanged.
    pub fn set_sum_m_s(&mut self, sum_m_s: [f64; N]) {
        self.sum_m_s = sum_m_s;
    }

    /// Moves the time base to `t_s` and returns the time since the previous call (s) when it is
    /// > 0; `None` on the first call and when time did not advance or is NaN.
    pub fn advance(&mut self, t_s: f64) -> Option<f64> {
        let previous = self.integrated_to_s.replace(t_s)?;
        let dt_s = t_s - previous;
        (dt_s > 0.0).then_some(dt_s)
    }

    /// Adds `dt_s * error_m`, then clamps each component `k` to `[-limit_m_s[k], limit_m_s[k]]`
    /// (each limit > 0); nothing when a component of `error_m` is not finite.
    pub fn add_clamped(&mut self, dt_s: f64, error_m: [f64; N], limit_m_s: [f64; N]) {
        if !error_m.iter().all(|e| e.is_finite()) {
            return;
        }
        for ((sum, e), limit) in self.sum_m_s.iter_mut().zip(error_m).zip(limit_m_s) {
            *sum = (*sum + dt_s * e).clamp(-limit, limit);
        }
    }

    /// Adds `dt_s * error_m`, then scales the sum back onto the ball of radius `limit_m_s` (> 0)
    /// when it is longer (its direction kept); nothing when a component of `error_m` is not finite.
    pub fn add_norm_limited(&mut self, dt_s: f64, error_m: [f64; N], limit_m_s: f64) {
        if !error_m.iter().all(|e| e.is_finite()) {
            return;
        }
        for (sum, e) in self.sum_m_s.iter_mut().zip(error_m) {
            *sum += dt_s * e;
        }
        let length = SVector::<f64, N>::from(self.sum_m_s).norm();
        if length > limit_m_s {
            for sum in &mut self.sum_m_s {
                *sum *= limit_m_s / length;
            }
        }
    }

    /// [`Self::advance`] to `t_s`, then [`Self::add_clamped`] over the step.
    pub fn integrate_clamped(&mut self, t_s: f64, error_m: [f64; N], limit_m_s: [f64; N]) {
        if let Some(dt_s) = self.advance(t_s) {
            self.add_clamped(dt_s, error_m, limit_m_s);
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector2;

    use super::*;

    #[test]
    fn the_first_call_sets_the_time_base_and_later_calls_add_the_rectangle() {
        let mut i = PositionIntegral::<2>::default();
        i.integrate_clamped(1.0, [3.0, -4.0], [100.0; 2]);
        assert_eq!(i.sum_m_s(), [0.0, 0.0]);
        i.integrate_clamped(1.25, [3.0, -4.0], [100.0; 2]);
        // Exact in binary: 0.25 * 3 and 0.25 * -4.
        assert_eq!(i.sum_m_s(), [0.75, -1.0]);
        i.integrate_clamped(1.75, [1.0, 2.0], [100.0; 2]);
        assert_eq!(i.sum_m_s(), [1.25, 0.0]);
    }

    #[test]
    fn time_that_does_not_advance_and_non_finite_errors_add_nothing() {
        let mut i = PositionIntegral::<1>::default();
        i.integrate_clamped(0.0, [1.0], [10.0]);
        i.integrate_clamped(0.5, [1.0], [10.0]);
        let at = i.sum_m_s();
        for (t_s, e) in [(0.5, 1.0), (0.25, 1.0), (f64::NAN, 1.0)] {
            i.integrate_clamped(t_s, [e], [10.0]);
            assert_eq!(i.sum_m_s(), at, "t = {t_s}");
        }
        // After a NaN time the next call only sets the time base again.
        i.integrate_clamped(1.0, [1.0], [10.0]);
        assert_eq!(i.sum_m_s(), at);
        for (t_s, e) in [
            (2.0, f64::NAN),
            (3.0, f64::INFINITY),
            (4.0, f64::NEG_INFINITY),
        ] {
            i.integrate_clamped(t_s, [e], [10.0]);
            assert_eq!(i.sum_m_s(), at, "error {e}");
        }
        let mut n = PositionIntegral::<2>::default();
        n.add_norm_limited(1.0, [f64::NAN, 1.0], 5.0);
        assert_eq!(n.sum_m_s(), [0.0, 0.0]);
    }

    #[test]
    fn each_axis_is_clamped_to_its_own_limit() {
        let mut i = PositionIntegral::<3>::default();
        i.add_clamped(2.0, [1.0, -1.0, 0.1], [0.5, 1.5, 1.0]);
        assert_eq!(i.sum_m_s(), [0.5, -1.5, 0.2]);
        // Leaving the limit takes only the error back, not the wind-up.
        i.add_clamped(0.5, [-1.0, 1.0, 0.0], [0.5, 1.5, 1.0]);
        assert_eq!(i.sum_m_s(), [0.0, -1.0, 0.2]);
    }

    #[test]
    fn the_norm_limit_keeps_the_direction() {
        let mut i = PositionIntegral::<2>::default();
        i.add_norm_limited(1.0, [3.0, 4.0], 10.0);
        assert_eq!(i.sum_m_s(), [3.0, 4.0]);
        i.add_norm_limited(1.0, [3.0, 4.0], 5.0);
        let s = Vector2::from(i.sum_m_s());
        assert!((s.norm() - 5.0).abs() < 1e-15, "{s}");
        assert!((s.x / s.y - 0.75).abs() < 1e-15, "{s}");
    }

    #[test]
    fn reset_forgets_the_time_base_and_set_keeps_it() {
        let mut i = PositionIntegral::<1>::default();
        i.integrate_clamped(0.0, [1.0], [10.0]);
        i.set_sum_m_s([2.0]);
        i.integrate_clamped(1.0, [1.0], [10.0]);
        assert_eq!(i.sum_m_s(), [3.0]);
        i.reset();
        assert_eq!(i, PositionIntegral::default());
        i.integrate_clamped(5.0, [1.0], [10.0]);
        assert_eq!(i.sum_m_s(), [0.0]);
    }
}
