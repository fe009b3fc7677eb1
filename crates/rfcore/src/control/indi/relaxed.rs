//! INDI flying a relaxed hover (Mueller and D'Andrea, IJRR 2016): after a failure that leaves no
//! static hover, the vehicle spins at a constant rate about an axis `n` fixed in the body and
//! tilted from body z, and `n` points up.
//!
//! **Why the law needs it.** With yaw given up the law holds the thrust axis (body z) up and lets
//! the rotors' drag torque spin the vehicle; a vehicle with rotational damping (`k_r > 0`) settles
//! at the spin where the damping balances that torque. Without it (PX4's x500 as imported: `k_r =
//! 0`) nothing balances it: the spin grows linearly for as long as the vehicle flies (x500, rotor
//! 3 at 43 %: 6.4 rad/s^2, 160 rad/s 25 s after the failure). A steady spin `omega = r n` needs
//! the rotors' torque to equal the gyroscopic one, `tau = r^2 n x (J n)`, whose component along
//! `n` is zero; for `n = z` it is zero altogether, a static hover the failure excludes. Tilted,
//! `n x (J n) = (J_z - J_xy) n_z (n_y, -n_x, 0)` (principal `J`, `J_x = J_y`): the gyroscopic
//! torque carries a roll/pitch torque perpendicular to the tilt that grows with `r^2`, so the
//! rotors can hold the weight with the roll/pitch torque the failure forces on them and no yaw
//! torque left over. Tilted toward the failed rotor of a quadrotor when `J_z > J_xy` (Sun's
//! `axis_tilt` rule, [`crate::control::indi::IndiGains::primary_axis_tilt`]), that torque is the
//! one the weak rotor's diagonal makes.
//!
//! **What the law does with it** (from [`RelaxedSpin::time_s`] on): the reduced attitude holds
//! `n` (in place of the failure mode's primary axis) along the wanted thrust direction, and the
//! yaw row becomes a spin-rate row on `n . omega'`, `nu = k_spin (r* - n . omega)`, weighted
//! [`crate::control::indi::IndiGains::spin_weight`] (after thrust and reduced attitude). With
//! `r* = 0` the row slows the spin until the rotors cannot slow it further without giving up
//! thrust or attitude: the spin settles at the slowest relaxed hover the tilt allows (the
//! failure spins the vehicle up to it, the row holds it from above), bounded whatever the
//! vehicle's errors, which a relaxed hover designed on the nominal vehicle is not (x500, rotor 3
//! at 43 %: the nominal design at 40 % spins at 200 rad/s with 0.1 degrees of tilt, the run's
//! own vehicle at 37 rad/s with 4.4 degrees). With `r* > 0` the
//! gyroscopic torque depends on `r^2`: both spin directions are relaxed hovers (the rotors'
//! gyroscopic moment, small, breaks the tie), and the failure itself starts the vehicle spinning
//! one way, so `r*` takes the sign of the measured spin, latched once it passes
//! [`SPIN_LATCH_SHARE`] of `r*`: asking for the other direction would have the rotors stop and
//! reverse the spin they cannot stop.
//!
//! **Which side to tilt when two rotors are weak** ([`RelaxedSpin::choosing_the_weaker_of`]). Two
//! opposing rotors of a quadrotor that both lost thrust (partly, by amounts the law is not told)
//! leave a relaxed hover only when the weaker of them is the one tilted toward (`J_z > J_xy`): the
//! stronger then carries more than the weaker, the difference's roll/pitch torque is the
//! gyroscopic one, and the two pairs' drag torques even out. Tilted toward the stronger, the
//! rotors would need the weaker to carry more, which it cannot: the spin runs away (x500, two
//! opposing rotors at 54-77 % with thrust factors 0.8-1.0, the deciding campaign's draws: 6 of 6
//! held within 0.07 m and a spin of 7-11 rad/s tilted 0.06 toward the weaker, none tilted toward
//! the stronger, 41-61 rad/s of spin growth in 5 s). The law is told both rotors and the time; for
//! [`SPIN_AXIS_CHOICE_S`] from it, it flies the failure mode as without a spin axis and sums each
//! rotor's produced and commanded thrust; then it tilts toward the one whose produced / commanded
//! ratio is the lower (the given axis is the first's, its mirror `(-n_x, -n_y, n_z)` the
//! second's) and latches the choice. Without rotor thrust samples at any step of the
//! measurement the given axis is kept: the law's actuator model is the commands' own lag and
//! tells no weak rotor. The choice rests on the measured thrusts: the x500 draws that needed it
//! (the 16 certified survivable only by spinning, seed 0) differ by 5.3 % and more, measured
//! exactly in the campaign (its flights pass the true rotor thrusts); a rotor-speed sensor's
//! error averaged over the 0.25 s must stay well below that. That `spin_axis` tilts along the
//! first rotor's arm is the caller's to give: the law checks only that the two are opposite.

use nalgebra::Vector3;

use crate::error::{require_finite, Result, RfError};

/// The measured spin's sign is latched as the target's once `|n . omega|` passes this share of
/// `|r*|` (below it the target follows the measured sign, zero at zero).
pub const SPIN_LATCH_SHARE: f64 = 0.25;
/// Smallest `n_z` of the spin axis (oriented to body z): the thrust must lift along it.
pub const MIN_SPIN_AXIS_Z: f64 = 0.5;
/// How long the law measures two weak rotors before choosing which to tilt toward, s (module
/// docs): twenty rotor time constants of the x500 (0.0125 s), so the produced thrusts have
/// followed their commands, and short enough that the spin gained meanwhile stays small.
pub const SPIN_AXIS_CHOICE_S: f64 = 0.25;

/// A relaxed hover for the INDI law to fly from `time_s` on (module docs; with a choice between two
/// rotors, measured from `time_s` and flown from [`RelaxedSpin::flown_from_s`]): `spin_axis` in the body
/// frame (either orientation; normalised, oriented to positive z) and the spin rate about it, rad/s
/// (its magnitude is the target, 0 the slowest spin the rotors allow; the sign comes from the
/// flight).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxedSpin {
    time_s: f64,
    spin_axis: [f64; 3],
    spin_rate_rad_s: f64,
    /// Two rotors (0-based): fly the axis of the weaker as measured (module docs); the axis as
    /// given is the first's, its mirror the second's.
    weaker_of: Option<[usize; 2]>,
}

impl RelaxedSpin {
    /// Checked: finite values, a non-zero axis within `acos(MIN_SPIN_AXIS_Z)` of body z (either
    /// way; any finite scale, from subnormal to near `f64::MAX`); the spin rate's sign is ignored.
    pub fn new(time_s: f64, spin_axis: [f64; 3], spin_rate_rad_s: f64) -> Result<Self> {
        require_finite("spin_axis_time_s", time_s)?;
        for (i, v) in spin_axis.iter().enumerate() {
            require_finite(&format!("spin_axis[{i}]"), *v)?;
        }
        require_finite("spin_rate_rad_s", spin_rate_rad_s)?;
        // Scaled by its largest |component| when the squared norm leaves the normal range: that of
        // (0, 0, 1e300) overflows and that of (0, 0, 1e-200) underflows, though both are body z.
        // In range the axis is used as given (a unit-scale axis normalised exactly as before).
        let raw = Vector3::from(spin_axis);
        let squared = raw.norm_squared();
        let axis = if squared.is_finite() && squared >= f64::MIN_POSITIVE {
            raw
        } else {
            let largest = spin_axis.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if largest > 0.0 {
                raw / largest
            } else {
                raw
            }
        };
        let norm = axis.norm();
        if !(norm > 0.0) || axis.z.abs() < MIN_SPIN_AXIS_Z * norm {
            return Err(RfError::invalid(
                "spin_axis",
                format!(
                    "must be a non-zero axis whose z component is at least {MIN_SPIN_AXIS_Z} of \
                     its length (the thrust lifts along it), got {spin_axis:?}"
                ),
            ));
        }
        let unit = axis * (axis.z.signum() / norm);
        Ok(RelaxedSpin {
            time_s,
            spin_axis: [unit.x, unit.y, unit.z],
            spin_rate_rad_s: spin_rate_rad_s.abs(),
            weaker_of: None,
        })
    }

    /// This spin flown on the side of whichever of `rotors` (0-based, distinct) measures the
    /// weaker over [`SPIN_AXIS_CHOICE_S`] from its time (module docs): the axis as given when the
    /// first, its mirror `(-n_x, -n_y, n_z)` when the second. The rotors' count, placement
    /// (opposite each other) and failures are checked by the controller that flies it.
    pub fn choosing_the_weaker_of(mut self, rotors: [usize; 2]) -> Result<Self> {
        if rotors[0] == rotors[1] {
            return Err(RfError::invalid(
                "spin_axis_weaker_of",
                format!(
                    "must name two different rotors, got {} twice",
                    rotors[0] as u128 + 1
                ),
            ));
        }
        if self.spin_axis[0] == 0.0 && self.spin_axis[1] == 0.0 {
            return Err(RfError::invalid(
                "spin_axis_weaker_of",
                "needs a spin axis tilted from body z (its mirror is the other choice), got body z",
            ));
        }
        self.weaker_of = Some(rotors);
        Ok(self)
    }

    /// The two rotors the spin's side is chosen between (0-based), if it is.
    pub fn spin_axis_weaker_of(&self) -> Option<[usize; 2]> {
        self.weaker_of
    }

    /// From when the law flies the spin, s: its time, plus [`SPIN_AXIS_CHOICE_S`] when it
    /// chooses between two rotors first.
    pub fn flown_from_s(&self) -> f64 {
        match self.weaker_of {
            Some(_) => self.time_s + SPIN_AXIS_CHOICE_S,
            None => self.time_s,
        }
    }

    /// The second rotor's axis of [`RelaxedSpin::spin_axis_weaker_of`]: the mirror `(-n_x, -n_y, n_z)`.
    pub fn mirrored_axis(&self) -> Vector3<f64> {
        let [x, y, z] = self.spin_axis;
        Vector3::new(-x, -y, z)
    }

    /// The spin axis, unit, positive z.
    pub fn axis(&self) -> Vector3<f64> {
        Vector3::from(self.spin_axis)
    }

    /// From when the relaxed hover applies, s: flown from then, or, with a choice between two
    /// rotors, measured from then ([`RelaxedSpin::flown_from_s`]).
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The spin axis as given to [`RelaxedSpin::new`], normalised to unit length and positive z.
    pub fn spin_axis(&self) -> [f64; 3] {
        self.spin_axis
    }

    /// The target spin rate's magnitude, rad/s (0: the slowest spin the rotors allow).
    pub fn spin_rate_rad_s(&self) -> f64 {
        self.spin_rate_rad_s
    }

    /// The target spin rate about the axis, rad/s, for the measured `spin_rad_s`; `latched` keeps
    /// the chosen sign (0 until chosen).
    pub(super) fn target(&self, spin_rad_s: f64, latched: &mut f64) -> f64 {
        if *latched == 0.0
            && self.spin_rate_rad_s > 0.0
            && spin_rad_s.abs() >= SPIN_LATCH_SHARE * self.spin_rate_rad_s
        {
            *latched = spin_rad_s.signum();
        }
        let sign = if *latched != 0.0 {
            *latched
        } else if spin_rad_s == 0.0 {
            0.0
        } else {
            spin_rad_s.signum()
        };
        sign * self.spin_rate_rad_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_axis_is_normalised_to_positive_z_and_bad_values_name_their_field() {
        let s = RelaxedSpin::new(1.0, [0.0, 0.6, -0.8], -30.0).unwrap();
        assert!((s.axis() - Vector3::new(0.0, -0.6, 0.8)).norm() < 1e-15);
        assert_eq!(s.spin_rate_rad_s(), 30.0);
        assert_eq!(s.time_s(), 1.0);
        // Far from unit length either way (the plain norm overflows or underflows): body z.
        for z in [1e300, -1e300, 1e-200, f64::MAX, 5e-324] {
            let s = RelaxedSpin::new(0.0, [0.0, 0.0, z], 1.0).unwrap();
            assert_eq!(s.spin_axis(), [0.0, 0.0, 1.0], "{z}");
        }
        let big = RelaxedSpin::new(0.0, [3e300, 0.0, 4e300], 1.0).unwrap();
        assert!((big.axis() - Vector3::new(0.6, 0.0, 0.8)).norm() < 1e-15);
        for (args, field) in [
            ((f64::NAN, [0.0, 0.0, 1.0], 1.0), "spin_axis_time_s"),
            ((0.0, [0.0, 0.0, 0.0], 1.0), "spin_axis"),
            ((0.0, [1e300, 0.0, 1e299], 1.0), "spin_axis"),
            ((0.0, [1.0, 0.0, 0.4], 1.0), "spin_axis"),
            ((0.0, [0.0, f64::INFINITY, 1.0], 1.0), "spin_axis[1]"),
            ((0.0, [0.0, 0.0, 1.0], f64::NAN), "spin_rate_rad_s"),
        ] {
            let err = RelaxedSpin::new(args.0, args.1, args.2)
                .unwrap_err()
                .to_string();
            assert!(err.contains(field), "{err}");
        }
    }

    #[test]
    fn the_target_follows_the_measured_sign_until_latched() {
        let s = RelaxedSpin::new(0.0, [0.0, 0.0, 1.0], 40.0).unwrap();
        let mut latched = 0.0;
        assert_eq!(s.target(0.0, &mut latched), 0.0);
        assert_eq!(s.target(-1.0, &mut latched), -40.0);
        assert_eq!(s.target(2.0, &mut latched), 40.0);
        assert_eq!(latched, 0.0);
        assert_eq!(s.target(-10.0, &mut latched), -40.0);
        assert_eq!(latched, -1.0);
        assert_eq!(s.target(5.0, &mut latched), -40.0);
        let slowest = RelaxedSpin::new(0.0, [0.0, 0.0, 1.0], 0.0).unwrap();
        assert_eq!(slowest.target(30.0, &mut latched), 0.0);
    }
}
