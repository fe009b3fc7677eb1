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
