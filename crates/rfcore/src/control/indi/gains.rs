//! The INDI controller's parameters ([`IndiGains`], with Sun's printed values as defaults) and
//! whether it holds yaw ([`YawMode`]).

use crate::error::{require_finite, Result, RfError};

/// Whether the controller holds the yaw rate (module docs, "When rotors fail").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum YawMode {
    /// Hold it while the remaining rotors have the yaw authority ([`IndiGains::min_yaw_authority`]),
    /// give it up otherwise; while held, it yields to thrust and attitude once the rotors saturate
    /// or cannot meet every weighted axis (its weight drops to [`IndiGains::given_up_yaw_weight`],
    /// module docs step 5).
    #[default]
    Auto,
    /// Always hold the yaw rate (with the weight `weights[3]`).
    Hold,
    /// Always let it go (spin about the primary axis).
    GiveUp,
}

impl YawMode {
    pub fn parse(text: &str) -> Result<Self> {
        match text {
            "auto" => Ok(YawMode::Auto),
            "hold" => Ok(YawMode::Hold),
            "give-up" => Ok(YawMode::GiveUp),
            other => Err(RfError::invalid(
                "yaw",
                format!("expected \"auto\", \"hold\" or \"give-up\", got {other:?}"),
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            YawMode::Auto => "auto",
            YawMode::Hold => "hold",
            YawMode::GiveUp => "give-up",
        }
    }
}

/// The controller's parameters. Defaults: Sun's printed values (`controlParams.m`) where he prints
/// them, else stated on the field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IndiGains {
    /// Horizontal position gain, 1/s (Sun: 1.0).
    pub k_p_xy: f64,
    /// Horizontal velocity gain, 1/s (Sun: 2.0).
    pub k_v_xy: f64,
    /// Horizontal velocity-integral gain, 1/s^2 (Sun: 0.0).
    pub k_i_xy: f64,
    /// Altitude gain of `nu_z`, 1/s^2 (Sun: 10).
    pub k_p_z: f64,
    /// Vertical-speed gain of `nu_z`, 1/s (Sun: 6).
    pub k_d_z: f64,
    /// Largest horizontal speed the position loop asks for, m/s (Sun: 10).
    pub max_speed_m_s: f64,
    /// Largest tilt of the thrust direction the position loop asks for, rad (Sun: 10 degrees).
    pub max_tilt_rad: f64,
    /// Largest vertical acceleration `|nu_z|` the position loop asks for, m/s^2: 5 (ours; Sun's
    /// code has none, and a demand beyond `g` downward would turn the thrust direction over: 1 m
    /// above the setpoint, `k_p,z = 10` asks for 10 m/s^2).
    pub max_vertical_accel_m_s2: f64,
    /// Limit on each horizontal velocity integral, m (Sun: 5).
    pub integral_limit_m: f64,
    /// Reduced-attitude proportional gain, 1/s^2 (Sun: 200).
    pub k_att_p: f64,
    /// Reduced-attitude derivative gain, 1/s (Sun: 30).
    pub k_att_d: f64,
    /// Yaw-rate gain, 1/s (Sun: 5).
    pub k_r: f64,
    /// Natural frequency of the second-order filter, rad/s: 50, the bandwidth of Sun's first-order
    /// filter (`t_indi = 0.02 s`, `controlParams.m`; module docs, "Filter and inertia coupling").
    pub filter_frequency_rad_s: f64,
    /// Damping ratio of the filter: 0.55 (Smeur et al. 2016).
    pub filter_damping: f64,
    /// Take the inertia coupling `-J^-1 (omega x J omega)` from the model at the current rate
    /// instead of through the filtered gyro (module docs, step 4): true (ours; Sun leaves it to the
    /// filter, false).
    pub model_coupling: bool,
    /// `delta` of the output redefinition with one torque axis left, rad (module docs): 65.67
    /// degrees, Sun's `chi = 105 deg` on his vehicle. Must lie in (0, pi/2).
    pub output_angle_rad: f64,
    /// Tilt of the primary axis from body z when one rotor of a quadrotor fails (Sun's
    /// `axis_tilt`, 0 to 0.2; his code: 0): `n_xy` of this length, toward the failed rotor when
    /// `J_z > J_xy` (the gyroscopic torque of the tilted spin then lets the opposite rotor carry
    /// thrust), away from it otherwise.
    pub primary_axis_tilt: f64,
    /// Tilt of the primary axis from body z when yaw is given up on a vehicle with spare rotors
    /// (more than the thrust and attitude rows use: a hexa- or octocopter) and no yaw-free hover is
    /// within their reach: `n_xy` of this length, toward the direction whose gyroscopic torque in
    /// the tilted spin most relieves the yaw torque the hover cannot avoid (module docs, "When
    /// rotors fail"). 0 (Sun's law: the vehicle spins about body z until the drag meets that yaw
    /// torque). Must lie in [0, 1). A relaxed spin's given axis
    /// ([`crate::control::indi::IndiController::with_relaxed_spin`]) takes precedence over this
    /// tilt from its time on.
    pub given_up_yaw_axis_tilt: f64,
    /// `W = diag(thrust, attitude 1, attitude 2, yaw)` of the incremental allocation (Sun: the
    /// unweighted pseudo-inverse, all 1).
    pub weights: [f64; 4],
    /// Time constant of the thrust-mismatch correction, s (ours; infinity turns it off): the slow
    /// low-pass of (previous command - produced thrust) added to the incremental base, so that a
    /// rotor producing less than commanded (an undetected partial loss, a thrust-coefficient
    /// error) leaves no steady output error (module docs, "The incremental base"). 0.5.
    pub mismatch_time_constant_s: f64,
    /// Time constant of the actuator model that stands in for the rotor samples when a step has
    /// none (the previous command through a first-order lag), s: 0.025 (Ke's Table III rotor lag;
    /// ours). 0: the previous command itself.
    pub actuator_time_constant_s: f64,
    /// The yaw weight once yaw is given up, in place of `weights[3]`, when more rotors remain than
    /// the thrust and attitude rows use (a hexa- or octocopter): their spare authority still damps
    /// the spin, after thrust and attitude. Otherwise (a quadrotor) the row is dropped, weight 0, as
    /// Sun does. 1e-4 (ours): the PPNNPN hexacopter without rotor 5 then spins at 33 rad/s, within
    /// a 2000 deg/s gyro's range, instead of 79 rad/s with weight 0, for 5 mm of altitude; a larger
    /// weight trades more altitude for yaw (1e-3: 5 cm, 1e-2: 0.41 m; `tests/test_indi.py`).
    pub given_up_yaw_weight: f64,
    /// Whether yaw is held (module docs).
    pub yaw: YawMode,
    /// [`YawMode::Auto`] holds yaw when the remaining rotors can make at least this fraction of
    /// the healthy vehicle's yaw torque at hover, in both directions: 0.1 (ours; Sun's quadrotor
    /// cases give yaw up whatever the fraction).
    pub min_yaw_authority: f64,
    /// Gain of the spin-rate loop while a relaxed hover is flown
    /// ([`crate::control::indi::RelaxedSpin`]), 1/s: the spin acceleration about the spin axis
    /// asked is `k_spin (r* - r)`. 1.0 (ours): a vehicle without rotational drag has only its
    /// rotors' drag torque to spin up with, a few rad/s^2 on PX4's x500, so a faster loop only
    /// saturates.
    pub k_spin: f64,
    /// Weight of that spin row in the incremental allocation, in place of the yaw row's: below
    /// thrust and reduced attitude (weight 1), so the spin rate gives way when the rotors cannot
    /// meet every row. 0.01 (ours).
    pub spin_weight: f64,
}

impl Default for IndiGains {
    fn default() -> Self {
        IndiGains {
            k_p_xy: 1.0,
            k_v_xy: 2.0,
            k_i_xy: 0.0,
            k_p_z: 10.0,
            k_d_z: 6.0,
            max_speed_m_s: 10.0,
            max_tilt_rad: 10f64.to_radians(),
            max_vertical_accel_m_s2: 5.0,
            integral_limit_m: 5.0,
            k_att_p: 200.0,
            k_att_d: 30.0,
            k_r: 5.0,
            filter_frequency_rad_s: 50.0,
            filter_damping: 0.55,
            model_coupling: true,
            output_angle_rad: sun_output_angle_rad(),
            primary_axis_tilt: 0.0,
            given_up_yaw_axis_tilt: 0.0,
            weights: [1.0; 4],
            mismatch_time_constant_s: 0.5,
            actuator_time_constant_s: 0.025,
            given_up_yaw_weight: 1e-4,
            yaw: YawMode::Auto,
            min_yaw_authority: 0.1,
            k_spin: 1.0,
            spin_weight: 0.01,
        }
    }
}

/// Sun's `chi = 105 deg` as the angle [`IndiGains::output_angle_rad`]: on his Bebop 2 (`b =
/// 0.115 m`, `l = 0.0875 m`, `I_x = 0.0014`, `I_y = 0.0013 kg m^2`, `controlParams.m`) the
/// remaining pair 1-3 makes angular acceleration along `atan2(l / I_y, b / I_x)` in the body x-y
/// plane, and `chi` is measured from body x: `delta = chi - that`.
pub fn sun_output_angle_rad() -> f64 {
    let (b, l, ix, iy): (f64, f64, f64, f64) = (0.115, 0.0875, 0.0014, 0.0013);
    105f64.to_radians() - (l / iy).atan2(b / ix)
}

impl IndiGains {
    /// Rejects gains the law excludes, naming the gain and the rule.
    pub fn check(&self) -> Result<()> {
        let positive = [
            ("k_p_xy", self.k_p_xy),
            ("k_v_xy", self.k_v_xy),
            ("k_p_z", self.k_p_z),
            ("k_d_z", self.k_d_z),
            ("max_speed_m_s", self.max_speed_m_s),
            ("max_vertical_accel_m_s2", self.max_vertical_accel_m_s2),
            ("k_att_p", self.k_att_p),
            ("k_att_d", self.k_att_d),
            ("filter_frequency_rad_s", self.filter_frequency_rad_s),
            ("filter_damping", self.filter_damping),
            ("mismatch_time_constant_s", self.mismatch_time_constant_s),
        ];
        for (field, value) in positive {
            if field == "mismatch_time_constant_s" && value == f64::INFINITY {
                continue; // off
            }
            require_finite(field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        for (field, value) in [
            ("k_i_xy", self.k_i_xy),
            ("k_r", self.k_r),
            ("k_spin", self.k_spin),
            ("spin_weight", self.spin_weight),
            ("given_up_yaw_weight", self.given_up_yaw_weight),
            ("actuator_time_constant_s", self.actuator_time_constant_s),
            ("integral_limit_m", self.integral_limit_m),
        ] {
            require_finite(field, value)?;
            if value < 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be >= 0, got {value}"),
                ));
            }
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        for (field, value) in [
            ("max_tilt_rad", self.max_tilt_rad),
            ("output_angle_rad", self.output_angle_rad),
        ] {
            require_finite(field, value)?;
            if !(value > 0.0 && value < half_pi) {
                return Err(RfError::invalid(
                    field,
                    format!("must lie in (0, pi/2), got {value}"),
                ));
            }
        }
        for (field, value) in [
            ("primary_axis_tilt", self.primary_axis_tilt),
            ("given_up_yaw_axis_tilt", self.given_up_yaw_axis_tilt),
        ] {
            require_finite(field, value)?;
            if !(0.0..1.0).contains(&value) {
                return Err(RfError::invalid(
                    field,
                    format!("must lie in [0, 1) (the x-y length of a unit axis), got {value}"),
                ));
            }
        }
        require_finite("min_yaw_authority", self.min_yaw_authority)?;
        if !(0.0..=1.0).contains(&self.min_yaw_authority) {
            return Err(RfError::invalid(
                "min_yaw_authority",
                format!(
                    "must lie in [0, 1] (a fraction of the healthy yaw torque), got {}",
                    self.min_yaw_authority
                ),
            ));
        }
        for (i, &w) in self.weights.iter().enumerate() {
            require_finite(&format!("weights[{i}]"), w)?;
            if w < 0.0 || (i < 3 && w == 0.0) {
                return Err(RfError::invalid(
                    format!("weights[{i}]"),
                    format!(
                        "thrust and attitude weights must be > 0 and the yaw weight >= 0, got {w}"
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::airframe::Airframe;

    #[test]
    fn the_defaults_pass_and_every_rule_names_its_gain() {
        IndiGains::default().check().unwrap();
        type Set = fn(&mut IndiGains, f64);
        let cases: [(&str, Set, f64); 28] = [
            ("k_p_xy", |g, v| g.k_p_xy = v, 0.0),
            ("k_v_xy", |g, v| g.k_v_xy = v, -1.0),
            ("k_i_xy", |g, v| g.k_i_xy = v, -0.1),
            ("k_p_z", |g, v| g.k_p_z = v, 0.0),
            ("k_d_z", |g, v| g.k_d_z = v, f64::NAN),
            ("max_speed_m_s", |g, v| g.max_speed_m_s = v, 0.0),
            (
                "max_vertical_accel_m_s2",
                |g, v| g.max_vertical_accel_m_s2 = v,
                0.0,
            ),
            ("max_tilt_rad", |g, v| g.max_tilt_rad = v, 1.6),
            ("max_tilt_rad", |g, v| g.max_tilt_rad = v, 0.0),
            ("integral_limit_m", |g, v| g.integral_limit_m = v, -1.0),
            ("k_att_p", |g, v| g.k_att_p = v, 0.0),
            ("k_att_d", |g, v| g.k_att_d = v, f64::INFINITY),
            ("k_r", |g, v| g.k_r = v, -5.0),
            ("k_spin", |g, v| g.k_spin = v, -1.0),
            ("spin_weight", |g, v| g.spin_weight = v, f64::NAN),
            (
                "filter_frequency_rad_s",
                |g, v| g.filter_frequency_rad_s = v,
                0.0,
            ),
            ("filter_damping", |g, v| g.filter_damping = v, -0.5),
            ("output_angle_rad", |g, v| g.output_angle_rad = v, 0.0),
            (
                "output_angle_rad",
                |g, v| g.output_angle_rad = v,
                std::f64::consts::FRAC_PI_2,
            ),
            ("primary_axis_tilt", |g, v| g.primary_axis_tilt = v, 1.0),
            (
                "given_up_yaw_axis_tilt",
                |g, v| g.given_up_yaw_axis_tilt = v,
                -0.1,
            ),
            (
                "given_up_yaw_axis_tilt",
                |g, v| g.given_up_yaw_axis_tilt = v,
                f64::NAN,
            ),
            (
                "mismatch_time_constant_s",
                |g, v| g.mismatch_time_constant_s = v,
                0.0,
            ),
            (
                "given_up_yaw_weight",
                |g, v| g.given_up_yaw_weight = v,
                -1e-4,
            ),
            ("min_yaw_authority", |g, v| g.min_yaw_authority = v, 1.5),
            (
                "actuator_time_constant_s",
                |g, v| g.actuator_time_constant_s = v,
                -0.01,
            ),
            ("weights[1]", |g, v| g.weights[1] = v, 0.0),
            ("weights[3]", |g, v| g.weights[3] = v, -1.0),
        ];
        for (field, set, value) in cases {
            let mut gains = IndiGains::default();
            set(&mut gains, value);
            let err = gains.check().unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("{field}:")),
                "{field} = {value}: {err}"
            );
        }
        // Infinity turns the mismatch correction off; a zero yaw weight is Sun's row elimination.
        let gains = IndiGains {
            mismatch_time_constant_s: f64::INFINITY,
            given_up_yaw_weight: 0.0,
            ..IndiGains::default()
        };
        gains.check().unwrap();
        assert_eq!(YawMode::parse("give-up").unwrap(), YawMode::GiveUp);
        for mode in [YawMode::Auto, YawMode::Hold, YawMode::GiveUp] {
            assert_eq!(YawMode::parse(mode.name()).unwrap(), mode);
        }
        assert!(YawMode::parse("spin")
            .unwrap_err()
            .to_string()
            .starts_with("yaw:"));
    }

    #[test]
    fn suns_chi_is_the_angle_from_the_remaining_pairs_angular_acceleration() {
        // Sun's Bebop 2 (controlParams.m): rotor 1 front left at (l, -b), 2 front right, 3 rear
        // right, 4 rear left; rotors 2 and 4 failed leave the pair 1-3, chi = 105 degrees from body x.
        let (b, l) = (0.115, 0.0875);
        let (ix, iy, iz) = (0.0014, 0.0013, 0.0025);
        let positions = [(l, -b), (l, b), (-l, b), (-l, -b)];
        let angles: Vec<f64> = positions
            .iter()
            .map(|(x, y): &(f64, f64)| y.atan2(*x))
            .collect();
        let arm = (b * b + l * l).sqrt();
        let bebop = Airframe::from_columns(
            "bebop-2",
            &angles,
            &[arm; 4],
            &[1.0, -1.0, 1.0, -1.0],
            &[3.0; 4],
            &[0.0; 4],
            &[1.0; 4],
            0.375,
            &[ix, iy, iz],
            0.01,
            9.81,
        )
        .unwrap();
        let m = bebop.nominal_effectiveness_matrix();
        let (wx, wy) = (m[(1, 0)] / ix, m[(2, 0)] / iy);
        let chi = 105f64.to_radians();
        // The angle between the two directions, from their dot and cross products.
        let delta = (wx * chi.sin() - wy * chi.cos()).atan2(wx * chi.cos() + wy * chi.sin());
        assert!((delta - sun_output_angle_rad()).abs() < 1e-12, "{delta}");
        assert!((sun_output_angle_rad().to_degrees() - 65.67).abs() < 0.005);
        assert_eq!(
            IndiGains::default().output_angle_rad,
            sun_output_angle_rad()
        );
    }

    #[test]
    fn the_default_filter_has_the_bandwidth_of_suns_first_order_filter() {
        let g = IndiGains::default();
        assert_eq!(g.filter_frequency_rad_s, 1.0 / 0.02);
        // |H(j w_n)| = 1 / (2 zeta): the second-order filter's gain at Sun's 3 dB frequency.
        assert!((1.0 / (2.0 * g.filter_damping) - 0.909).abs() < 1e-3);
    }
}
