//! Criterion benchmarks of the ACAI core (Du et al., JGCD 2015, Theorem 3).
//!
//! Run from the workspace root with `cargo bench` (add `-- --warm-up-time 1 --measurement-time 3`
//! for a quick run, or `-- acai/batch` to select one group). The Python-side comparison with
//! NumPy lives in `benches/acai_grid.py`.
//!
//! - `acai/single/hexa-pnpnpn`: one evaluation for one efficiency vector through the public
//!   `ControllabilityAnalysis::acai` (includes the efficiency-vector validation);
//! - `acai/analysis_new/hexa-pnpnpn`: building the analysis once (facet enumeration over the
//!   C(6, 3) = 20 column groups, hover model, controllability rank by SVD);
//! - `acai/batch/fig4-grid`: `acai_batch` over Du's Fig. 4 grid (eta1, eta2, eta5 in
//!   {0, 0.04, ..., 1}, other rotors healthy; 26^3 = 17,576 rows), parallel via rayon;
//! - `acai/single/octo-x`: one evaluation for the octocopter (C(8, 3) = 56 groups);
//! - `acai/evaluate_unchecked/*`: the same two evaluations through `FacetNormals::evaluate`, the
//!   allocation-free hot path that `acai_batch` runs per row, without the per-call efficiency
//!   validation of `ControllabilityAnalysis::acai` (the gap between the two is that validation).
//!
//! Note: `cargo bench -- <criterion flags>` also passes the flags to the library's unit-test
//! harness, which rejects them; use `cargo bench --bench acai -- <flags>` for that.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rfcore::analysis::{AcaiFormula, ControlAxes, ControllabilityAnalysis, FacetNormals, LanePath};
use rfcore::{Airframe, Cancel};

/// Du's Fig. 4 grid: eta1, eta2, eta5 (1-based) in {0, 0.04, ..., 1}, the other rotors at 1.
/// Row-major, 6 per row, 26^3 rows.
fn fig4_grid() -> Vec<f64> {
    let levels: Vec<f64> = (0..=25).map(|i| i as f64 * 0.04).collect();
    let mut etas = Vec::with_capacity(levels.len().pow(3) * 6);
    for &e1 in &levels {
        for &e2 in &levels {
            for &e5 in &levels {
                etas.extend_from_slice(&[e1, e2, 1.0, 1.0, e5, 1.0]);
            }
        }
    }
    etas
}

fn bench_acai(c: &mut Criterion) {
    let hexa = rfcore::fixtures::preset("hexa-pnpnpn");
    let octo = rfcore::fixtures::preset("octo-x");
    let axes = ControlAxes::ThrustRollPitchYaw;
    let hexa_analysis = ControllabilityAnalysis::new(&hexa, axes).expect("hexa analysis");
    let octo_analysis = ControllabilityAnalysis::new(&octo, axes).expect("octo analysis");

    // Sanity checks before timing: Du Table II gives 1.4861 for the healthy PNPNPN hexacopter.
    let healthy = hexa_analysis.acai(&[1.0; 6], AcaiFormula::Eq13).unwrap();
    assert!(
        (healthy - 1.4861).abs() < 5e-4,
        "healthy hexa-pnpnpn ACAI = {healthy}"
    );
    let grid = fig4_grid();
    let rows = grid.len() / 6;
    assert_eq!(rows, 17_576);
    let values = hexa_analysis
        .acai_batch(&grid, AcaiFormula::Eq13, &Cancel::never())
        .unwrap();
    assert_eq!(values.len(), rows);

    let mut group = c.benchmark_group("acai");

    // (b) Building the analysis: facet enumeration + hover model + rank of C(A, B). No throughput:
    // this is not an ACAI evaluation.
    group.bench_function("analysis_new/hexa-pnpnpn", |b| {
        b.iter(|| ControllabilityAnalysis::new(black_box(&hexa), black_box(axes)).unwrap())
    });

    // (a) One evaluation, a partially degraded efficiency vector (nothing failed, so every group
    // counts and nothing short-circuits).
    let eta_hexa = [0.8, 0.6, 1.0, 1.0, 0.9, 1.0];
    group.throughput(Throughput::Elements(1));
    group.bench_function("single/hexa-pnpnpn", |b| {
        b.iter(|| {
            hexa_analysis
                .acai(black_box(&eta_hexa), black_box(AcaiFormula::Eq13))
                .unwrap()
        })
    });

    // (d) The same for the octocopter.
    let eta_octo = [0.8, 0.6, 1.0, 1.0, 0.9, 1.0, 0.7, 1.0];
    group.bench_function("single/octo-x", |b| {
        b.iter(|| {
            octo_analysis
                .acai(black_box(&eta_octo), black_box(AcaiFormula::Eq13))
                .unwrap()
        })
    });

    // The hot path without validation, for reference.
    for (label, airframe, eta, analysis) in [
        ("hexa-pnpnpn", &hexa, &eta_hexa[..], &hexa_analysis),
        ("octo-x", &octo, &eta_octo[..], &octo_analysis),
    ] {
        let (normals, f_min, f_max, g) = hot_path(airframe);
        let checked = analysis.acai(eta, AcaiFormula::Eq13).unwrap();
        let unchecked = normals.evaluate(eta, &f_min, &f_max, &g).eq13;
        assert_eq!(
            checked.to_bits(),
            unchecked.to_bits(),
            "{label}: {checked} vs {unchecked}"
        );
        group.bench_function(format!("evaluate_unchecked/{label}"), |b| {
            b.iter(|| {
                normals.evaluate(
                    black_box(eta),
                    black_box(&f_min),
                    black_box(&f_max),
                    black_box(&g),
                )
            })
        });
    }

    // (c) The Fig. 4 grid in one parallel batch (the analysis is built outside the loop).
    group.throughput(Throughput::Elements(rows as u64));
    let never = Cancel::never();
    group.bench_function("batch/fig4-grid", |b| {
        b.iter(|| {
            hexa_analysis
                .acai_batch(black_box(&grid), black_box(AcaiFormula::Eq13), &never)
                .unwrap()
        })
    });

    // The facet evaluation over the grid on one thread: the scalar path row by row, then the
    // lanes kernel in each compiled form this CPU runs (the batch's path). Ratios: scalar / lanes.
    let (normals, f_min, f_max, g) = hot_path(&hexa);
    let mut eq13 = vec![0.0; rows];
    let mut margin = vec![0.0; rows];
    group.bench_function("rows_scalar/fig4-grid", |b| {
        b.iter(|| {
            for (out, eta) in eq13.iter_mut().zip(grid.chunks_exact(6)) {
                *out = normals.evaluate(black_box(eta), &f_min, &f_max, &g).eq13;
            }
            black_box(&eq13);
        })
    });
    for path in [LanePath::Portable, LanePath::Avx2] {
        if !path.is_available() {
            continue;
        }
        normals.evaluate_rows(&grid, &f_min, &f_max, &g, path, &mut eq13, &mut margin);
        assert_eq!(eq13, values, "{path:?}");
        group.bench_function(
            format!("rows_lanes_{path:?}/fig4-grid").to_lowercase(),
            |b| {
                b.iter(|| {
                    normals.evaluate_rows(
                        black_box(&grid),
                        &f_min,
                        &f_max,
                        &g,
                        path,
                        &mut eq13,
                        &mut margin,
                    );
                })
            },
        );
    }

    group.finish();
}

/// `FacetNormals` and the box / hover wrench for Du's four axes, as `ControllabilityAnalysis` builds them.
fn hot_path(airframe: &Airframe) -> (FacetNormals, Vec<f64>, Vec<f64>, Vec<f64>) {
    let normals =
        FacetNormals::new(&airframe.nominal_effectiveness_matrix()).expect("facet normals");
    (
        normals,
        airframe.min_thrust_n(),
        airframe.max_thrust_n(),
        airframe.hover_wrench().to_vec(),
    )
}

criterion_group!(benches, bench_acai);
criterion_main!(benches);
