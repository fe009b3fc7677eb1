//! The ACAI facet evaluation over lanes of efficiency vectors: the batch hot path.
//!
//! [`crate::analysis::FacetNormals::evaluate`] takes one efficiency vector at a time (the scalar
//! path, the reference). A batch instead hands [`evaluate_rows`] a block of rows: they are
//! transposed into structure-of-arrays form, [`LANES`] points per pass, so that every per-group
//! operation (two dot products over the rotors, the distance, the zero snap, three running
//! minima and the rank flags) runs across the points in SIMD registers. What does not depend on
//! the efficiencies (each facet's `xi_j . G` and its zero threshold) is computed once per batch
//! by the caller ([`FacetTable`]), not once per point.
//!
//! Every lane does exactly the scalar path's floating-point operations in the same order (no
//! fused multiply-add, the same summation order), so the two paths agree bit for bit; the tests
//! check it on grids with failed rotors. On x86-64 with AVX2 (detected at run time) the kernel is
//! compiled for 4 f64 per register; elsewhere the same source runs with the baseline's registers
//! ([`LanePath`]).

/// Points evaluated together: two AVX2 registers of 4 f64, so the two dot products' add chains
/// of one group overlap with the next pass's.
pub const LANES: usize = 8;

/// What the per-point work reads, all independent of the efficiencies.
#[derive(Debug, Clone, Copy)]
pub struct FacetTable<'a> {
    /// Number of actuators m.
    pub m: usize,
    /// Column indices of each group, `group_size` per group.
    pub groups: &'a [usize],
    /// Columns per group (n - 1).
    pub group_size: usize,
    /// `xi_j . b_k`, `m` per group (exactly zero for the group's own columns).
    pub projections: &'a [f64],
    /// `|xi_j . b_k|`, the same layout.
    pub abs_projections: &'a [f64],
    /// `xi_j . G`, one per group.
    pub along_g: &'a [f64],
    /// `|d_j|` at or below this counts as zero, one per group.
    pub zero_snap: &'a [f64],
    /// The thrust box, one per actuator.
    pub f_min: &'a [f64],
    pub f_max: &'a [f64],
}

/// Which compiled form of the kernel runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LanePath {
    /// The same kernel compiled for the target's baseline registers (SSE2 on x86-64): runs
    /// everywhere.
    Portable,
    /// Compiled for AVX2 (4 f64 per register; the flight room's laned code for AVX2 and FMA,
    /// which changes no result: Rust contracts no `a * b + c`); only chosen when the CPU has
    /// what it is compiled for.
    Avx2,
}

impl LanePath {
    /// The fastest form this CPU runs.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return LanePath::Avx2;
        }
        LanePath::Portable
    }

    /// Whether this CPU can run the form.
    pub fn is_available(self) -> bool {
        match self {
            LanePath::Portable => true,
            LanePath::Avx2 => LanePath::detect() == LanePath::Avx2,
        }
    }
}

/// Eq. (13) and the facet margin of each row of `etas` (row-major, `table.m` per row, already
/// validated) into `eq13` and `facet_margin` (one per row), on `path` (which must be available:
/// otherwise the portable form runs).
pub fn evaluate_rows(
    table: &FacetTable<'_>,
    etas: &[f64],
    eq13: &mut [f64],
    facet_margin: &mut [f64],
    path: LanePath,
) {
    #[cfg(target_arch = "x86_64")]
    if path == LanePath::Avx2 && path.is_available() {
        // SAFETY: the CPU has AVX2 (checked at run time just above).
        unsafe { evaluate_rows_avx2(table, etas, eq13, facet_margin) };
        return;
    }
    let _ = path;
    evaluate_rows_lanes(table, etas, eq13, facet_margin);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn evaluate_rows_avx2(
    table: &FacetTable<'_>,
    etas: &[f64],
    eq13: &mut [f64],
    margin: &mut [f64],
) {
    evaluate_rows_lanes(table, etas, eq13, margin);
}

/// Per-rotor columns of one pass, reused across passes (no allocation per point).
struct Scratch {
    half_range: Vec<[f64; LANES]>,
    centre_thrust: Vec<[f64; LANES]>,
    working: Vec<[bool; LANES]>,
}

#[inline(always)]
fn evaluate_rows_lanes(table: &FacetTable<'_>, etas: &[f64], eq13: &mut [f64], margin: &mut [f64]) {
    let m = table.m;
    let mut scratch = Scratch {
        half_range: vec![[0.0; LANES]; m],
        centre_thrust: vec![[0.0; LANES]; m],
        working: vec![[false; LANES]; m],
    };
    let full = etas.len() / m / LANES * LANES;
    for start in (0..full).step_by(LANES) {
        let rows = &etas[start * m..(start + LANES) * m];
        let (e, f) = pass(table, rows, &mut scratch);
        eq13[start..start + LANES].copy_from_slice(&e);
        margin[start..start + LANES].copy_from_slice(&f);
    }
    let tail = eq13.len() - full;
    if tail > 0 {
        // The last rows padded with healthy rotors; the padding's values are dropped.
        let mut padded = etas[full * m..].to_vec();
        padded.resize(LANES * m, 1.0);
        let (e, f) = pass(table, &padded, &mut scratch);
        eq13[full..].copy_from_slice(&e[..tail]);
        margin[full..].copy_from_slice(&f[..tail]);
    }
}

/// One pass over [`LANES`] rows: the scalar path's operations, lane by lane.
#[inline(always)]
fn pass(table: &FacetTable<'_>, rows: &[f64], s: &mut Scratch) -> ([f64; LANES], [f64; LANES]) {
    let m = table.m;
    for k in 0..m {
        let (lo, hi) = (table.f_min[k], table.f_max[k]);
        for l in 0..LANES {
            let e = rows[l * m + k];
            s.half_range[k][l] = 0.5 * e * (hi - lo);
            s.centre_thrust[k][l] = 0.5 * e * (hi + lo);
            s.working[k][l] = e != 0.0;
        }
    }
    let mut full_rank = [false; LANES];
    let mut min_d_working = [f64::INFINITY; LANES];
    let mut min_abs_d_working = [f64::INFINITY; LANES];
    let mut min_d_all = [f64::INFINITY; LANES];
    let groups = table.along_g.len();
    for j in 0..groups {
        let projections = &table.projections[j * m..(j + 1) * m];
        let abs_projections = &table.abs_projections[j * m..(j + 1) * m];
        // `Sum` of f64 starts from -0.0; so do these.
        let mut half_width = [-0.0; LANES];
        let mut centre = [-0.0; LANES];
        let mut leaves = [false; LANES];
        for k in 0..m {
            let (p, abs_p) = (projections[k], abs_projections[k]);
            for l in 0..LANES {
                half_width[l] += abs_p * s.half_range[k][l];
                centre[l] += p * s.centre_thrust[k][l];
            }
            if p != 0.0 {
                for l in 0..LANES {
                    leaves[l] |= s.working[k][l];
                }
            }
        }
        let mut valid = [true; LANES];
        for &k in &table.groups[j * table.group_size..(j + 1) * table.group_size] {
            for l in 0..LANES {
                valid[l] &= s.working[k][l];
            }
        }
        let (along_g, snap) = (table.along_g[j], table.zero_snap[j]);
        for l in 0..LANES {
            let d = half_width[l] - (centre[l] - along_g).abs();
            let d = if d.abs() <= snap { 0.0 } else { d };
            min_d_all[l] = min_d_all[l].min(d);
            full_rank[l] |= valid[l] & leaves[l];
            let (dw, aw) = if valid[l] {
                (d, d.abs())
            } else {
                (f64::INFINITY, f64::INFINITY)
            };
            min_d_working[l] = min_d_working[l].min(dw);
            min_abs_d_working[l] = min_abs_d_working[l].min(aw);
        }
    }
    let mut eq13 = [0.0; LANES];
    let mut margin = [0.0; LANES];
    for l in 0..LANES {
        if full_rank[l] {
            // `0.0 - x` rather than `-x`: a snapped zero is +0.0, never -0.0.
            eq13[l] = if min_d_working[l] >= 0.0 {
                min_d_working[l]
            } else {
                0.0 - min_abs_d_working[l]
            };
            margin[l] = min_d_all[l];
        } else {
            eq13[l] = f64::NEG_INFINITY;
            margin[l] = f64::NEG_INFINITY;
        }
    }
    (eq13, margin)
}
