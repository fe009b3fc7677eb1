//! The multirotor airframe: rotor geometry, thrust limits, efficiency, mass properties.
//!
//! # Frame convention (one for the whole project)
//! Body frame FRD: x forward, y right, z down (Ke et al.'s body frame). Rotor i sits in the body
//! x-y plane at arm angle `phi_i` measured from body x towards body y, at distance `r_i` from the
//! centre of mass, and pushes along -z (up). Its thrust f_i then produces the roll torque
//! `L = -r_i sin(phi_i) f_i` and the pitch torque `M = r_i cos(phi_i) f_i`: exactly the rows of
//! Du et al. eq. (5). The reaction (drag) torque is `N = w_i k_mu f_i`, with `w_i = +1` for a rotor
//! spinning anticlockwise seen from above and `-1` clockwise (Du eq. (6)); in Du's eq. (17) a "P"
//! rotor is clockwise. Papers written in other frames (Lanzon: z up) are converted in their
//! preset files, which say how.

use nalgebra::DMatrix;
use serde::Deserialize;

use crate::error::{require_finite, require_len, Result, RfError};

/// Standard gravity used when an airframe does not give its own (m/s^2).
pub const DEFAULT_GRAVITY_M_S2: f64 = 9.81;

/// Rotor spin direction seen from above.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpinDirection {
    Clockwise,
    Anticlockwise,
}

impl SpinDirection {
    /// `w_i` of Du eq. (6): +1 anticlockwise, -1 clockwise.
    pub fn yaw_sign(self) -> f64 {
        match self {
            SpinDirection::Anticlockwise => 1.0,
            SpinDirection::Clockwise => -1.0,
        }
    }

    /// Inverse of [`SpinDirection::yaw_sign`]: accepts exactly +1 or -1.
    pub fn from_yaw_sign(field: &str, w: f64) -> Result<Self> {
        if w == 1.0 {
            Ok(SpinDirection::Anticlockwise)
        } else if w == -1.0 {
            Ok(SpinDirection::Clockwise)
        } else {
            Err(RfError::invalid(
                field,
                format!("must be +1 (anticlockwise) or -1 (clockwise), got {w}"),
            ))
        }
    }

    /// Parses "cw"/"clockwise" and "ccw"/"anticlockwise"/"counterclockwise" (any case).
    pub fn parse(field: &str, text: &str) -> Result<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "cw" | "clockwise" => Ok(SpinDirection::Clockwise),
            "ccw" | "acw" | "anticlockwise" | "counterclockwise" => {
                Ok(SpinDirection::Anticlockwise)
            }
            _ => Err(RfError::invalid(
                field,
                format!("must be \"cw\" (clockwise) or \"ccw\" (anticlockwise), got {text:?}"),
            )),
        }
    }

    pub fn short_name(self) -> &'static str {
        match self {
            SpinDirection::Clockwise => "cw",
            SpinDirection::Anticlockwise => "ccw",
        }
    }
}

/// One rotor. Thrusts in newtons, angles in radians, lengths in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Rotor {
    pub arm_angle_rad: f64,
    pub arm_length_m: f64,
    pub spin: SpinDirection,
    pub max_thrust_n: f64,
    /// May be negative (a variable-pitch rotor can push down).
    pub min_thrust_n: f64,
    /// eta_i of Du (lambda_i of Ke): 1 healthy, 0 failed.
    pub efficiency: f64,
}

/// A validated multirotor. Construct with [`Airframe::new`], [`Airframe::from_columns`] or
/// [`Airframe::from_toml_str`]; every constructor checks every field.
#[derive(Debug, Clone, PartialEq)]
pub struct Airframe {
    name: String,
    description: String,
    rotors: Vec<Rotor>,
    mass_kg: f64,
    inertia_kg_m2: [f64; 3],
    drag_torque_ratio_m: f64,
    gravity_m_s2: f64,
}

/// Field name for rotor `i` (0-based index into the arrays, 1-based rotor number for people).
fn rotor_field(field: &str, i: usize) -> String {
    format!("{field}[{i}] (rotor {})", i + 1)
}

impl Airframe {
    pub fn new(
        name: impl Into<String>,
        rotors: Vec<Rotor>,
        mass_kg: f64,
        inertia_kg_m2: [f64; 3],
        drag_torque_ratio_m: f64,
        gravity_m_s2: f64,
    ) -> Result<Self> {
        if rotors.is_empty() {
            return Err(RfError::invalid("rotors", "at least one rotor is required"));
        }
        for (i, rotor) in rotors.iter().enumerate() {
            validate_rotor(rotor, i)?;
        }
        require_finite("mass_kg", mass_kg)?;
        if mass_kg <= 0.0 {
            return Err(RfError::invalid(
                "mass_kg",
                format!("must be > 0, got {mass_kg}"),
            ));
        }
        for (axis, value) in ["Jx", "Jy", "Jz"].iter().zip(inertia_kg_m2) {
            let field = format!("inertia_kg_m2 ({axis})");
            require_finite(&field, value)?;
            if value <= 0.0 {
                return Err(RfError::invalid(field, format!("must be > 0, got {value}")));
            }
        }
        require_finite("drag_torque_ratio_m", drag_torque_ratio_m)?;
        if drag_torque_ratio_m < 0.0 {
            return Err(RfError::invalid(
                "drag_torque_ratio_m",
                format!(
                    "must be >= 0 (the spin direction carries the sign), got {drag_torque_ratio_m}"
                ),
            ));
        }
        require_finite("gravity_m_s2", gravity_m_s2)?;
        if gravity_m_s2 < 0.0 {
            return Err(RfError::invalid(
                "gravity_m_s2",
                format!("must be >= 0, got {gravity_m_s2}"),
            ));
        }
        Ok(Airframe {
            name: name.into(),
            description: String::new(),
            rotors,
            mass_kg,
            inertia_kg_m2,
            drag_torque_ratio_m,
            gravity_m_s2,
        })
    }

    /// Builds an airframe from per-rotor arrays (the Python constructor's shape).
    /// `spin_sign` holds `w_i` (+1 anticlockwise, -1 clockwise).
    #[allow(clippy::too_many_arguments)]
    pub fn from_columns(
        name: impl Into<String>,
        arm_angle_rad: &[f64],
        arm_length_m: &[f64],
        spin_sign: &[f64],
        max_thrust_n: &[f64],
        min_thrust_n: &[f64],
        efficiency: &[f64],
        mass_kg: f64,
        inertia_kg_m2: &[f64],
        drag_torque_ratio_m: f64,
        gravity_m_s2: f64,
    ) -> Result<Self> {
        let m = arm_angle_rad.len();
        if m == 0 {
            return Err(RfError::invalid(
                "arm_angle_rad",
                "at least one rotor is required",
            ));
        }
        require_len("arm_length_m", arm_length_m, m)?;
        require_len("spin", spin_sign, m)?;
        require_len("max_thrust_n", max_thrust_n, m)?;
        require_len("min_thrust_n", min_thrust_n, m)?;
        require_len("efficiency", efficiency, m)?;
        if inertia_kg_m2.len() != 3 {
            return Err(RfError::shape(
                "inertia_kg_m2",
                "3 entries (Jx, Jy, Jz)",
                format!("{}", inertia_kg_m2.len()),
            ));
        }
        let mut rotors = Vec::with_capacity(m);
        for i in 0..m {
            rotors.push(Rotor {
                arm_angle_rad: arm_angle_rad[i],
                arm_length_m: arm_length_m[i],
                spin: SpinDirection::from_yaw_sign(&rotor_field("spin", i), spin_sign[i])?,
                max_thrust_n: max_thrust_n[i],
                min_thrust_n: min_thrust_n[i],
                efficiency: efficiency[i],
            });
        }
        Airframe::new(
            name,
            rotors,
            mass_kg,
            [inertia_kg_m2[0], inertia_kg_m2[1], inertia_kg_m2[2]],
            drag_torque_ratio_m,
            gravity_m_s2,
        )
    }

    /// Parses and validates an airframe TOML document; `origin` (a path or preset name) prefixes
    /// every error message. The schema is documented in `python/rotorfault/presets/README.md`.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Self> {
        let parse_error = |message: String| RfError::Parse {
            origin: origin.to_string(),
            message,
        };
        let raw: AirframeToml = toml::from_str(text)
            .map_err(|e| parse_error(e.to_string().trim().replace('\n', " ")))?;
        let mut rotors = Vec::with_capacity(raw.rotor.len());
        for (i, r) in raw.rotor.iter().enumerate() {
            let where_ = format!("[[rotor]] number {}", i + 1);
            let arm_angle_rad = match (r.arm_angle_deg, r.arm_angle_rad) {
                (Some(deg), None) => deg.to_radians(),
                (None, Some(rad)) => rad,
                _ => {
                    return Err(parse_error(format!(
                        "{where_}: give exactly one of arm_angle_deg or arm_angle_rad"
                    )))
                }
            };
            let spin = SpinDirection::parse(&format!("{where_}.spin"), &r.spin)
                .map_err(|e| parse_error(e.to_string()))?;
            rotors.push(Rotor {
                arm_angle_rad,
                arm_length_m: r.arm_length_m,
                spin,
                max_thrust_n: r.max_thrust_n,
                min_thrust_n: r.min_thrust_n,
                efficiency: r.efficiency,
            });
        }
        let mut airframe = Airframe::new(
            raw.name,
            rotors,
            raw.mass_kg,
            raw.inertia_kg_m2,
            raw.drag_torque_ratio_m,
            raw.gravity_m_s2,
        )
        .map_err(|e| parse_error(e.to_string()))?;
        airframe.description = raw.description;
        Ok(airframe)
    }

    pub fn name(&self) -> &str {
        &self.name
    }
    pub fn description(&self) -> &str {
        &self.description
    }
    pub fn rotors(&self) -> &[Rotor] {
        &self.rotors
    }
    /// Number of rotors m.
    pub fn rotor_count(&self) -> usize {
        self.rotors.len()
    }
    pub fn mass_kg(&self) -> f64 {
        self.mass_kg
    }
    /// Principal moments of inertia (Jx, Jy, Jz), kg m^2.
    pub fn inertia_kg_m2(&self) -> [f64; 3] {
        self.inertia_kg_m2
    }
    /// k_mu of Du (c of Ke, d of Lanzon): reaction torque per unit thrust, metres.
    pub fn drag_torque_ratio_m(&self) -> f64 {
        self.drag_torque_ratio_m
    }
    pub fn gravity_m_s2(&self) -> f64 {
        self.gravity_m_s2
    }
    pub fn efficiency(&self) -> Vec<f64> {
        self.rotors.iter().map(|r| r.efficiency).collect()
    }
    pub fn min_thrust_n(&self) -> Vec<f64> {
        self.rotors.iter().map(|r| r.min_thrust_n).collect()
    }
    pub fn max_thrust_n(&self) -> Vec<f64> {
        self.rotors.iter().map(|r| r.max_thrust_n).collect()
    }

    /// G of Du eq. (1): the thrust/torque needed to hover, [m g, 0, 0, 0] (N, N m, N m, N m).
    pub fn hover_wrench(&self) -> [f64; 4] {
        [self.mass_kg * self.gravity_m_s2, 0.0, 0.0, 0.0]
    }

    /// A copy with the rotor efficiencies replaced; `eta` is validated like any field.
    pub fn with_efficiency(&self, eta: &[f64]) -> Result<Self> {
        check_efficiency("efficiency", eta, self.rotor_count())?;
        let mut out = self.clone();
        for (rotor, &e) in out.rotors.iter_mut().zip(eta) {
            rotor.efficiency = e;
        }
        Ok(out)
    }

    /// The contribution vectors b̄_i of Du eq. (4)-(5) without efficiencies: a 4 x m matrix with
    /// rows thrust T (N per N), roll L and pitch M (m), yaw N (m).
    pub fn nominal_effectiveness_matrix(&self) -> DMatrix<f64> {
        let k_mu = self.drag_torque_ratio_m;
        DMatrix::from_fn(4, self.rotor_count(), |row, i| {
            let r = &self.rotors[i];
            match row {
                0 => 1.0,
                1 => -r.arm_length_m * r.arm_angle_rad.sin(),
                2 => r.arm_length_m * r.arm_angle_rad.cos(),
                _ => r.spin.yaw_sign() * k_mu,
            }
        })
    }

    /// The airframe in the TOML schema of the presets. Floats are written in shortest round-trip
    /// form, so [`Airframe::from_toml_str`] gives back an equal airframe.
    pub fn to_toml_string(&self) -> String {
        let quoted = |text: &str| toml::Value::String(text.to_string()).to_string();
        let [jx, jy, jz] = self.inertia_kg_m2;
        let mut out = format!("name = {}\n", quoted(&self.name));
        if !self.description.is_empty() {
            out += &format!("description = {}\n", quoted(&self.description));
        }
        out += &format!(
            "mass_kg = {:?}\ngravity_m_s2 = {:?}\ninertia_kg_m2 = [{jx:?}, {jy:?}, {jz:?}]\n\
             drag_torque_ratio_m = {:?}\n",
            self.mass_kg, self.gravity_m_s2, self.drag_torque_ratio_m
        );
        for r in &self.rotors {
            out += &format!(
                "\n[[rotor]]\narm_angle_rad = {:?}\narm_length_m = {:?}\nspin = \"{}\"\n\
                 max_thrust_n = {:?}\nmin_thrust_n = {:?}\nefficiency = {:?}\n",
                r.arm_angle_rad,
                r.arm_length_m,
                r.spin.short_name(),
                r.max_thrust_n,
                r.min_thrust_n,
                r.efficiency
            );
        }
        out
    }

    /// B_f of Du eq. (5): the nominal matrix with column i scaled by eta_i.
    pub fn effectiveness_matrix(&self) -> DMatrix<f64> {
        let mut b = self.nominal_effectiveness_matrix();
        for (i, rotor) in self.rotors.iter().enumerate() {
            b.column_mut(i).scale_mut(rotor.efficiency);
        }
        b
    }
}

fn validate_rotor(r: &Rotor, i: usize) -> Result<()> {
    require_finite(&rotor_field("arm_angle_rad", i), r.arm_angle_rad)?;
    let field = rotor_field("arm_length_m", i);
    require_finite(&field, r.arm_length_m)?;
    if r.arm_length_m < 0.0 {
        return Err(RfError::invalid(
            field,
            format!("must be >= 0, got {}", r.arm_length_m),
        ));
    }
    require_finite(&rotor_field("max_thrust_n", i), r.max_thrust_n)?;
    let field = rotor_field("min_thrust_n", i);
    require_finite(&field, r.min_thrust_n)?;
    if r.min_thrust_n > r.max_thrust_n {
        return Err(RfError::invalid(
            field,
            format!(
                "must not exceed max_thrust_n ({} > {})",
                r.min_thrust_n, r.max_thrust_n
            ),
        ));
    }
    let field = rotor_field("efficiency", i);
    require_finite(&field, r.efficiency)?;
    if !(0.0..=1.0).contains(&r.efficiency) {
        return Err(RfError::invalid(
            field,
            format!("must lie in [0, 1], got {}", r.efficiency),
        ));
    }
    Ok(())
}

/// Checks an efficiency vector: m entries, each finite and in [0, 1].
pub fn check_efficiency(field: &str, eta: &[f64], m: usize) -> Result<()> {
    require_len(field, eta, m)?;
    // The hot path builds no strings: a message is made only for the first bad entry.
    match eta.iter().position(|e| !(0.0..=1.0).contains(e)) {
        None => Ok(()),
        Some(i) if !eta[i].is_finite() => Err(RfError::invalid(
            rotor_field(field, i),
            format!("must be finite, got {}", eta[i]),
        )),
        Some(i) => Err(RfError::invalid(
            rotor_field(field, i),
            format!("must lie in [0, 1], got {}", eta[i]),
        )),
    }
}

fn default_gravity() -> f64 {
    DEFAULT_GRAVITY_M_S2
}
fn default_efficiency() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AirframeToml {
    name: String,
    #[serde(default)]
    description: String,
    /// Where the numbers come from (paper, table); kept in the file for people, unused here.
    #[serde(default)]
    #[allow(dead_code)]
    source: String,
    mass_kg: f64,
    inertia_kg_m2: [f64; 3],
    drag_torque_ratio_m: f64,
    #[serde(default = "default_gravity")]
    gravity_m_s2: f64,
    rotor: Vec<RotorToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RotorToml {
    arm_angle_deg: Option<f64>,
    arm_angle_rad: Option<f64>,
    arm_length_m: f64,
    spin: String,
    max_thrust_n: f64,
    #[serde(default)]
    min_thrust_n: f64,
    #[serde(default = "default_efficiency")]
    efficiency: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Airframe {
        Airframe::from_columns(
            "q",
            &[0.0, 1.0, 2.0, 3.0],
            &[0.2; 4],
            &[1.0, -1.0, 1.0, -1.0],
            &[5.0; 4],
            &[0.0; 4],
            &[1.0; 4],
            1.0,
            &[0.01, 0.01, 0.02],
            0.1,
            9.81,
        )
        .unwrap()
    }

    #[test]
    fn effectiveness_matrix_follows_du_eq5() {
        let a = quad().with_efficiency(&[1.0, 0.5, 1.0, 0.0]).unwrap();
        let b = a.effectiveness_matrix();
        assert_eq!(b[(0, 1)], 0.5);
        assert!((b[(1, 1)] - (-0.5 * 0.2 * 1.0f64.sin())).abs() < 1e-15);
        assert!((b[(2, 1)] - (0.5 * 0.2 * 1.0f64.cos())).abs() < 1e-15);
        assert_eq!(b[(3, 1)], -0.05);
        assert_eq!(b.column(3).norm(), 0.0);
    }

    #[test]
    fn bad_fields_are_named() {
        // One rotor with the given spin sign and minimum thrust (maximum 1 N).
        let single = |spin: f64, min_thrust: f64| {
            Airframe::from_columns(
                "q",
                &[0.0],
                &[0.2],
                &[spin],
                &[1.0],
                &[min_thrust],
                &[1.0],
                1.0,
                &[1.0; 3],
                0.1,
                9.81,
            )
            .unwrap_err()
        };
        let err = single(1.0, 2.0);
        assert!(
            err.to_string().starts_with("min_thrust_n[0] (rotor 1)"),
            "{err}"
        );
        let err = single(0.5, 0.0);
        assert!(err.to_string().starts_with("spin[0]"), "{err}");
        let err = quad()
            .with_efficiency(&[1.0, f64::NAN, 1.0, 1.0])
            .unwrap_err();
        assert!(err.to_string().contains("efficiency[1]"), "{err}");
    }

    #[test]
    fn toml_round_trip_is_exact() {
        let mut a = quad().with_efficiency(&[1.0, 0.3, 1e-300, 0.0]).unwrap();
        a.description = "a \"quoted\" name\nwith a newline".to_string();
        a.rotors[1].max_thrust_n = 1e300;
        a.rotors[2].min_thrust_n = -0.1;
        let text = a.to_toml_string();
        assert_eq!(
            Airframe::from_toml_str(&text, "round trip").unwrap(),
            a,
            "{text}"
        );
    }

    #[test]
    fn toml_errors_name_the_field() {
        let err = Airframe::from_toml_str("name = \"x\"\n", "x.toml").unwrap_err();
        assert!(
            err.to_string().contains("x.toml") && err.to_string().contains("mass_kg"),
            "{err}"
        );
        let text = r#"
name = "x"
mass_kg = 1.0
inertia_kg_m2 = [1.0, 1.0, 1.0]
drag_torque_ratio_m = 0.1
[[rotor]]
arm_angle_deg = 0
arm_length_m = 0.2
spin = "sideways"
max_thrust_n = 5
"#;
        let err = Airframe::from_toml_str(text, "x.toml").unwrap_err();
        assert!(err.to_string().contains("spin"), "{err}");
        let ok = text.replace("sideways", "cw");
        let a = Airframe::from_toml_str(&ok, "x.toml").unwrap();
        assert_eq!(a.rotors()[0].spin, SpinDirection::Clockwise);
        assert_eq!(a.gravity_m_s2(), DEFAULT_GRAVITY_M_S2);
    }
}
