//! Du et al. Section IV.B: the step-by-step controllability test of the hover model (1).
//!
//! The hover model has state `[h, phi, theta, psi, v_h, p, q, r]`, `A = [[0, I], [0, 0]]` and
//! `B = [0; J_f^-1]` with `J_f = diag(-m_a, J_x, J_y, J_z)`. With the yaw axis given up (a vehicle
//! that spins, as in Lanzon's and Ke's controllers) the yaw angle, yaw rate and yaw torque drop out:
//! state `[h, phi, theta, v_h, p, q]`, `J_f = diag(-m_a, J_x, J_y)`, virtual control `[T, L, M]`.
//! The system is controllable iff rank C(A, B) = 2n and the ACAI is positive (Theorem 2).

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::airframe::{check_efficiency, Airframe};
use crate::analysis::acai::{AcaiBatch, AcaiFormula, AcaiResult, FacetNormals, HoverPoint};
use crate::analysis::rank::scale_free_rank;
use crate::cancel::Cancel;
use crate::error::{Result, RfError};

/// Which virtual-control axes must remain controllable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ControlAxes {
    /// Thrust, roll, pitch and yaw: Du's n = 4.
    ThrustRollPitchYaw,
    /// Thrust, roll and pitch only (yaw given up): n = 3.
    ThrustRollPitch,
    /// The full wrench, force and torque (F_x, F_y, F_z, L, M, N) in body FRD: n = 6, for
    /// tilted and fully actuated frames (hover needs zero lateral force as well).
    Wrench,
}

impl ControlAxes {
    pub fn from_give_up_yaw(give_up_yaw: bool) -> Self {
        if give_up_yaw {
            ControlAxes::ThrustRollPitch
        } else {
            ControlAxes::ThrustRollPitchYaw
        }
    }

    /// The kebab-case name (`thrust-roll-pitch-yaw`, `thrust-roll-pitch`, `wrench`).
    pub fn name(self) -> &'static str {
        match self {
            ControlAxes::ThrustRollPitchYaw => "thrust-roll-pitch-yaw",
            ControlAxes::ThrustRollPitch => "thrust-roll-pitch",
            ControlAxes::Wrench => "wrench",
        }
    }

    /// Inverse of [`ControlAxes::name`].
    pub fn parse(field: &str, text: &str) -> Result<Self> {
        [
            ControlAxes::ThrustRollPitchYaw,
            ControlAxes::ThrustRollPitch,
            ControlAxes::Wrench,
        ]
        .into_iter()
        .find(|a| a.name() == text)
        .ok_or_else(|| {
            RfError::invalid(
                field,
                format!(
                    "must be \"thrust-roll-pitch-yaw\", \"thrust-roll-pitch\" or \"wrench\", \
                     got {text:?}"
                ),
            )
        })
    }

    /// Virtual-control dimension n.
    pub fn dimension(self) -> usize {
        match self {
            ControlAxes::ThrustRollPitchYaw => 4,
            ControlAxes::ThrustRollPitch => 3,
            ControlAxes::Wrench => 6,
        }
    }

    /// The n x m effectiveness matrix of these axes without efficiencies: rows of Du's 4 x m
    /// B_f, or the 6 x m force/torque matrix.
    pub fn nominal_matrix(self, airframe: &Airframe) -> DMatrix<f64> {
        match self {
            ControlAxes::ThrustRollPitchYaw => airframe.nominal_effectiveness_matrix(),
            ControlAxes::ThrustRollPitch => airframe.nominal_effectiveness_matrix().remove_row(3),
            ControlAxes::Wrench => airframe.nominal_wrench_matrix(),
        }
    }

    /// The n x m matrix with the airframe's efficiencies applied.
    pub fn matrix(self, airframe: &Airframe) -> DMatrix<f64> {
        airframe.with_efficiencies(self.nominal_matrix(airframe))
    }

    /// What hovering level asks of these axes: `[m g, 0, 0(, 0)]`, or `[0, 0, -m g, 0, 0, 0]`.
    pub fn hover_wrench(self, airframe: &Airframe) -> Vec<f64> {
        match self {
            ControlAxes::Wrench => airframe.hover_wrench_6d().to_vec(),
            _ => airframe.hover_wrench()[..self.dimension()].to_vec(),
        }
    }

    /// The unit virtual control of "more thrust" (up): `e_1`, or `-e_3` for the wrench.
    pub fn thrust_direction(self) -> Vec<f64> {
        let mut d = vec![0.0; self.dimension()];
        match self {
            ControlAxes::Wrench => d[2] = -1.0,
            _ => d[0] = 1.0,
        }
        d
    }

    /// The diagonal J_f of the hover model: `(-m, Jx, Jy(, Jz))` or `(m, m, m, Jx, Jy, Jz)`.
    fn generalised_inertia(self, airframe: &Airframe) -> Vec<f64> {
        let [jx, jy, jz] = airframe.inertia_kg_m2();
        let m = airframe.mass_kg();
        match self {
            ControlAxes::ThrustRollPitchYaw => vec![-m, jx, jy, jz],
            ControlAxes::ThrustRollPitch => vec![-m, jx, jy],
            ControlAxes::Wrench => vec![m, m, m, jx, jy, jz],
        }
    }
}

/// Why the test ended the way it did (Du Step 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    Controllable,
    /// Step 1 failed: rank C(A, B) < 2n.
    ModelRankDeficient,
    /// Step 2 failed: rank B_f < n, the ACAI is undefined (-inf).
    EffectivenessRankDeficient,
    /// ACAI = 0: the hover wrench G lies on the boundary of the attainable set.
    HoverOnBoundary,
    /// ACAI < 0: G lies outside the attainable set.
    HoverOutside,
}

impl Verdict {
    pub fn is_controllable(self) -> bool {
        self == Verdict::Controllable
    }

    /// A short machine-readable reason.
    pub fn code(self) -> &'static str {
        match self {
            Verdict::Controllable => "controllable",
            Verdict::ModelRankDeficient => "uncontrollable: rank C(A, B) deficient",
            Verdict::EffectivenessRankDeficient => "uncontrollable: rank B_f deficient",
            Verdict::HoverOnBoundary => "uncontrollable: hover wrench on the boundary",
            Verdict::HoverOutside => "uncontrollable: hover wrench outside the attainable set",
        }
    }

    /// Inverse of [`Verdict::code`] (a report read back from its printed fields).
    pub fn parse(field: &str, code: &str) -> Result<Self> {
        [
            Verdict::Controllable,
            Verdict::ModelRankDeficient,
            Verdict::EffectivenessRankDeficient,
            Verdict::HoverOnBoundary,
            Verdict::HoverOutside,
        ]
        .into_iter()
        .find(|v| v.code() == code)
        .ok_or_else(|| RfError::invalid(field, format!("not a verdict of Du's test, got {code:?}")))
    }
}

/// The outcome of the 9-step procedure for one efficiency vector.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllabilityReport {
    pub axes: ControlAxes,
    /// The efficiency vector the test was asked about (one per rotor, in rotor order).
    pub efficiency: Vec<f64>,
    /// 2n: 8 with yaw, 6 without.
    pub state_dimension: usize,
    /// rank C(A, B) (Step 1).
    pub controllability_rank: usize,
    /// n: 4 with yaw, 3 without.
    pub virtual_control_dimension: usize,
    /// rank B_f with the efficiencies applied (Step 2).
    pub effectiveness_rank: usize,
    /// rho(G, dOmega) (Steps 3-8) in the requested formula; -inf when rank B_f < n.
    pub acai: f64,
    pub formula: AcaiFormula,
    /// Where the hover wrench G lies (the facet margin's sign), also when rank C(A, B) is
    /// deficient: `Outside` marks an `acai` that is not a distance.
    pub hover: HoverPoint,
    pub verdict: Verdict,
}

/// Everything about an airframe that does not depend on rotor efficiencies, built once and then
/// evaluated for any number of efficiency vectors.
#[derive(Debug, Clone)]
pub struct ControllabilityAnalysis {
    axes: ControlAxes,
    nominal: DMatrix<f64>,
    normals: FacetNormals,
    controllability_rank: usize,
    f_min: Vec<f64>,
    f_max: Vec<f64>,
    g: Vec<f64>,
    default_eta: Vec<f64>,
}

impl ControllabilityAnalysis {
    pub fn new(airframe: &Airframe, axes: ControlAxes) -> Result<Self> {
        Self::new_cancellable(airframe, axes, &Cancel::never())
    }

    /// [`ControllabilityAnalysis::new`] with the facet enumeration checking `cancel`.
    pub fn new_cancellable(
        airframe: &Airframe,
        axes: ControlAxes,
        cancel: &Cancel,
    ) -> Result<Self> {
        let nominal = axes.nominal_matrix(airframe);
        let normals = FacetNormals::new_cancellable(&nominal, cancel)?;
        let (a, b) = hover_model(airframe, axes);
        let f_min = airframe.min_thrust_n();
        let f_max = airframe.max_thrust_n();
        let g = axes.hover_wrench(airframe);
        normals.check_bounds_and_g(&f_min, &f_max, &g)?;
        Ok(ControllabilityAnalysis {
            axes,
            nominal,
            normals,
            controllability_rank: scale_free_rank(
                &controllability_matrix(&a, &b),
                "C(A, B) (from mass_kg and inertia_kg_m2)",
            )?,
            f_min,
            f_max,
            g,
            default_eta: airframe.efficiency(),
        })
    }

    pub fn axes(&self) -> ControlAxes {
        self.axes
    }

    /// The airframe's own efficiencies, used when none are given.
    pub fn default_efficiency(&self) -> &[f64] {
        &self.default_eta
    }

    /// ACAI for one efficiency vector (validated).
    pub fn acai(&self, eta: &[f64], formula: AcaiFormula) -> Result<f64> {
        check_efficiency("efficiency", eta, self.nominal.ncols())?;
        Ok(self
            .normals
            .evaluate(eta, &self.f_min, &self.f_max, &self.g)
            .get(formula))
    }

    /// [`ControllabilityAnalysis::acai`] with where the hover wrench lies (inside, on the
    /// boundary, outside, or rank B_f < n), by the verdict's rule.
    pub fn acai_with_hover(&self, eta: &[f64], formula: AcaiFormula) -> Result<AcaiResult> {
        check_efficiency("efficiency", eta, self.nominal.ncols())?;
        Ok(self
            .normals
            .evaluate(eta, &self.f_min, &self.f_max, &self.g)
            .result(formula))
    }

    /// ACAI for N efficiency vectors (row-major N x m), in parallel, checking `cancel`.
    pub fn acai_batch(
        &self,
        etas: &[f64],
        formula: AcaiFormula,
        cancel: &Cancel,
    ) -> Result<Vec<f64>> {
        self.normals
            .acai_batch(etas, &self.f_min, &self.f_max, &self.g, formula, cancel)
    }

    /// [`ControllabilityAnalysis::acai_batch`] with where the hover wrench lies for each row.
    pub fn acai_batch_with_hover(
        &self,
        etas: &[f64],
        formula: AcaiFormula,
        cancel: &Cancel,
    ) -> Result<AcaiBatch> {
        self.normals
            .acai_batch_with_hover(etas, &self.f_min, &self.f_max, &self.g, formula, cancel)
    }

    /// Du's Steps 1-9 for one efficiency vector; `formula` chooses how an ACAI with G outside
    /// the attainable set is reported (the verdict does not depend on it).
    pub fn report(&self, eta: &[f64], formula: AcaiFormula) -> Result<ControllabilityReport> {
        check_efficiency("efficiency", eta, self.nominal.ncols())?;
        let n = self.axes.dimension();
        let values = self
            .normals
            .evaluate(eta, &self.f_min, &self.f_max, &self.g);
        // Step 2 uses the same column-group test as the ACAI, so the report cannot contradict
        // itself; the (scale-free) SVD only says how deficient a deficient B_f is.
        let effectiveness_rank = if values.facet_margin == f64::NEG_INFINITY {
            let mut scaled = self.nominal.clone();
            for (k, &e) in eta.iter().enumerate() {
                scaled.column_mut(k).scale_mut(e);
            }
            scale_free_rank(&scaled, "B_f")?.min(n - 1)
        } else {
            n
        };
        let (acai, margin) = (values.get(formula), values.facet_margin);
        let verdict = if self.controllability_rank < 2 * n {
            Verdict::ModelRankDeficient
        } else if margin == f64::NEG_INFINITY {
            Verdict::EffectivenessRankDeficient
        } else if margin > 0.0 {
            Verdict::Controllable
        } else if margin == 0.0 {
            Verdict::HoverOnBoundary
        } else {
            Verdict::HoverOutside
        };
        Ok(ControllabilityReport {
            axes: self.axes,
            efficiency: eta.to_vec(),
            state_dimension: 2 * n,
            controllability_rank: self.controllability_rank,
            virtual_control_dimension: n,
            effectiveness_rank,
            acai,
            formula,
            hover: values.hover(),
            verdict,
        })
    }
}

/// Du's hover model (1) restricted to `axes`: `(A, B)` with A (2n x 2n) and B (2n x n).
pub fn hover_model(airframe: &Airframe, axes: ControlAxes) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = axes.dimension();
    let j_f = axes.generalised_inertia(airframe);
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    let mut b = DMatrix::zeros(2 * n, n);
    for (i, &j) in j_f.iter().enumerate() {
        a[(i, n + i)] = 1.0;
        b[(n + i, i)] = 1.0 / j;
    }
    (a, b)
}

/// C(A, B) = [B, AB, ..., A^(k-1) B] with k the state dimension.
pub fn controllability_matrix(a: &DMatrix<f64>, b: &DMatrix<f64>) -> DMatrix<f64> {
    let k = a.nrows();
    let mut blocks = Vec::with_capacity(k);
    let mut block = b.clone();
    for _ in 0..k {
        let next = a * &block;
        blocks.push(block);
        block = next;
    }
    DMatrix::from_columns(
        &blocks
            .iter()
            .flat_map(|blk| blk.column_iter().map(|c| c.into_owned()))
            .collect::<Vec<_>>(),
    )
}

/// One row of a failure table: a set of fully failed rotors (indices from 0 here; Python numbers
/// them from 1) and the verdicts with all four axes and giving up yaw (thrust, roll, pitch).
#[derive(Debug, Clone, PartialEq)]
pub struct FailureCase {
    pub failed: Vec<usize>,
    pub all_axes: ControllabilityReport,
    pub give_up_yaw: ControllabilityReport,
    /// The full-wrench test (n = 6), for fully actuated airframes only (nominal 6 x m matrix of
    /// rank 6); `None` for the others, where it would always read rank deficient.
    pub wrench: Option<ControllabilityReport>,
}

/// A fully actuated airframe: its nominal 6 x m force/torque matrix has rank 6 (scale-free).
pub fn is_fully_actuated(airframe: &Airframe) -> Result<bool> {
    Ok(airframe.rotor_count() >= 6
        && scale_free_rank(&airframe.nominal_wrench_matrix(), "wrench matrix")? == 6)
}

/// Largest number of failure combinations [`failure_table`] enumerates (each becomes a Python
/// object; a 16-rotor vehicle with up to 6 failures has 14,893).
pub const MAX_FAILURE_CASES: usize = 100_000;

/// Every combination of up to `max_failed` fully failed rotors (efficiency set to 0, the other
/// rotors keeping the airframe's efficiencies), in order of the number failed, then lexicographic.
/// `cancel` is checked before every combination.
pub fn failure_table(
    airframe: &Airframe,
    max_failed: usize,
    formula: AcaiFormula,
    cancel: &Cancel,
) -> Result<Vec<FailureCase>> {
    use crate::analysis::combinations::{binomial, Combinations};
    use crate::error::RfError;
    let m = airframe.rotor_count();
    if max_failed > m {
        return Err(RfError::invalid(
            "max_failed",
            format!("must be between 0 and the number of rotors ({m}), got {max_failed}"),
        ));
    }
    let total: usize = (0..=max_failed)
        .map(|k| binomial(m, k))
        .fold(0, usize::saturating_add);
    if total > MAX_FAILURE_CASES {
        return Err(RfError::invalid(
            "max_failed",
            format!("{total} failure combinations exceed the limit of {MAX_FAILURE_CASES}"),
        ));
    }
    let analysis = |axes| ControllabilityAnalysis::new_cancellable(airframe, axes, cancel);
    let all_axes = analysis(ControlAxes::ThrustRollPitchYaw)?;
    let give_up_yaw = analysis(ControlAxes::ThrustRollPitch)?;
    let wrench = if is_fully_actuated(airframe)? {
        Some(analysis(ControlAxes::Wrench)?)
    } else {
        None
    };
    let base = airframe.efficiency();
    let sets: Vec<Vec<usize>> = (0..=max_failed)
        .flat_map(|k| Combinations::new(m, k))
        .collect();
    sets.into_par_iter()
        .map(|failed| {
            cancel.check()?;
            let mut eta = base.clone();
            for &k in &failed {
                eta[k] = 0.0;
            }
            Ok(FailureCase {
                all_axes: all_axes.report(&eta, formula)?,
                give_up_yaw: give_up_yaw.report(&eta, formula)?,
                wrench: match &wrench {
                    Some(analysis) => Some(analysis.report(&eta, formula)?),
                    None => None,
                },
                failed,
            })
        })
        .collect()
}
