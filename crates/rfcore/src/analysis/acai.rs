//! The Available Control Authority Index (ACAI) of Du et al., Theorem 3, by hyperplane enumeration.
//!
//! The attainable set `Omega = { B f : f_min <= f <= f_max }` of an `n x m` effectiveness matrix is
//! a zonotope. Each group of `n - 1` linearly independent columns spans a pair of parallel facets
//! with unit normal `xi_j` (Du eq. (16)); the half-width of the zonotope along `xi_j` is
//! `sum_k |xi_j . b_k| (f_max,k - f_min,k) / 2` (eq. (29), with a general box instead of [0, K]),
//! and the offset of G from the centre `F_c = B (f_min + f_max) / 2` is `|xi_j . (F_c - G)|`
//! (eq. (30)). `d_j` is their difference (eq. (14)) and the ACAI is eq. (13).
//!
//! The dimension `n` is free: `n = 4` is Du's thrust/roll/pitch/yaw; `n = 3` (thrust, roll, pitch)
//! answers "can this vehicle hover if it gives up yaw and spins?".
//!
//! Two facts make the batch fast and exact:
//! - `xi_j` is the generalised cross product of the group's columns (signed maximal minors), a
//!   closed form with no SVD;
//! - scaling a column by `eta_k > 0` scales that cross product by a positive factor, so the
//!   *normalised* `xi_j` does not depend on the efficiencies. [`FacetNormals`] computes every
//!   `xi_j` and every projection `xi_j . b_k` once per geometry; an evaluation for a new
//!   efficiency vector is then `O(groups x m)` multiply-adds with no allocation.
//!
//! A group holding a rotor with `eta_k = 0` has rank `< n - 1` and spans no facet (Du Step 6), but
//! its direction `xi_j` is still a valid supporting direction of Omega, so its `d_j` is an upper
//! bound on the distance from an interior G to the boundary and never changes the result there.
//! Keeping it makes the index continuous as `eta_k -> 0` (see "G outside Omega").
//!
//! # Tolerances (one rank rule, free of units)
//! Every decision below is invariant to the units of the rows (a positive scaling of any row of B
//! and the same entry of G maps Omega and G linearly, so inside / on / outside and every rank stay
//! what they are); only the reported values are in the user's units.
//! - **Row equilibration.** Facets and ranks are decided on `E = D B`, where `D` scales each row
//!   of the nominal B to unit Euclidean norm by a power of two ([`equilibrating_row_scale`]: exact,
//!   and scaling a row of B by a power of two leaves E bit for bit unchanged). Without it, a
//!   wrench of forces in N beside torques in N m, or a quadrotor with 1e-5 m arms, lost real
//!   facets (G reported inside) or full rank (-inf).
//! - A column group is rank-deficient when the cross product of its *unit* columns of E has norm
//!   `<= RANK_RTOL = 1e-9` (the group's volume "sine", 1 for orthogonal columns, 0 for dependent
//!   ones).
//! - A column lies in a group's hyperplane (projection exactly zero) when the cosine between its
//!   unit column of E and the group's normal in E is `<= RANK_RTOL`.
//! - `rank B_f = n` iff some group of `n - 1` independent working columns has a working column off
//!   its hyperplane; otherwise the ACAI is `-inf` and the report's `rank B_f` (Step 2) is the
//!   [`scale_free_rank`](crate::analysis::rank::scale_free_rank) of B_f capped at `n - 1`, so the
//!   report and the ACAI cannot disagree. `rank C(A, B)` (Step 1) is that rank too: rows and columns equilibrated by powers of
//!   two, then singular values above `RANK_RTOL` times the largest (any J/m is read correctly).
//! - **Distances in the user's units.** A group's normal `xi` in E maps to `D xi` in B (for any v,
//!   `(D xi) . v = xi . (D v)`); `xi_j` is that vector normalised, so every `d_j` is exactly the
//!   value of eq. (14) in the units of B and G (identical to computing the normal in B directly
//!   whenever no facet is lost). A change of units of a row changes every `d_j` by a positive
//!   factor of its own (so the values, not the signs, depend on units: a distance between a
//!   force and a torque has no unit-free meaning).
//! - **Zero.** A `d_j` with `|d_j| <= ZERO_RTOL = 1e-9` times the problem's size along its own
//!   normal, `sum_k |xi_j . b_k| (|f_min,k| + |f_max,k|) / 2 + |xi_j . G|`, is exactly `0.0`
//!   (never `-0.0`): G is on that facet's hyperplane to working precision. A change of units
//!   scales `d_j` and this size by the same factor, so the snap is unit-free (one size for the
//!   whole problem would read every facet along a small unit as "boundary"). `b_k` are the nominal
//!   columns (efficiencies not applied), so the threshold does not move with `eta` and snapping
//!   never breaks monotonicity in the efficiencies. The ACAI is then formed from the snapped
//!   `d_j`.
//! - **Where G lies** ([`HoverPoint`], returned with every value by the `*_with_hover`
//!   functions): the sign of the facet margin formed from the snapped `d_j`: `> 0` inside, `0` on
//!   the boundary, `< 0` outside, `-inf` rank deficient. The verdicts of
//!   [`crate::analysis::ControllabilityReport`] use the same classification, whatever formula the
//!   value is reported in.

//! # G outside Omega (a decided paper gap): [`AcaiFormula`]
//! For G inside Omega or on its boundary, `min_j d_j` is the distance of definition (9) and both
//! formulas below agree. For G outside they differ:
//! - [`AcaiFormula::Eq13`] (default, reproduces the paper's tables): Du's eq. (13) as printed,
//!   `sign(min_j d_j) min_j |d_j|` over the full-rank groups. This is not the distance of (9): a
//!   single `d_j` that happens to vanish makes it 0 although G is outside (Du Table III prints 0
//!   for the PPNNPN hexacopter with rotor 5 or 6 failed, where hover is infeasible and the hover
//!   wrench lies 0.2133 outside a facet), and it is not monotone in the efficiencies.
//! - [`AcaiFormula::FacetMargin`]: `min_j d_j` over every nominal facet direction (including
//!   groups with a failed rotor, whose directions still support Omega): minus the largest
//!   violation of a facet inequality. A lower bound on the distance of (9), exact when the point
//!   of Omega nearest to G lies inside a facet; continuous and non-decreasing in every `eta_i` when
//!   every box contains zero (`f_min <= 0 <= f_max`).
//!
//! Verdicts never depend on the choice: they use the sign of the facet margin, which is the sign
//! of `min_j d_j` in eq. (13).

use nalgebra::DMatrix;
use rayon::prelude::*;

use crate::analysis::combinations::{binomial, Combinations};
use crate::analysis::cross_product::generalized_cross_product;
use crate::analysis::facet_lanes::{evaluate_rows, FacetTable, LanePath, LANES};
use crate::cancel::{rows_per_check, Cancel, GROUPS_PER_CHECK};
use crate::error::{require_all_finite, require_entries, require_finite, Result, RfError};

/// Relative tolerance for rank decisions (see the module documentation).
pub const RANK_RTOL: f64 = 1e-9;
/// Relative tolerance under which an ACAI is reported as exactly zero.
pub const ZERO_RTOL: f64 = 1e-9;
/// Largest `groups x m` table [`FacetNormals`] will build (two f64 tables: about 400 MB).
pub const MAX_TABLE_ENTRIES: usize = 25_000_000;
/// Largest virtual-control dimension n (rows of B); physical problems have n <= 6.
pub const MAX_DIMENSION: usize = 12;

/// How the index is reported when G lies outside the attainable set (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AcaiFormula {
    /// Du et al. eq. (13) exactly as printed (reproduces Tables II and III).
    #[default]
    Eq13,
    /// `min_j d_j` over every facet direction: a monotone lower bound on the signed distance.
    FacetMargin,
}

impl AcaiFormula {
    /// Parses the names used by the Python API and the CLI: `"eq13"` and `"facet-margin"`.
    pub fn parse(text: &str) -> Result<Self> {
        match text {
            "eq13" => Ok(AcaiFormula::Eq13),
            "facet-margin" => Ok(AcaiFormula::FacetMargin),
            other => Err(RfError::invalid(
                "formula",
                format!("must be \"eq13\" or \"facet-margin\", got {other:?}"),
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            AcaiFormula::Eq13 => "eq13",
            AcaiFormula::FacetMargin => "facet-margin",
        }
    }
}

/// Both readings of one evaluation; equal whenever G is inside Omega or on its boundary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AcaiValues {
    /// Du eq. (13) as printed.
    pub eq13: f64,
    /// `min_j d_j` over every facet direction; its sign decides controllability.
    pub facet_margin: f64,
}

impl AcaiValues {
    pub fn get(self, formula: AcaiFormula) -> f64 {
        match formula {
            AcaiFormula::Eq13 => self.eq13,
            AcaiFormula::FacetMargin => self.facet_margin,
        }
    }
}

impl AcaiValues {
    /// Where G lies, from the sign of the facet margin (the verdict's rule).
    pub fn hover(self) -> HoverPoint {
        HoverPoint::from_facet_margin(self.facet_margin)
    }

    /// The ACAI in `formula` together with where G lies.
    pub fn result(self, formula: AcaiFormula) -> AcaiResult {
        AcaiResult {
            acai: self.get(formula),
            hover: self.hover(),
        }
    }
}

/// Where the required wrench G lies relative to the attainable set Omega, decided by the sign of
/// the facet margin with the tolerances of the module documentation (the rule every verdict
/// uses). Eq. (13) can print 0 or a small negative number for G far outside: this says which.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HoverPoint {
    /// G is an interior point of Omega (ACAI > 0).
    Inside,
    /// G is on the boundary of Omega to working precision (facet margin exactly 0).
    OnBoundary,
    /// G is outside Omega: hover is infeasible, whatever eq. (13) prints.
    Outside,
    /// rank B < n: Omega has no interior and the ACAI is undefined (-inf).
    RankDeficient,
}

impl HoverPoint {
    /// The classification of a facet margin (`-inf` for rank B < n).
    pub fn from_facet_margin(margin: f64) -> Self {
        if margin == f64::NEG_INFINITY {
            HoverPoint::RankDeficient
        } else if margin > 0.0 {
            HoverPoint::Inside
        } else if margin == 0.0 {
            HoverPoint::OnBoundary
        } else {
            HoverPoint::Outside
        }
    }

    /// G can be produced: inside Omega or on its boundary.
    pub fn is_attainable(self) -> bool {
        matches!(self, HoverPoint::Inside | HoverPoint::OnBoundary)
    }

    /// G is outside Omega: the value of eq. (13) is not a distance (mark it in tables).
    pub fn is_outside(self) -> bool {
        self == HoverPoint::Outside
    }

    /// A short name: `"inside"`, `"boundary"`, `"outside"`, `"rank-deficient"`.
    pub fn name(self) -> &'static str {
        match self {
            HoverPoint::Inside => "inside",
            HoverPoint::OnBoundary => "boundary",
            HoverPoint::Outside => "outside",
            HoverPoint::RankDeficient => "rank-deficient",
        }
    }

    /// Every hover point, in code order (parsers look names and codes up here).
    const ALL: [HoverPoint; 4] = [
        HoverPoint::Inside,
        HoverPoint::OnBoundary,
        HoverPoint::Outside,
        HoverPoint::RankDeficient,
    ];

    /// Inverse of [`HoverPoint::name`].
    pub fn parse(field: &str, text: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|h| h.name() == text)
            .ok_or_else(|| {
                RfError::invalid(
                    field,
                    format!(
                        "must be \"inside\", \"boundary\", \"outside\" or \"rank-deficient\", \
                     got {text:?}"
                    ),
                )
            })
    }

    /// The hover point of a code (`code`'s inverse); any other value is refused, naming `field`.
    pub fn from_code(field: &str, code: i64) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|h| i64::from(h.code()) == code)
            .ok_or_else(|| {
                RfError::invalid(
                    field,
                    format!(
                        "must be a hover code (1 inside, 0 boundary, -1 outside, \
                     -2 rank-deficient), got {code}"
                    ),
                )
            })
    }

    /// `1` inside, `0` on the boundary, `-1` outside, `-2` rank deficient (a compact column).
    pub fn code(self) -> i8 {
        match self {
            HoverPoint::Inside => 1,
            HoverPoint::OnBoundary => 0,
            HoverPoint::Outside => -1,
            HoverPoint::RankDeficient => -2,
        }
    }
}

/// One ACAI in the requested formula with where G lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AcaiResult {
    /// The ACAI in the requested formula.
    pub acai: f64,
    /// Where G lies (the facet margin's sign): `Outside` marks an eq. (13) value that is not a
    /// distance, e.g. the 0 of Du Table III for PPNNPN with rotor 5 failed.
    pub hover: HoverPoint,
}

/// A batch of ACAIs with where G lies for each row, as two columns.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AcaiBatch {
    /// The ACAI of each row in the requested formula.
    pub acai: Vec<f64>,
    /// Where G lies for each row.
    pub hover: Vec<HoverPoint>,
}

/// Facet normals and projections of a nominal effectiveness matrix, reusable for any efficiencies,
/// bounds and G.
#[derive(Debug, Clone)]
pub struct FacetNormals {
    /// Virtual-control dimension n (rows of B).
    n: usize,
    /// Number of actuators m (columns of B).
    m: usize,
    /// Column indices of each full-rank group, `n - 1` per group.
    groups: Vec<usize>,
    /// Unit normals, `n` per group.
    normals: Vec<f64>,
    /// `xi_j . b_k`, `m` per group; exactly zero for the group's own columns.
    projections: Vec<f64>,
    /// `|xi_j . b_k|`, the same layout (the half-width weights of eq. (29)).
    abs_projections: Vec<f64>,
    /// `|b_k|`, for the zero tolerance.
    column_norms: Vec<f64>,
}

impl FacetNormals {
    /// Enumerates the column groups of `b` (n x m, efficiencies not applied).
    pub fn new(b: &DMatrix<f64>) -> Result<Self> {
        Self::new_cancellable(b, &Cancel::never())
    }

    /// [`FacetNormals::new`], checking `cancel` every [`GROUPS_PER_CHECK`] groups: up to
    /// [`MAX_TABLE_ENTRIES`] entries take seconds.
    pub fn new_cancellable(b: &DMatrix<f64>, cancel: &Cancel) -> Result<Self> {
        let (n, m) = b.shape();
        if n == 0 || m == 0 {
            return Err(RfError::shape(
                "effectiveness_matrix",
                "at least one row and one column",
                format!("{n} x {m}"),
            ));
        }
        if n > MAX_DIMENSION {
            return Err(RfError::invalid(
                "effectiveness_matrix",
                format!(
                    "at most {MAX_DIMENSION} rows (virtual-control axes) are supported, got {n}"
                ),
            ));
        }
        for ((r, c), &v) in b.iter().enumerate().map(|(i, v)| ((i % n, i / n), v)) {
            require_finite(&format!("effectiveness_matrix[{r}, {c}]"), v)?;
        }
        let group_count = binomial(m, n - 1);
        if group_count.saturating_mul(m) > MAX_TABLE_ENTRIES {
            return Err(RfError::invalid(
                "effectiveness_matrix",
                format!(
                    "{m} columns in {n} dimensions give {group_count} facet groups, more than \
                     this enumeration handles ({MAX_TABLE_ENTRIES} table entries)"
                ),
            ));
        }
        let column_norms: Vec<f64> = (0..m).map(|k| scaled_norm(b.column(k).iter())).collect();
        if let Some(k) = column_norms.iter().position(|v| !v.is_finite()) {
            return Err(RfError::invalid(
                format!("effectiveness_matrix[:, {k}]"),
                "too large: the column's norm overflows double precision",
            ));
        }
        // Rank decisions are made on the row-equilibrated matrix `E = D B` (each row scaled by a
        // power of two to unit norm, so exactly and with no rounding): a change of units of any
        // row maps Omega linearly, keeps every facet, and leaves E (hence every decision)
        // unchanged. Then unit columns: the cross product of a group measures its "sine".
        let row_scale = equilibrating_row_scale(b);
        let mut unit = b.clone();
        for (r, &s) in row_scale.iter().enumerate() {
            unit.row_mut(r).scale_mut(s);
        }
        let equilibrated_norms: Vec<f64> =
            (0..m).map(|k| scaled_norm(unit.column(k).iter())).collect();
        for (k, &norm) in equilibrated_norms.iter().enumerate() {
            if norm > 0.0 {
                unit.column_mut(k).unscale_mut(norm);
            }
        }
        let mut out = FacetNormals {
            n,
            m,
            groups: Vec::new(),
            normals: Vec::new(),
            projections: Vec::new(),
            abs_projections: Vec::new(),
            column_norms,
        };
        let mut minor = vec![0.0; (n - 1) * (n - 1)];
        let mut xi = vec![0.0; n];
        let mut normal = vec![0.0; n];
        // With m < n - 1 there is no group at all, and every evaluation reports rank < n.
        for (index, group) in Combinations::new(m, n - 1).enumerate() {
            if index % GROUPS_PER_CHECK == 0 {
                cancel.check()?;
            }
            if group.iter().any(|&k| equilibrated_norms[k] == 0.0) {
                continue; // a zero column: rank B_{1,j} < n - 1
            }
            generalized_cross_product(&unit, &group, &mut minor, &mut xi);
            let norm = scaled_norm(xi.iter());
            if norm <= RANK_RTOL {
                continue; // rank B_{1,j} < n - 1: no facet (Du Step 6)
            }
            xi.iter_mut().for_each(|v| *v /= norm);
            // xi is normal to the group in E's coordinates; D xi is normal to it in B's (for any
            // v, (D xi) . v = xi . (D v)). Distances are reported along the unit normal of B's.
            normal
                .iter_mut()
                .zip(xi.iter().zip(&row_scale))
                .for_each(|(nu, (x, s))| *nu = x * s);
            let normal_norm = scaled_norm(normal.iter());
            normal.iter_mut().for_each(|v| *v /= normal_norm);
            for k in 0..m {
                // The cosine between the equilibrated column and the group's normal decides
                // whether the column lies in the group's hyperplane, by the same scale-free rule.
                let cosine: f64 = if group.contains(&k) || equilibrated_norms[k] == 0.0 {
                    0.0
                } else {
                    (0..n).map(|r| xi[r] * unit[(r, k)]).sum()
                };
                let p = if cosine.abs() <= RANK_RTOL {
                    0.0
                } else {
                    cosine * (equilibrated_norms[k] / normal_norm)
                };
                out.projections.push(p);
                out.abs_projections.push(p.abs());
            }
            out.groups.extend_from_slice(&group);
            out.normals.extend_from_slice(&normal);
        }
        Ok(out)
    }

    /// Virtual-control dimension n.
    pub fn dimension(&self) -> usize {
        self.n
    }

    /// Number of actuators m.
    pub fn actuator_count(&self) -> usize {
        self.m
    }

    /// Number of full-rank column groups kept (Du's `s_m` less the rank-deficient ones).
    pub fn group_count(&self) -> usize {
        self.normals.len() / self.n
    }

    /// Checks the bounds and hover wrench passed to [`FacetNormals::evaluate`].
    pub fn check_bounds_and_g(&self, f_min: &[f64], f_max: &[f64], g: &[f64]) -> Result<()> {
        for (field, v, len, what) in [
            ("f_min", f_min, self.m, "one per actuator"),
            ("f_max", f_max, self.m, "one per actuator"),
            ("g_vec", g, self.n, "one per virtual-control axis"),
        ] {
            require_entries(field, v, len, what)?;
            require_all_finite(field, v)?;
        }
        if let Some(k) = (0..self.m).find(|&k| f_min[k] > f_max[k]) {
            return Err(RfError::invalid(
                format!("f_min[{k}]"),
                format!("must not exceed f_max[{k}] ({} > {})", f_min[k], f_max[k]),
            ));
        }
        // Bounds every sum the evaluation forms, so no overflow can turn into inf or NaN there.
        let size: f64 = (0..self.m)
            .map(|k| self.column_norms[k] * (f_min[k].abs() + f_max[k].abs()))
            .sum::<f64>()
            + g.iter().map(|v| v.abs()).sum::<f64>();
        if !size.is_finite() {
            return Err(RfError::invalid(
                "f_min, f_max, g_vec",
                "too large: sum_k |b_k| (|f_min,k| + |f_max,k|) + |G| overflows double precision",
            ));
        }
        Ok(())
    }

    /// The ACAI for efficiencies `eta` (each in [0, 1]), thrust box `[f_min, f_max]` and hover
    /// wrench `g`, in both readings. Arguments must have passed
    /// [`FacetNormals::check_bounds_and_g`] and [`crate::airframe::check_efficiency`]; this is the
    /// allocation-free hot path.
    pub fn evaluate(&self, eta: &[f64], f_min: &[f64], f_max: &[f64], g: &[f64]) -> AcaiValues {
        let (n, m) = (self.n, self.m);
        // Half-width and centre of each efficiency-scaled thrust interval, once per evaluation so
        // the per-group work is two plain dot products. Small airframes stay on the stack.
        let mut stack = [0.0; 2 * STACK_ROTORS];
        let mut heap = Vec::new();
        let scratch: &mut [f64] = if m <= STACK_ROTORS {
            &mut stack[..2 * m]
        } else {
            heap.resize(2 * m, 0.0);
            &mut heap
        };
        let (half_range, centre_thrust) = scratch.split_at_mut(m);
        for k in 0..m {
            half_range[k] = 0.5 * eta[k] * (f_max[k] - f_min[k]);
            centre_thrust[k] = 0.5 * eta[k] * (f_max[k] + f_min[k]);
        }
        // Each d_j counts as zero within ZERO_RTOL of the problem's size along its own normal,
        // `sum_k |xi_j . b_k| (|f_min,k| + |f_max,k|) / 2 + |xi_j . G|` (nominal columns): a change
        // of units scales d_j and that size by the same factor, so the decision is scale-free.
        // That size never exceeds the same sum with |b_k| and |G|, so it is only formed for the
        // rare d_j within ZERO_RTOL of the latter.
        let coarse_zero = ZERO_RTOL
            * ((0..m)
                .map(|k| self.column_norms[k] * 0.5 * (f_min[k].abs() + f_max[k].abs()))
                .sum::<f64>()
                + scaled_norm(g.iter()));
        let mut full_rank = false;
        // Over the groups without a failed rotor (Du's d_j), and over every group.
        let mut min_d_working = f64::INFINITY;
        let mut min_abs_d_working = f64::INFINITY;
        let mut min_d_all = f64::INFINITY;
        let rows = self
            .normals
            .chunks_exact(n)
            .zip(self.projections.chunks_exact(m))
            .zip(self.abs_projections.chunks_exact(m));
        for (j, ((normal, projections), abs_projections)) in rows.enumerate() {
            let half_width = dot(abs_projections, half_range);
            let centre = dot(projections, centre_thrust);
            let along_g = dot(normal, g);
            let mut d = half_width - (centre - along_g).abs();
            if d.abs() <= coarse_zero {
                let size: f64 = abs_projections
                    .iter()
                    .zip(f_min.iter().zip(f_max))
                    .map(|(p, (lo, hi))| p * 0.5 * (lo.abs() + hi.abs()))
                    .sum::<f64>()
                    + along_g.abs();
                if d.abs() <= ZERO_RTOL * size {
                    d = 0.0;
                }
            }
            min_d_all = min_d_all.min(d);
            let group = &self.groups[j * (n - 1)..(j + 1) * (n - 1)];
            if group.iter().all(|&k| eta[k] != 0.0) {
                // rank B = n iff some group of n - 1 independent working columns has a working
                // column off its hyperplane; settled by the first such group, so checked once.
                full_rank = full_rank
                    || projections
                        .iter()
                        .zip(eta)
                        .any(|(&p, &e)| p != 0.0 && e != 0.0);
                min_d_working = min_d_working.min(d);
                min_abs_d_working = min_abs_d_working.min(d.abs());
            }
        }
        if !full_rank {
            return AcaiValues {
                eq13: f64::NEG_INFINITY,
                facet_margin: f64::NEG_INFINITY,
            };
        }
        // `0.0 - x` rather than `-x`: a snapped zero is +0.0, never -0.0.
        let eq13 = if min_d_working >= 0.0 {
            min_d_working
        } else {
            0.0 - min_abs_d_working
        };
        AcaiValues {
            eq13,
            facet_margin: min_d_all,
        }
    }

    /// ACAI for each row of `etas` (row-major, `m` per row), in parallel. Every row is validated
    /// first; the error names the first bad row and rotor. `cancel` is checked every
    /// [`rows_per_check`] rows (about 1 ms of work).
    pub fn acai_batch(
        &self,
        etas: &[f64],
        f_min: &[f64],
        f_max: &[f64],
        g: &[f64],
        formula: AcaiFormula,
        cancel: &Cancel,
    ) -> Result<Vec<f64>> {
        self.check_batch(etas, f_min, f_max, g)?;
        let mut acai = vec![0.0; etas.len() / self.m];
        self.for_each_block(etas, f_min, f_max, g, &mut acai, cancel, |values, out| {
            *out = values.get(formula);
        })?;
        Ok(acai)
    }

    /// [`FacetNormals::acai_batch`] with where G lies for each row.
    pub fn acai_batch_with_hover(
        &self,
        etas: &[f64],
        f_min: &[f64],
        f_max: &[f64],
        g: &[f64],
        formula: AcaiFormula,
        cancel: &Cancel,
    ) -> Result<AcaiBatch> {
        self.check_batch(etas, f_min, f_max, g)?;
        let mut rows = vec![(0.0, HoverPoint::Inside); etas.len() / self.m];
        self.for_each_block(etas, f_min, f_max, g, &mut rows, cancel, |values, out| {
            *out = (values.get(formula), values.hover());
        })?;
        let (acai, hover) = rows.into_iter().unzip();
        Ok(AcaiBatch { acai, hover })
    }

    /// Each group's `xi_j . G` and zero threshold: what [`FacetNormals::evaluate`] forms per
    /// point but does not depend on the efficiencies (same expressions, so the same bits).
    fn per_group_constants(&self, f_min: &[f64], f_max: &[f64], g: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (n, m) = (self.n, self.m);
        let coarse_zero = ZERO_RTOL
            * ((0..m)
                .map(|k| self.column_norms[k] * 0.5 * (f_min[k].abs() + f_max[k].abs()))
                .sum::<f64>()
                + scaled_norm(g.iter()));
        let along_g: Vec<f64> = self
            .normals
            .chunks_exact(n)
            .map(|normal| dot(normal, g))
            .collect();
        let zero_snap = self
            .abs_projections
            .chunks_exact(m)
            .zip(&along_g)
            .map(|(abs_projections, along)| {
                let size: f64 = abs_projections
                    .iter()
                    .zip(f_min.iter().zip(f_max))
                    .map(|(p, (lo, hi))| p * 0.5 * (lo.abs() + hi.abs()))
                    .sum::<f64>()
                    + along.abs();
                // |d| <= coarse and |d| <= ZERO_RTOL size, as `evaluate` tests it.
                coarse_zero.min(ZERO_RTOL * size)
            })
            .collect();
        (along_g, zero_snap)
    }

    /// [`FacetNormals::evaluate`] for every row of `etas` (row-major, `m` per row) into `eq13` and
    /// `facet_margin` (one per row) on one thread, through the lanes kernel in the compiled form
    /// `path` (bit for bit the same values). Unchecked like `evaluate`; the batches' hot path.
    #[allow(clippy::too_many_arguments)]
    pub fn evaluate_rows(
        &self,
        etas: &[f64],
        f_min: &[f64],
        f_max: &[f64],
        g: &[f64],
        path: LanePath,
        eq13: &mut [f64],
        facet_margin: &mut [f64],
    ) {
        let (along_g, zero_snap) = self.per_group_constants(f_min, f_max, g);
        let table = self.table(&along_g, &zero_snap, f_min, f_max);
        evaluate_rows(&table, etas, eq13, facet_margin, path);
    }

    fn table<'a>(
        &'a self,
        along_g: &'a [f64],
        zero_snap: &'a [f64],
        f_min: &'a [f64],
        f_max: &'a [f64],
    ) -> FacetTable<'a> {
        FacetTable {
            m: self.m,
            groups: &self.groups,
            group_size: self.n - 1,
            projections: &self.projections,
            abs_projections: &self.abs_projections,
            along_g,
            zero_snap,
            f_min,
            f_max,
        }
    }

    /// Evaluates every row of `etas` on the lanes kernel ([`facet_lanes`]) and hands each row's
    /// values to `row(values, out)` (one `out` per row), in parallel blocks of at most
    /// [`ROWS_PER_BLOCK`] rows and at most [`rows_per_check`] rows, checking `cancel` before each.
    #[allow(clippy::too_many_arguments)]
    fn for_each_block<T: Send>(
        &self,
        etas: &[f64],
        f_min: &[f64],
        f_max: &[f64],
        g: &[f64],
        out: &mut [T],
        cancel: &Cancel,
        row: impl Fn(AcaiValues, &mut T) + Sync,
    ) -> Result<()> {
        let (along_g, zero_snap) = self.per_group_constants(f_min, f_max, g);
        let table = self.table(&along_g, &zero_snap, f_min, f_max);
        let path = LanePath::detect();
        // Whole passes of LANES rows: a large table's check interval (a few rows) would otherwise
        // pad each block to a pass and run up to 8 times the work.
        let block = rows_per_check(self.group_count() * self.m)
            .next_multiple_of(LANES)
            .min(ROWS_PER_BLOCK);
        out.par_chunks_mut(block)
            .zip(etas.par_chunks(block * self.m))
            .try_for_each(|(out, etas)| {
                cancel.check()?;
                let mut eq13 = [0.0; ROWS_PER_BLOCK];
                let mut facet_margin = [0.0; ROWS_PER_BLOCK];
                let rows = out.len();
                evaluate_rows(
                    &table,
                    etas,
                    &mut eq13[..rows],
                    &mut facet_margin[..rows],
                    path,
                );
                for ((o, &eq13), &facet_margin) in out.iter_mut().zip(&eq13).zip(&facet_margin) {
                    row(AcaiValues { eq13, facet_margin }, o);
                }
                Ok(())
            })
    }

    fn check_batch(&self, etas: &[f64], f_min: &[f64], f_max: &[f64], g: &[f64]) -> Result<()> {
        self.check_bounds_and_g(f_min, f_max, g)?;
        let m = self.m;
        if !etas.len().is_multiple_of(m) {
            return Err(RfError::shape(
                "efficiencies",
                format!("a multiple of {m} values (N rows of one efficiency per rotor)"),
                etas.len().to_string(),
            ));
        }
        if let Some(i) = etas
            .iter()
            .position(|e| !(e.is_finite() && (0.0..=1.0).contains(e)))
        {
            return Err(RfError::invalid(
                format!("efficiencies[{}, {}] (rotor {})", i / m, i % m, i % m + 1),
                format!("must be finite and lie in [0, 1], got {}", etas[i]),
            ));
        }
        Ok(())
    }
}

/// Rows of an ACAI batch per parallel block (rayon groups blocks further), small enough to share
/// a batch among many threads (the batch used `with_min_len(256)` before blocks existed).
/// A multiple of [`LANES`].
const ROWS_PER_BLOCK: usize = 256;

/// Airframes with at most this many rotors evaluate without touching the heap.
const STACK_ROTORS: usize = 32;

/// Euclidean norm without intermediate overflow or underflow (entries of 1e300 are fine).
pub(crate) fn scaled_norm<'a>(values: impl Iterator<Item = &'a f64> + Clone) -> f64 {
    let largest = values.clone().fold(0.0_f64, |acc, v| acc.max(v.abs()));
    if largest == 0.0 {
        return 0.0;
    }
    largest * values.map(|v| (v / largest).powi(2)).sum::<f64>().sqrt()
}

/// The power of two nearest to `1 / norm` (1 for a zero norm): multiplying by it is exact.
pub(crate) fn inverse_power_of_two(norm: f64) -> f64 {
    if norm > 0.0 && norm.is_finite() {
        2.0_f64.powi(-(norm.log2().round() as i32).clamp(-1000, 1000))
    } else {
        1.0
    }
}

/// Row factors `D` that bring every nonzero row of `b` to unit Euclidean norm within a factor
/// of sqrt(2), as powers of two (so `D b` carries no rounding). Scaling a row of `b` by a power of
/// two leaves `D b` bit for bit unchanged; by any other positive factor, to rounding.
pub fn equilibrating_row_scale(b: &DMatrix<f64>) -> Vec<f64> {
    (0..b.nrows())
        .map(|r| inverse_power_of_two(scaled_norm(b.row(r).iter())))
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// ACAI of an arbitrary effectiveness matrix `b` (n x m, efficiencies already applied), box
/// `[f_min, f_max]` and required wrench `g` (length n).
pub fn acai_from_matrix(
    b: &DMatrix<f64>,
    f_min: &[f64],
    f_max: &[f64],
    g: &[f64],
    formula: AcaiFormula,
) -> Result<f64> {
    Ok(acai_from_matrix_with_hover(b, f_min, f_max, g, formula)?.acai)
}

/// [`acai_from_matrix`] with where G lies.
pub fn acai_from_matrix_with_hover(
    b: &DMatrix<f64>,
    f_min: &[f64],
    f_max: &[f64],
    g: &[f64],
    formula: AcaiFormula,
) -> Result<AcaiResult> {
    acai_from_matrix_cancellable(b, f_min, f_max, g, formula, &Cancel::never())
}

/// [`acai_from_matrix_with_hover`] with the facet enumeration checking `cancel` (up to
/// [`MAX_TABLE_ENTRIES`] entries take seconds).
pub fn acai_from_matrix_cancellable(
    b: &DMatrix<f64>,
    f_min: &[f64],
    f_max: &[f64],
    g: &[f64],
    formula: AcaiFormula,
    cancel: &Cancel,
) -> Result<AcaiResult> {
    let normals = FacetNormals::new_cancellable(b, cancel)?;
    normals.check_bounds_and_g(f_min, f_max, g)?;
    Ok(normals
        .evaluate(&vec![1.0; b.ncols()], f_min, f_max, g)
        .result(formula))
}

#[cfg(test)]
mod lanes_tests;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_in_one_dimension_is_distance_to_nearest_end() {
        // n = 1: Omega = [sum f_min, sum f_max]; G = 3 in [0, 10] -> 3.
        let b = DMatrix::from_row_slice(1, 2, &[1.0, 1.0]);
        assert_eq!(
            acai_from_matrix(&b, &[0.0, 0.0], &[5.0, 5.0], &[3.0], AcaiFormula::Eq13).unwrap(),
            3.0
        );
        assert_eq!(
            acai_from_matrix(&b, &[0.0, 0.0], &[5.0, 5.0], &[12.0], AcaiFormula::Eq13).unwrap(),
            -2.0
        );
        assert_eq!(
            acai_from_matrix(&b, &[0.0, 0.0], &[5.0, 5.0], &[10.0], AcaiFormula::Eq13).unwrap(),
            0.0
        );
    }

    #[test]
    fn eq13_is_zero_where_a_direction_touches_but_margin_sees_the_gap() {
        // Square [0, 1]^2 (identity) and G = (2, 0.5): G is 1 outside the side x = 1.
        // Eq. (13) takes min |d_j| = |0.5 - 0| = 0.5 from the y direction: -0.5, not -1.
        let b = DMatrix::identity(2, 2);
        let g = [2.0, 0.5];
        let eq13 = acai_from_matrix(&b, &[0.0; 2], &[1.0; 2], &g, AcaiFormula::Eq13).unwrap();
        let margin =
            acai_from_matrix(&b, &[0.0; 2], &[1.0; 2], &g, AcaiFormula::FacetMargin).unwrap();
        assert_eq!(eq13, -0.5);
        assert_eq!(margin, -1.0);
    }

    #[test]
    fn square_in_two_dimensions() {
        // Identity 2 x 2 with box [-1, 2]^2 and G = (0, 0.5): nearest side x = -1 at distance 1.
        let b = DMatrix::identity(2, 2);
        let rho = acai_from_matrix(
            &b,
            &[-1.0, -1.0],
            &[2.0, 2.0],
            &[0.0, 0.5],
            AcaiFormula::FacetMargin,
        )
        .unwrap();
        assert!((rho - 1.0).abs() < 1e-15);
    }

    #[test]
    fn rank_deficient_is_negative_infinity() {
        let b = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 2.0, 4.0, 6.0]);
        let rho =
            acai_from_matrix(&b, &[0.0; 3], &[1.0; 3], &[1.0, 2.0], AcaiFormula::Eq13).unwrap();
        assert_eq!(rho, f64::NEG_INFINITY);
        let too_few = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(
            acai_from_matrix(&too_few, &[0.0; 2], &[1.0; 2], &[0.0; 3], AcaiFormula::Eq13).unwrap(),
            f64::NEG_INFINITY
        );
    }

    #[test]
    fn zero_snap_is_per_facet_and_unit_free() {
        // Omega = [0, 1] x [0, 1e-12] (the second row in a tiny unit), G 1e-15 above the bottom
        // side: 1e-3 of that side's extent, clearly inside. One size for the whole problem (~1)
        // read it as "on the boundary"; along its own normal the size is ~1e-12.
        let b = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1e-12]);
        let g = [0.5, 1e-15];
        let result =
            acai_from_matrix_with_hover(&b, &[0.0; 2], &[1.0; 2], &g, AcaiFormula::Eq13).unwrap();
        assert_eq!(result.hover, HoverPoint::Inside);
        assert!((result.acai / 1e-15 - 1.0).abs() < 1e-9, "{result:?}");
        // The same problem with the second row in a unit 1e12 larger.
        let unit = DMatrix::identity(2, 2);
        let result = acai_from_matrix_with_hover(
            &unit,
            &[0.0; 2],
            &[1.0; 2],
            &[0.5, 1e-3],
            AcaiFormula::Eq13,
        )
        .unwrap();
        assert_eq!(result.hover, HoverPoint::Inside);
        assert!((result.acai - 1e-3).abs() < 1e-15);
        // On the side to rounding: exactly +0.0 and on the boundary, in either unit.
        for (b, g) in [(b, [0.5, 0.0]), (unit, [0.5, 1e-3 * 1e-12])] {
            let result =
                acai_from_matrix_with_hover(&b, &[0.0; 2], &[1.0; 2], &g, AcaiFormula::Eq13)
                    .unwrap();
            assert_eq!(result.hover, HoverPoint::OnBoundary, "{g:?}");
            assert!(result.acai == 0.0 && result.acai.is_sign_positive());
        }
    }

    #[test]
    fn row_equilibration_is_exact_and_undoes_units() {
        let b = DMatrix::from_row_slice(2, 3, &[3.0, 4.0, 0.0, 1e-7, 0.0, 2e-7]);
        let scale = equilibrating_row_scale(&b);
        assert!(scale.iter().all(|s| s.log2().fract() == 0.0), "{scale:?}");
        let mut other_units = b.clone();
        other_units.row_mut(1).scale_mut(2f64.powi(40));
        let again = equilibrating_row_scale(&other_units);
        for r in 0..2 {
            for k in 0..3 {
                assert_eq!(b[(r, k)] * scale[r], other_units[(r, k)] * again[r]);
            }
        }
        assert_eq!(equilibrating_row_scale(&DMatrix::zeros(1, 2)), vec![1.0]);
    }

    #[test]
    fn hover_point_classifies_the_margin() {
        assert_eq!(HoverPoint::from_facet_margin(0.1), HoverPoint::Inside);
        assert_eq!(HoverPoint::from_facet_margin(0.0), HoverPoint::OnBoundary);
        assert_eq!(HoverPoint::from_facet_margin(-0.0), HoverPoint::OnBoundary);
        assert_eq!(HoverPoint::from_facet_margin(-1e-300), HoverPoint::Outside);
        assert_eq!(
            HoverPoint::from_facet_margin(f64::NEG_INFINITY),
            HoverPoint::RankDeficient
        );
        let codes: Vec<(i8, &str, bool)> = [
            HoverPoint::Inside,
            HoverPoint::OnBoundary,
            HoverPoint::Outside,
            HoverPoint::RankDeficient,
        ]
        .iter()
        .map(|h| (h.code(), h.name(), h.is_attainable()))
        .collect();
        assert_eq!(
            codes,
            vec![
                (1, "inside", true),
                (0, "boundary", true),
                (-1, "outside", false),
                (-2, "rank-deficient", false)
            ]
        );
    }

    #[test]
    fn bad_bounds_are_rejected() {
        let b = DMatrix::identity(2, 2);
        let err = acai_from_matrix(&b, &[0.0, 3.0], &[1.0, 2.0], &[0.0, 0.0], AcaiFormula::Eq13)
            .unwrap_err();
        assert!(err.to_string().starts_with("f_min[1]"), "{err}");
        let err =
            acai_from_matrix(&b, &[0.0, 0.0], &[1.0, 1.0], &[0.0], AcaiFormula::Eq13).unwrap_err();
        assert!(err.to_string().starts_with("g_vec"), "{err}");
    }

    #[test]
    fn huge_magnitudes_are_rejected_or_exact_never_rounded_to_zero() {
        let b = DMatrix::identity(2, 2);
        let err = acai_from_matrix(&b, &[-1e308; 2], &[1e308; 2], &[0.0; 2], AcaiFormula::Eq13)
            .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("f_min, f_max, g_vec: too large"),
            "{err}"
        );
        // Large but representable: the square [0, 1e300]^2 seen from its centre.
        let big = DMatrix::identity(2, 2) * 1e300;
        let rho =
            acai_from_matrix(&big, &[0.0; 2], &[1.0; 2], &[0.5e300; 2], AcaiFormula::Eq13).unwrap();
        assert!((rho / 0.5e300 - 1.0).abs() < 1e-12, "{rho}");
        let column = DMatrix::from_row_slice(2, 1, &[1.5e308, 1.5e308]);
        let err = FacetNormals::new(&column).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("effectiveness_matrix[:, 0]: too large"),
            "{err}"
        );
    }

    #[test]
    fn dimension_is_bounded_before_any_allocation() {
        let tall = DMatrix::from_element(200_000, 1, 1.0);
        let err = FacetNormals::new(&tall).unwrap_err();
        assert!(err.to_string().contains("at most 12 rows"), "{err}");
    }
}
