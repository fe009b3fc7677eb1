//! Criterion benchmarks of constrained control allocation: the active-set solver (cold and warm
//! started) against Clarabel on the same problems.
//!
//! Run from the workspace root with `cargo bench --bench allocation` (add
//! `-- --warm-up-time 1 --measurement-time 3` for a quick run). Per airframe (quad-x, hexa-pnpnpn,
//! octo-x: 4, 6 and 8 rotors) the problem is Ke et al. eq. (33) with Table IV's weight ordering
//! (`W = diag(1, 20, 20, 0.01)`, thrust bounds [0, f_max]) and a fixed set of 256 virtual
//! controls around hover, a third of them (in runs of 32) beyond what the rotors can give (bounds active).
//! One iteration solves all 256 (`Throughput::Elements(256)`), so "time" / 256 is the mean per
//! solve. `benches/allocation_clarabel.py` reports per-problem medians and the Python package.
//!
//! - `allocation/active_set_cold/<m>`: every solve from an empty active set;
//! - `allocation/active_set_warm/<m>`: the virtual controls as a slowly varying sequence, each
//!   solve warm-started from the previous active set (the closed-loop case);
//! - `allocation/clarabel/<m>`: the Clarabel reference (setup + solve, default settings).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rfcore::allocation::active_set::{ActiveSet, ActiveSetSolver};
use rfcore::allocation::AllocationProblem;
use rfcore::Airframe;
use rfcore::allocation::clarabel::{allocate_clarabel, ClarabelSettings};

const PROBLEMS: usize = 256;


fn problem(airframe: &Airframe) -> AllocationProblem {
    AllocationProblem::new(
        airframe.effectiveness_matrix(),
        &[1.0, 20.0, 20.0, 0.01],
        &airframe.min_thrust_n(),
        &airframe.max_thrust_n(),
    )
    .expect("valid problem")
}

/// Hover wrench plus a sinusoidal sweep; every third point scaled up to saturate the rotors.
fn virtual_controls(airframe: &Airframe) -> Vec<[f64; 4]> {
    let hover = airframe.hover_wrench()[0];
    let max_total: f64 = airframe.max_thrust_n().iter().sum();
    (0..PROBLEMS)
        .map(|k| {
            let phase = k as f64 * 0.05;
            // Saturating stretches come in runs, so the warm-started sequence varies slowly.
            let gain = if (k / 32) % 3 == 0 { 6.0 } else { 1.0 };
            [
                hover + 0.1 * max_total * phase.sin(),
                gain * 0.3 * phase.cos(),
                gain * 0.3 * (1.3 * phase).sin(),
                gain * 0.05 * (0.7 * phase).cos(),
            ]
        })
        .collect()
}

fn bench_allocation(c: &mut Criterion) {
    let mut group = c.benchmark_group("allocation");
    group.throughput(Throughput::Elements(PROBLEMS as u64));
    for name in ["quad-x", "hexa-pnpnpn", "octo-x"] {
        let airframe = rfcore::fixtures::preset(name);
        let m = airframe.rotor_count();
        let problem = problem(&airframe);
        let controls = virtual_controls(&airframe);
        let solver = ActiveSetSolver::new(&problem);
        let mut commands = vec![0.0; m];
        group.bench_function(format!("active_set_cold/{m}"), |b| {
            b.iter(|| {
                for u in &controls {
                    let mut active = ActiveSet::cold(m);
                    black_box(solver.solve_unchecked(black_box(u), &mut active, &mut commands));
                }
            })
        });
        group.bench_function(format!("active_set_warm/{m}"), |b| {
            let mut active = ActiveSet::cold(m);
            b.iter(|| {
                for u in &controls {
                    black_box(solver.solve_unchecked(black_box(u), &mut active, &mut commands));
                }
            })
        });
        let settings = ClarabelSettings::default();
        group.bench_function(format!("clarabel/{m}"), |b| {
            b.iter(|| {
                for u in &controls {
                    black_box(
                        allocate_clarabel(&problem, black_box(u), &settings).expect("solves"),
                    );
                }
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_allocation);
criterion_main!(benches);
