//! When a sensor samples: its own clock, `t_k = k / rate_hz` from time 0, independent of the
//! control period. The simulator hands a sensor the true state at each of its sample times (exact
//! when the time falls on the integration grid, the latest grid state otherwise: sample-and-hold),
//! so any rate works with any control period; none has to divide another.

/// Fraction of a period by which a time computed as `k / rate_hz` may fall short of the grid
/// point it stands for (rounding) and still count as on it: when a sample is due, and which fusion
/// slot a fix belongs to (`crate::flight::estimation`).
pub const PERIOD_TOLERANCE: f64 = 1e-6;

/// Sample times `k / rate_hz`, k = 0, 1, 2, ... (computed from k, so they never drift).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleClock {
    rate_hz: f64,
    next_index: u64,
    /// `next_index / rate_hz` and the due tolerance, kept so that the simulator's many "which
    /// sensor is next" questions per sample cost no division.
    next_time_s: f64,
    due_tolerance_s: f64,
}

impl SampleClock {
    /// A clock at `rate_hz` (finite and > 0, checked by the sensor's profile).
    pub fn new(rate_hz: f64) -> Self {
        SampleClock {
            rate_hz,
            next_index: 0,
            next_time_s: 0.0,
            due_tolerance_s: PERIOD_TOLERANCE * (1.0 / rate_hz),
        }
    }

    pub fn rate_hz(&self) -> f64 {
        self.rate_hz
    }

    pub fn period_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// The time of the next sample, s.
    #[inline]
    pub fn next_time_s(&self) -> f64 {
        self.next_time_s
    }

    /// `true` when the next sample is due at or before `t_s`. A sample within a millionth of a
    /// period after `t_s` counts as due, so a simulator time `k dt` that rounds just below a
    /// sample time `j / rate` still takes that sample.
    #[inline]
    pub fn is_due(&self, t_s: f64) -> bool {
        self.next_time_s <= t_s + self.due_tolerance_s
    }

    /// The time of the first sample from the next one on at or after `t_s` (finite, >= 0), s:
    /// `k / rate_hz` as [`SampleClock::tick`] will give it; inf for a time that is not finite.
    pub fn first_at_or_after(&self, t_s: f64) -> f64 {
        // No sample lies at or after a time that is not finite (NaN, inf): answer inf rather than
        // count ticks forever.
        if !t_s.is_finite() {
            return f64::INFINITY;
        }
        // From one sample below the estimate up: the product's rounding is then on the safe side.
        // `as u64` truncates towards zero and saturates negatives at 0, which for a finite
        // product is `floor` followed by the same cast (libm's `floor` is a call: about 0.4 % of
        // a sensed Ke batch, two clock checks per tape node).
        let mut k = ((t_s * self.rate_hz) as u64)
            .saturating_sub(1)
            .max(self.next_index);
        loop {
            let x = k as f64 / self.rate_hz;
            if x >= t_s {
                return x;
            }
            k += 1;
        }
    }

    /// `true` when a sample from the next one on falls in `[from_s, to_s)`.
    #[inline]
    pub fn has_sample_in(&self, from_s: f64, to_s: f64) -> bool {
        self.next_time_s < to_s && self.first_at_or_after(from_s) < to_s
    }

    /// `true` when a sample from the next one on at or after `t_s` counts as due at `t_s`
    /// ([`SampleClock::is_due`]: within a millionth of a period after it).
    #[inline]
    pub fn has_due_sample_at_or_after(&self, t_s: f64) -> bool {
        self.first_at_or_after(t_s) <= t_s + self.due_tolerance_s
    }

    /// The time of the sample being taken now; the clock moves to the next one.
    pub fn tick(&mut self) -> f64 {
        let t = self.next_time_s;
        self.next_index += 1;
        self.next_time_s = self.next_index as f64 / self.rate_hz;
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn times_are_exact_multiples_and_due_with_rounding() {
        let mut clock = SampleClock::new(240.0);
        for k in 0..1000u64 {
            assert_eq!(clock.tick(), k as f64 / 240.0);
        }
        // 400 Hz control steps: step k at k * (1/400) is due for every sample j/240 <= k/400.
        let mut clock = SampleClock::new(240.0);
        let dt = 1.0 / 400.0;
        let mut taken = 0;
        for k in 0..=400 {
            let t = k as f64 * dt;
            while clock.is_due(t) {
                clock.tick();
                taken += 1;
            }
        }
        // Samples at 0, 1/240, ..., 1 s: 241 of them in [0, 1].
        assert_eq!(taken, 241);
    }

    #[test]
    fn a_time_that_is_not_finite_has_no_sample_after_it() {
        let clock = SampleClock::new(240.0);
        for t in [f64::NAN, f64::INFINITY] {
            assert_eq!(clock.first_at_or_after(t), f64::INFINITY);
        }
        assert_eq!(clock.first_at_or_after(f64::NEG_INFINITY), f64::INFINITY);
    }

    #[test]
    fn the_truncating_cast_is_floor_for_every_finite_product() {
        // `first_at_or_after`'s estimate casts without `floor`: the same index for negatives
        // (both saturate at 0), fractions, whole numbers, and products beyond u64.
        for x in [
            -1e300f64, -3.5, -1.0, -0.5, -0.0, 0.0, 1e-310, 0.5, 1.0, 2.999_999_999_999_999_6, 3.0,
            1e15 + 0.5, 1.8e19, 1e300,
        ] {
            assert_eq!(x as u64, x.floor() as u64, "{x}");
        }
    }

    #[test]
    fn sample_windows_agree_with_the_ticks() {
        // Against the ticked times themselves, on 400 Hz control steps cut in 4 substeps.
        for rate in [240.0, 500.0, 1000.0, 333.0] {
            let mut clock = SampleClock::new(rate);
            clock.tick();
            let times: Vec<f64> = {
                let mut c = clock;
                (0..2000).map(|_| c.tick()).collect()
            };
            let h = 1.0 / 1600.0;
            for k in 0..1000 {
                let (a, b) = (k as f64 * h, (k + 1) as f64 * h);
                let expected = times.iter().any(|&x| a <= x && x < b);
                assert_eq!(clock.has_sample_in(a, b), expected, "{rate} {k}");
                let due = times
                    .iter()
                    .any(|&x| x >= b && x <= b + PERIOD_TOLERANCE * (1.0 / rate));
                assert_eq!(clock.has_due_sample_at_or_after(b), due, "{rate} {k}");
                let first = times.iter().copied().find(|&x| x >= a).unwrap();
                assert_eq!(clock.first_at_or_after(a), first);
            }
        }
    }
}
