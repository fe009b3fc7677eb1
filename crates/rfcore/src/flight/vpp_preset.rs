//! A variable-pitch vehicle preset file (`presets/vpp/*.toml`): read by Rust tests and Python
//! through this one parser, and turned into the actuator model it describes.

use serde::Deserialize;

use super::actuator::{Lag, VariablePitch, VariablePitchLags};
use crate::airframe::Airframe;
use crate::error::{require_non_negative, Result, RfError};

/// A variable-pitch vehicle preset (`presets/vpp/*.toml`): the airframe preset it flies, the
/// propeller model (Wang et al. eq. (3)) with its bounds and the two channels' lags, and the
/// drag the paper does not give. Read by Rust tests and Python through this one parser.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VariablePitchPreset {
    pub name: String,
    pub description: String,
    pub source: String,
    /// Name of the airframe preset (geometry, mass, inertia, the bidirectional thrust box).
    pub airframe: String,
    /// `k1..k4` of eq. (3), in the paper's speed unit.
    pub coefficients: [f64; 4],
    pub speed_bounds: (f64, f64),
    pub pitch_bounds: (f64, f64),
    /// Speed unit to rad/s for the gyroscopic moment (0: not modelled).
    pub speed_to_rad_s: f64,
    pub speed_time_constant_s: f64,
    pub speed_rate_limit_per_s: f64,
    pub pitch_time_constant_s: f64,
    pub pitch_rate_limit_rad_s: f64,
    /// Linear translational drag `d_x = d_y = d_z` of eq. (1), N s/m.
    pub linear_drag_n_s_m: f64,
}

impl VariablePitchPreset {
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let preset: VariablePitchPreset = toml::from_str(text).map_err(|e| RfError::Parse {
            origin: origin.to_string(),
            message: e.to_string(),
        })?;
        preset.lags().check()?;
        require_non_negative("linear_drag_n_s_m", preset.linear_drag_n_s_m)?;
        Ok(preset)
    }

    pub fn lags(&self) -> VariablePitchLags {
        VariablePitchLags {
            speed: Lag {
                time_constant_s: self.speed_time_constant_s,
                rate_limit_per_s: self.speed_rate_limit_per_s,
            },
            pitch: Lag {
                time_constant_s: self.pitch_time_constant_s,
                rate_limit_per_s: self.pitch_rate_limit_rad_s,
            },
        }
    }

    /// The actuator model on `airframe` (the preset's own airframe preset).
    pub fn actuator(&self, airframe: &Airframe) -> Result<VariablePitch> {
        VariablePitch::new(
            airframe,
            self.coefficients,
            self.speed_bounds,
            self.pitch_bounds,
            self.speed_to_rad_s,
            self.lags(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flight::actuator::Actuators;

    #[test]
    fn wang_preset_parses_and_holds_the_papers_numbers() {
        let text = crate::fixtures::preset_text("vpp/wang.toml");
        let preset = VariablePitchPreset::from_toml_str(&text, "wang").unwrap();
        assert_eq!(preset.coefficients, [5e-7, 1e-8, 2e-10, 4e-7]);
        assert_eq!(preset.speed_bounds, (0.0, 10_000.0));
        assert_eq!(preset.pitch_bounds, (-0.26, 0.26));
        assert_eq!(preset.lags(), VariablePitchLags::default());
        let airframe = crate::fixtures::preset(&preset.airframe);
        assert_eq!(airframe.mass_kg(), 1.0);
        assert_eq!(airframe.gravity_m_s2(), 10.0);
        // The thrust box is the propeller's: k1 omega_max^2 alpha_max = 13 N either way.
        let actuator = preset.actuator(&airframe).unwrap();
        let mut rotors = Actuators::VariablePitch(actuator);
        rotors.settle(&[[10_000.0, 0.26]; 4].concat()).unwrap();
        let most = rotors.output(0, 1.0).thrust_n;
        assert!((most - airframe.max_thrust_n()[0]).abs() < 1e-12, "{most}");
        assert!((airframe.min_thrust_n()[0] + most).abs() < 1e-12);
        let bad = text.replace("linear_drag_n_s_m = 0.25", "linear_drag_n_s_m = -1");
        let err = VariablePitchPreset::from_toml_str(&bad, "wang").unwrap_err();
        assert!(err.to_string().starts_with("linear_drag_n_s_m"), "{err}");
        let unknown = format!("{text}\nextra = 1\n");
        assert!(VariablePitchPreset::from_toml_str(&unknown, "wang").is_err());
    }
}
