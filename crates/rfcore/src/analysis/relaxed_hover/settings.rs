//! The settings of the relaxed hover analysis: the vehicle's rotor parameters the airframe does
//! not hold, and how hard the search looks (own file: every step of the search reads them).

use crate::error::{require_scale, require_scale_or_zero, Result, RfError};

/// What the analysis needs beyond the airframe, and how hard it looks. The first three are the
/// simulator's (`Drag::rotational_drag_n_m_s`, `Drag::rotor_inertia_kg_m2`,
/// `FixedPitch::thrust_coefficient_n_s2`): pass the values the vehicle is flown with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RelaxedHoverSettings {
    /// `k_r`: aerodynamic rotational damping, torque `-k_r omega` (N m s). Default 0.
    pub rotational_drag_n_m_s: f64,
    /// `I_R`: rotor and propeller inertia about its axis (kg m^2). Default 0 (no gyroscopic
    /// moment).
    pub rotor_inertia_kg_m2: f64,
    /// `k_f` in `f = k_f omega_rotor^2` (N s^2): the rotor speed behind the gyroscopic moment.
    /// Needed (> 0) when `rotor_inertia_kg_m2 > 0`. Default 0.
    pub thrust_coefficient_n_s2: f64,
    /// Largest spin rate searched (rad/s). Default 200, the simulator's body-rate limit.
    pub max_spin_rate_rad_s: f64,
    /// Largest circle the centre of mass may describe (m): a relaxed hover stays substantially
    /// in one place. Default 0.1; `inf` for no limit.
    pub max_circle_radius_m: f64,
    /// Largest number of working rotors held at their lower bound (idle) in a branch. Default 2.
    pub max_idle_rotors: usize,
    /// Points per side of the spin-axis grid (odd, 11 to 401). Default 61.
    pub grid_points: usize,
}

impl Default for RelaxedHoverSettings {
    fn default() -> Self {
        RelaxedHoverSettings {
            rotational_drag_n_m_s: 0.0,
            rotor_inertia_kg_m2: 0.0,
            thrust_coefficient_n_s2: 0.0,
            max_spin_rate_rad_s: 200.0,
            max_circle_radius_m: 0.1,
            max_idle_rotors: 2,
            grid_points: 61,
        }
    }
}

impl RelaxedHoverSettings {
    pub fn check(&self) -> Result<()> {
        // Divided by (k_r in the spin rate, k_f in the rotor speed): zero or a scale (error.rs).
        require_scale_or_zero("rotational_drag_n_m_s", self.rotational_drag_n_m_s, "N m s")?;
        require_scale_or_zero("rotor_inertia_kg_m2", self.rotor_inertia_kg_m2, "kg m^2")?;
        require_scale_or_zero("thrust_coefficient_n_s2", self.thrust_coefficient_n_s2, "N s^2")?;
        if self.rotor_inertia_kg_m2 > 0.0 && self.thrust_coefficient_n_s2 == 0.0 {
            return Err(RfError::invalid(
                "thrust_coefficient_n_s2",
                "must be > 0 when rotor_inertia_kg_m2 > 0 (the gyroscopic moment needs the rotor \
                 speed sqrt(f / k_f))",
            ));
        }
        require_scale("max_spin_rate_rad_s", self.max_spin_rate_rad_s, "rad/s")?;
        let r = self.max_circle_radius_m;
        if r.is_nan() || r <= 0.0 {
            return Err(RfError::invalid(
                "max_circle_radius_m",
                format!("must be > 0 (inf for no limit), got {r}"),
            ));
        }
        let g = self.grid_points;
        if !(11..=401).contains(&g) || g.is_multiple_of(2) {
            return Err(RfError::invalid(
                "grid_points",
                format!("must be odd and in [11, 401], got {g}"),
            ));
        }
        Ok(())
    }
}
