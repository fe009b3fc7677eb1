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

use crate::error::{
    require_finite, require_len, require_normal, require_scale, require_scale_or_zero, Result,
    RfError,
};

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

/// Where a rotor sits and where it pushes.
#[derive(Debug, Clone, PartialEq)]
pub enum RotorPlacement {
    /// The short form: in the body x-y plane at `arm_angle_rad` (from body x towards body y) and
    /// `arm_length_m` from the centre of mass, thrust along body -z (up). Its columns are
    /// computed by Du's eq. (5) exactly as before the general form existed.
    Planar {
        arm_angle_rad: f64,
        arm_length_m: f64,
    },
    /// PX4's form: position (body FRD, m, from the centre of mass) and the unit thrust axis
    /// (body FRD; `[0, 0, -1]` is straight up).
    General {
        position_m: [f64; 3],
        thrust_axis: [f64; 3],
    },
}

/// How far a thrust axis may be from unit length (written with 7 significant digits it passes).
pub const THRUST_AXIS_TOLERANCE: f64 = 1e-6;
/// Two rotors closer than this (m), with the same axis and spin, are the same rotor twice.
pub const COINCIDENT_ROTOR_M: f64 = 1e-9;

impl RotorPlacement {
    /// Body FRD position, m.
    pub fn position_m(&self) -> [f64; 3] {
        match *self {
            RotorPlacement::Planar {
                arm_angle_rad,
                arm_length_m,
            } => [
                arm_length_m * arm_angle_rad.cos(),
                arm_length_m * arm_angle_rad.sin(),
                0.0,
            ],
            RotorPlacement::General { position_m, .. } => position_m,
        }
    }

    /// Body FRD unit thrust direction.
    pub fn thrust_axis(&self) -> [f64; 3] {
        match *self {
            RotorPlacement::Planar { .. } => [0.0, 0.0, -1.0],
            RotorPlacement::General { thrust_axis, .. } => thrust_axis,
        }
    }

    /// Thrust along body -z exactly (what the simulator's rotor model assumes).
    pub fn is_vertical(&self) -> bool {
        self.thrust_axis() == [0.0, 0.0, -1.0]
    }
}

/// One rotor. Thrusts in newtons, angles in radians, lengths in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct Rotor {
    pub placement: RotorPlacement,
    /// Seen from the side the thrust points to ("from above" for an upright rotor).
    pub spin: SpinDirection,
    /// This rotor's k_mu (m, >= 0); `None`: the airframe's `drag_torque_ratio_m`.
    pub drag_torque_ratio_m: Option<f64>,
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
        check_coincident(&rotors)?;
        // Both are divided by (the rigid body, the hover model's J_f): see `crate::error`.
        require_scale("mass_kg", mass_kg, "kg")?;
        for (axis, value) in ["Jx", "Jy", "Jz"].iter().zip(inertia_kg_m2) {
            require_scale(&format!("inertia_kg_m2 ({axis})"), value, "kg m^2")?;
        }
        require_normal("drag_torque_ratio_m", drag_torque_ratio_m)?;
        if drag_torque_ratio_m < 0.0 {
            return Err(RfError::invalid(
                "drag_torque_ratio_m",
                format!(
                    "must be >= 0 (the spin direction carries the sign), got {drag_torque_ratio_m}"
                ),
            ));
        }
        require_scale_or_zero("gravity_m_s2", gravity_m_s2, "m/s^2")?;
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
        let per_rotor = PerRotor {
            spin_sign,
            max_thrust_n,
            min_thrust_n,
            efficiency,
        };
        let rotors = per_rotor.rotors(|i| {
            let placement = RotorPlacement::Planar {
                arm_angle_rad: arm_angle_rad[i],
                arm_length_m: arm_length_m[i],
            };
            (placement, None)
        })?;
        Airframe::new(
            name,
            rotors,
            mass_kg,
            inertia3(inertia_kg_m2)?,
            drag_torque_ratio_m,
            gravity_m_s2,
        )
    }

    /// Builds an airframe from PX4-style per-rotor geometry: `position_m` and `thrust_axis` are
    /// row-major m x 3 (body FRD), `rotor_drag_torque_ratio_m` holds each rotor's k_mu (`None`:
    /// the airframe's `drag_torque_ratio_m` for every rotor).
    #[allow(clippy::too_many_arguments)]
    pub fn from_general_columns(
        name: impl Into<String>,
        position_m: &[f64],
        thrust_axis: &[f64],
        spin_sign: &[f64],
        rotor_drag_torque_ratio_m: Option<&[f64]>,
        max_thrust_n: &[f64],
        min_thrust_n: &[f64],
        efficiency: &[f64],
        mass_kg: f64,
        inertia_kg_m2: &[f64],
        drag_torque_ratio_m: f64,
        gravity_m_s2: f64,
    ) -> Result<Self> {
        let m = spin_sign.len();
        if m == 0 {
            return Err(RfError::invalid("spin", "at least one rotor is required"));
        }
        for (field, values) in [("position_m", position_m), ("thrust_axis", thrust_axis)] {
            if values.len() != 3 * m {
                return Err(RfError::shape(
                    field,
                    format!("{m} x 3 (one row per rotor)"),
                    format!("{} values", values.len()),
                ));
            }
        }
        if let Some(k) = rotor_drag_torque_ratio_m {
            require_len("rotor_drag_torque_ratio_m", k, m)?;
        }
        let row = |v: &[f64], i: usize| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
        let per_rotor = PerRotor {
            spin_sign,
            max_thrust_n,
            min_thrust_n,
            efficiency,
        };
        let rotors = per_rotor.rotors(|i| {
            let placement = RotorPlacement::General {
                position_m: row(position_m, i),
                thrust_axis: row(thrust_axis, i),
            };
            (placement, rotor_drag_torque_ratio_m.map(|k| k[i]))
        })?;
        Airframe::new(
            name,
            rotors,
            mass_kg,
            inertia3(inertia_kg_m2)?,
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
            let planar =
                r.arm_angle_deg.is_some() || r.arm_angle_rad.is_some() || r.arm_length_m.is_some();
            let general = r.position_m.is_some() || r.thrust_axis.is_some();
            let placement = match (planar, general) {
                (true, false) => {
                    let arm_angle_rad = match (r.arm_angle_deg, r.arm_angle_rad) {
                        (Some(deg), None) => deg.to_radians(),
                        (None, Some(rad)) => rad,
                        _ => {
                            return Err(parse_error(format!(
                                "{where_}: give exactly one of arm_angle_deg or arm_angle_rad"
                            )))
                        }
                    };
                    let arm_length_m = r.arm_length_m.ok_or_else(|| {
                        parse_error(format!(
                            "{where_}: arm_length_m is required with an arm angle"
                        ))
                    })?;
                    RotorPlacement::Planar {
                        arm_angle_rad,
                        arm_length_m,
                    }
                }
                (false, true) => RotorPlacement::General {
                    position_m: r.position_m.ok_or_else(|| {
                        parse_error(format!("{where_}: position_m is required with thrust_axis"))
                    })?,
                    thrust_axis: r.thrust_axis.unwrap_or([0.0, 0.0, -1.0]),
                },
                _ => {
                    return Err(parse_error(format!(
                        "{where_}: give either the planar form (arm_angle_deg or arm_angle_rad, \
                         arm_length_m) or the general form (position_m, thrust_axis), not both"
                    )))
                }
            };
            let spin = SpinDirection::parse(&format!("{where_}.spin"), &r.spin)
                .map_err(|e| parse_error(e.to_string()))?;
            rotors.push(Rotor {
                placement,
                spin,
                drag_torque_ratio_m: r.drag_torque_ratio_m,
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
    /// A general rotor contributes its upward force `-a_z` and the torques of
    /// [`Airframe::nominal_wrench_matrix`]; lateral force is not one of these axes.
    pub fn nominal_effectiveness_matrix(&self) -> DMatrix<f64> {
        // From the wrench column: for a planar rotor `-(-1) = 1` and Du's eq. (5) torques, the
        // same bits as writing eq. (5) out.
        let columns: Vec<[f64; 6]> = (0..self.rotor_count())
            .map(|i| self.wrench_column(i))
            .collect();
        DMatrix::from_fn(4, self.rotor_count(), |row, i| {
            if row == 0 {
                -columns[i][2]
            } else {
                columns[i][2 + row]
            }
        })
    }

    /// Rotor i's k_mu (m): its own, else the airframe's.
    pub fn rotor_drag_torque_ratio_m(&self, i: usize) -> f64 {
        self.rotors[i]
            .drag_torque_ratio_m
            .unwrap_or(self.drag_torque_ratio_m)
    }

    /// Force and torque per newton of rotor i's thrust, body FRD: `[a; p x a - w k_mu a]` with `a`
    /// the thrust axis, `p` the position and `w` the spin sign (+1 anticlockwise seen from the
    /// side the thrust points to). For a planar rotor, `a = (0, 0, -1)` and the torque is Du's
    /// `(-r sin(phi), r cos(phi), w k_mu)` (PX4's `p x a - KM a` with `KM = w k_mu`).
    fn wrench_column(&self, i: usize) -> [f64; 6] {
        let r = &self.rotors[i];
        let k = r.spin.yaw_sign() * self.rotor_drag_torque_ratio_m(i);
        let column = match r.placement {
            RotorPlacement::Planar {
                arm_angle_rad,
                arm_length_m,
            } => [
                0.0,
                0.0,
                -1.0,
                -arm_length_m * arm_angle_rad.sin(),
                arm_length_m * arm_angle_rad.cos(),
                k,
            ],
            RotorPlacement::General {
                position_m: p,
                thrust_axis: a,
            } => [
                a[0],
                a[1],
                a[2],
                p[1] * a[2] - p[2] * a[1] - k * a[0],
                p[2] * a[0] - p[0] * a[2] - k * a[1],
                p[0] * a[1] - p[1] * a[0] - k * a[2],
            ],
        };
        column.map(flushed)
    }

    /// The full 6 x m effectiveness matrix without efficiencies: rows force `(F_x, F_y, F_z)` (N
    /// per N) and torque `(L, M, N)` (N m per N), body FRD. Hovering needs
    /// [`Airframe::hover_wrench_6d`].
    pub fn nominal_wrench_matrix(&self) -> DMatrix<f64> {
        let columns: Vec<[f64; 6]> = (0..self.rotor_count())
            .map(|i| self.wrench_column(i))
            .collect();
        DMatrix::from_fn(6, self.rotor_count(), |row, i| columns[i][row])
    }

    /// [`Airframe::nominal_wrench_matrix`] with column i scaled by eta_i.
    pub fn wrench_matrix(&self) -> DMatrix<f64> {
        self.with_efficiencies(self.nominal_wrench_matrix())
    }

    /// `nominal` (one column per rotor) with column i scaled by eta_i: the one place every
    /// effectiveness matrix of the crate takes its efficiencies, a subnormal product read as 0.
    pub fn with_efficiencies(&self, mut nominal: DMatrix<f64>) -> DMatrix<f64> {
        for (i, rotor) in self.rotors.iter().enumerate() {
            nominal.column_mut(i).scale_mut(rotor.efficiency);
        }
        nominal.apply(|x| *x = flushed(*x));
        nominal
    }

    /// The force and torque the rotors must supply to hover level, body FRD:
    /// `[0, 0, -m g, 0, 0, 0]` (thrust up is -z).
    pub fn hover_wrench_6d(&self) -> [f64; 6] {
        [0.0, 0.0, -self.mass_kg * self.gravity_m_s2, 0.0, 0.0, 0.0]
    }

    /// Every rotor in the x-y plane form (what the short TOML form writes).
    pub fn is_planar(&self) -> bool {
        self.rotors
            .iter()
            .all(|r| matches!(r.placement, RotorPlacement::Planar { .. }))
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
            out += "\n[[rotor]]\n";
            out += &match r.placement {
                RotorPlacement::Planar {
                    arm_angle_rad,
                    arm_length_m,
                } => {
                    format!("arm_angle_rad = {arm_angle_rad:?}\narm_length_m = {arm_length_m:?}\n")
                }
                RotorPlacement::General {
                    position_m: [x, y, z],
                    thrust_axis: [ax, ay, az],
                } => format!(
                    "position_m = [{x:?}, {y:?}, {z:?}]\nthrust_axis = [{ax:?}, {ay:?}, {az:?}]\n"
                ),
            };
            out += &format!("spin = \"{}\"\n", r.spin.short_name());
            if let Some(k) = r.drag_torque_ratio_m {
                out += &format!("drag_torque_ratio_m = {k:?}\n");
            }
            out += &format!(
                "max_thrust_n = {:?}\nmin_thrust_n = {:?}\nefficiency = {:?}\n",
                r.max_thrust_n, r.min_thrust_n, r.efficiency
            );
        }
        out
    }

    /// B_f of Du eq. (5): the nominal matrix with column i scaled by eta_i.
    pub fn effectiveness_matrix(&self) -> DMatrix<f64> {
        self.with_efficiencies(self.nominal_effectiveness_matrix())
    }
}

/// `x`, or 0 when it is subnormal: an entry of an effectiveness or wrench matrix below 2.2e-308
/// (an arm angle of 1e-309 rad, an efficiency of 1e-310) has no precision left and is zero at the
/// precision of every other entry, while the allocation and rank tests refuse a subnormal as a
/// scale (`matrix[r, c]: must be 0 or a normal number`, a matrix the user never wrote). Normal
/// entries keep their bits.
fn flushed(x: f64) -> f64 {
    if x.is_subnormal() {
        0.0
    } else {
        x
    }
}

fn validate_rotor(r: &Rotor, i: usize) -> Result<()> {
    match r.placement {
        RotorPlacement::Planar {
            arm_angle_rad,
            arm_length_m,
        } => {
            require_finite(&rotor_field("arm_angle_rad", i), arm_angle_rad)?;
            let field = rotor_field("arm_length_m", i);
            require_normal(&field, arm_length_m)?;
            if arm_length_m < 0.0 {
                return Err(RfError::invalid(
                    field,
                    format!("must be >= 0, got {arm_length_m}"),
                ));
            }
        }
        RotorPlacement::General {
            position_m,
            thrust_axis,
        } => {
            for (c, &x) in position_m.iter().enumerate() {
                require_normal(&format!("position_m[{i}][{c}] (rotor {})", i + 1), x)?;
            }
            for (c, &x) in thrust_axis.iter().enumerate() {
                require_finite(&format!("thrust_axis[{i}][{c}] (rotor {})", i + 1), x)?;
            }
            let norm = thrust_axis.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > THRUST_AXIS_TOLERANCE {
                return Err(RfError::invalid(
                    rotor_field("thrust_axis", i),
                    format!(
                        "must be a unit vector (length 1 within {THRUST_AXIS_TOLERANCE}), got \
                         length {norm} for {thrust_axis:?}"
                    ),
                ));
            }
        }
    }
    if let Some(k) = r.drag_torque_ratio_m {
        let field = rotor_field("rotor_drag_torque_ratio_m", i);
        require_normal(&field, k)?;
        if k < 0.0 {
            return Err(RfError::invalid(
                field,
                format!("must be >= 0 (the spin direction carries the sign), got {k}"),
            ));
        }
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

/// The per-rotor columns both column constructors share: spin, thrust box, efficiency.
struct PerRotor<'a> {
    spin_sign: &'a [f64],
    max_thrust_n: &'a [f64],
    min_thrust_n: &'a [f64],
    efficiency: &'a [f64],
}

impl PerRotor<'_> {
    /// The rotors, `placement(i)` giving rotor i's placement and own k_mu; the shared columns'
    /// lengths are checked against the spin column's first.
    fn rotors(
        &self,
        placement: impl Fn(usize) -> (RotorPlacement, Option<f64>),
    ) -> Result<Vec<Rotor>> {
        let m = self.spin_sign.len();
        require_len("max_thrust_n", self.max_thrust_n, m)?;
        require_len("min_thrust_n", self.min_thrust_n, m)?;
        require_len("efficiency", self.efficiency, m)?;
        (0..m)
            .map(|i| {
                let (placement, drag_torque_ratio_m) = placement(i);
                Ok(Rotor {
                    placement,
                    spin: SpinDirection::from_yaw_sign(&rotor_field("spin", i), self.spin_sign[i])?,
                    drag_torque_ratio_m,
                    max_thrust_n: self.max_thrust_n[i],
                    min_thrust_n: self.min_thrust_n[i],
                    efficiency: self.efficiency[i],
                })
            })
            .collect()
    }
}

/// `[Jx, Jy, Jz]` from a slice, naming the field when it has another length.
fn inertia3(inertia_kg_m2: &[f64]) -> Result<[f64; 3]> {
    match inertia_kg_m2 {
        [x, y, z] => Ok([*x, *y, *z]),
        _ => Err(RfError::shape(
            "inertia_kg_m2",
            "3 entries (Jx, Jy, Jz)",
            format!("{}", inertia_kg_m2.len()),
        )),
    }
}

/// The same rotor twice (same position within [`COINCIDENT_ROTOR_M`], same axis and spin) is
/// almost always a copy-paste slip in a general (PX4-style) rotor list; a coaxial pair spins the
/// other way and passes. Planar rotors (Du's arm angle and length) are exempt: that form accepted
/// any layout before general rotors existed, and the analysis of two rotors at one place is
/// well defined (they act as one rotor with the summed box).
fn check_coincident(rotors: &[Rotor]) -> Result<()> {
    let general = |r: &Rotor| matches!(r.placement, RotorPlacement::General { .. });
    for j in 1..rotors.len() {
        for i in 0..j {
            let (a, b) = (&rotors[i], &rotors[j]);
            if !(general(a) || general(b)) {
                continue;
            }
            let (pa, pb) = (a.placement.position_m(), b.placement.position_m());
            let distance = (0..3).map(|c| (pa[c] - pb[c]).powi(2)).sum::<f64>().sqrt();
            if distance <= COINCIDENT_ROTOR_M
                && a.placement.thrust_axis() == b.placement.thrust_axis()
                && a.spin == b.spin
            {
                return Err(RfError::invalid(
                    rotor_field("position_m", j),
                    format!(
                        "rotor {} coincides with rotor {} (same position, thrust axis and spin)",
                        j + 1,
                        i + 1
                    ),
                ));
            }
        }
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
    arm_length_m: Option<f64>,
    position_m: Option<[f64; 3]>,
    thrust_axis: Option<[f64; 3]>,
    spin: String,
    drag_torque_ratio_m: Option<f64>,
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
