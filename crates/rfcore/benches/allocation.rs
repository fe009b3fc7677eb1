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
//! - `allocation/active_set_uncertified/<m>`: the same cold solves without the certificate
//!   ([`rfcore::fixtures::solve_uncertified`]: phases 1 and 2 only), the baseline of the
//!   certificate's cost;
//! - `allocation/active_set_warm/<m>`: the virtual controls as a slowly varying sequence, each
//!   solve warm-started from the previous active set (the closed-loop case);
//! - `allocation/clarabel/<m>`: the Clarabel reference (setup + solve, default settings);
//! - `allocation_ill/active_set_cold`: the ill-conditioned class (4 x m, m = 4..8, one
//!   column scaled by 10^-k, k = 4..12, weights in [0.01, 30]), every solve from an empty active
//!   set on its own prepared solver.
//!
//! Before the criterion groups, a table is printed (the issues' targets, like
//! `benches/allocation_clarabel.py`): per airframe, 500 random virtual controls (half attainable,
//! half beyond), the median and 90th percentile over problems of the per-solve time (cold start,
//! mean of 200 repeats per problem) of the certified solve ([`ActiveSetSolver::solve_unchecked`])
//! and, timed right after it on the same problem, of the uncertified one
//! ([`rfcore::fixtures::solve_uncertified`]), the same for Clarabel (5 repeats, [`time_each`]),
//! the ratios clarabel / certified and certified / uncertified (of the medians), and the fallback
//! count; then the ill-conditioned class's median time and fallback rate. Targets (issue 32):
//! certified >= 100x clarabel for 4, 6 and 8 rotors, and within 1.2x of uncertified.

use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rfcore::allocation::active_set::{ActiveSet, ActiveSetSolver};
use rfcore::allocation::allocate_clarabel;
use rfcore::allocation::clarabel::ClarabelSettings;
use rfcore::allocation::{AllocationProblem, Method, SolvedBy};
use rfcore::fixtures::{ill_conditioned_allocation, solve_uncertified, time_each, Rng};
use rfcore::{Airframe, Cancel};

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
        group.bench_function(format!("active_set_uncertified/{m}"), |b| {
            b.iter(|| {
                for u in &controls {
                    let mut active = ActiveSet::cold(m);
                    black_box(solve_uncertified(
                        &solver,
                        black_box(u),
                        &mut active,
                        &mut commands,
                    ));
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

const RANDOM_PROBLEMS: usize = 500;

/// As `benches/allocation_clarabel.py`: half `M T` for a random T in the box, half twice such a
/// point plus noise (beyond the attainable set), flattened row after row.
fn random_controls(airframe: &Airframe, problem: &AllocationProblem, rng: &mut Rng) -> Vec<f64> {
    let (lo, hi) = (airframe.min_thrust_n(), airframe.max_thrust_n());
    let noise = [5.0, 0.5, 0.5, 0.05];
    let mut out = Vec::with_capacity(4 * RANDOM_PROBLEMS);
    for k in 0..RANDOM_PROBLEMS {
        let t: Vec<f64> = (0..lo.len()).map(|i| rng.uniform(lo[i], hi[i])).collect();
        let inside = problem.achieved(&t);
        for r in 0..4 {
            out.push(if k < RANDOM_PROBLEMS / 2 {
                inside[r]
            } else {
                2.0 * inside[r] + rng.normal() * noise[r]
            });
        }
    }
    out
}

fn median_p90(mut times: Vec<f64>) -> (f64, f64) {
    times.sort_by(f64::total_cmp);
    let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize];
    (at(0.5), at(0.9))
}

/// The ill-conditioned class (as `ill_conditioned_columns_are_certified_and_exact`):
/// `per_k` problems for each k = 4..12.
fn ill_conditioned(per_k: usize) -> Vec<(AllocationProblem, Vec<f64>)> {
    let mut rng = Rng(2020);
    let mut out = Vec::new();
    for k in 4..=12 {
        for _ in 0..per_k {
            let (p, u_c) = ill_conditioned_allocation(&mut rng, k);
            out.push((p, u_c));
        }
    }
    out
}

/// Mean seconds of one call of `solve` over `repeats` calls in a row.
fn mean_seconds(repeats: usize, mut solve: impl FnMut()) -> f64 {
    let start = Instant::now();
    for _ in 0..repeats {
        solve();
    }
    start.elapsed().as_secs_f64() / repeats as f64
}

/// The issues' targets, printed once: medians over problems of per-solve times.
fn report_targets(_: &mut Criterion) {
    const REPEATS: usize = 200;
    let mut rng = Rng(2026);
    println!("\n{RANDOM_PROBLEMS} random problems per airframe (half beyond the attainable set), per-solve time, cold start, median / p90 over problems");
    println!(
        "{:<12} {:>2} {:>20} {:>20} {:>22} {:>9} {:>11} {:>7} {:>9} {:>6}",
        "airframe",
        "m",
        "certified",
        "uncertified",
        "clarabel (Rust)",
        "clarabel/",
        "certified/",
        "bounds",
        "fallback",
        "iters"
    );
    println!(
        "{:<12} {:>2} {:>20} {:>20} {:>22} {:>9} {:>11}",
        "", "", "", "", "", "certified", "uncertified"
    );
    let mut met = true;
    for name in ["quad-x", "hexa-pnpnpn", "octo-x"] {
        let airframe = rfcore::fixtures::preset(name);
        let m = airframe.rotor_count();
        let problem = problem(&airframe);
        let controls = random_controls(&airframe, &problem, &mut rng);
        let solver = ActiveSetSolver::new(&problem);
        let (mut fallbacks, mut saturated, mut iterations) = (0, 0, 0);
        let mut commands = vec![0.0; m];
        let (mut certified, mut uncertified) = (Vec::new(), Vec::new());
        for u in controls.chunks(4) {
            let mut active = ActiveSet::cold(m);
            let report = solver.solve_unchecked(u, &mut active, &mut commands);
            fallbacks += usize::from(report.solved_by == SolvedBy::Clarabel);
            iterations += report.iterations;
            saturated += usize::from(
                active
                    .states()
                    .iter()
                    .any(|s| *s != rfcore::allocation::active_set::BoundState::Free),
            );
            // The same problem, back to back: the two differ only by the certificate.
            certified.push(mean_seconds(REPEATS, || {
                let mut active = ActiveSet::cold(m);
                black_box(solver.solve_unchecked(black_box(u), &mut active, &mut commands));
            }));
            uncertified.push(mean_seconds(REPEATS, || {
                let mut active = ActiveSet::cold(m);
                black_box(solve_uncertified(
                    &solver,
                    black_box(u),
                    &mut active,
                    &mut commands,
                ));
            }));
        }
        let ours = median_p90(certified);
        let bare = median_p90(uncertified);
        let clarabel = Method::Clarabel(ClarabelSettings::default());
        let theirs =
            median_p90(time_each(&problem, &clarabel, &controls, 5, &Cancel::never()).unwrap());
        let (speedup, cost) = (theirs.0 / ours.0, ours.0 / bare.0);
        println!(
            "{name:<12} {m:>2} {:>8.0} / {:>6.0} ns {:>8.0} / {:>6.0} ns {:>9.1} / {:>6.1} us {:>8.0}x {:>10.2}x {:>6.0}% {:>9} {:>6.2}",
            ours.0 * 1e9,
            ours.1 * 1e9,
            bare.0 * 1e9,
            bare.1 * 1e9,
            theirs.0 * 1e6,
            theirs.1 * 1e6,
            speedup,
            cost,
            100.0 * saturated as f64 / RANDOM_PROBLEMS as f64,
            fallbacks,
            iterations as f64 / RANDOM_PROBLEMS as f64
        );
        met &= speedup >= 100.0 && cost <= 1.2;
    }
    println!(
        "targets (issue 32: certified >= 100x clarabel and <= 1.2x uncertified): {}",
        if met { "met" } else { "NOT met" }
    );

    let cases = ill_conditioned(100);
    let mut times = Vec::with_capacity(cases.len());
    let mut fallbacks = 0;
    for (p, u) in &cases {
        let solver = ActiveSetSolver::new(p);
        let mut commands = vec![0.0; p.actuator_count()];
        let mut active = ActiveSet::cold(p.actuator_count());
        let report = solver.solve_unchecked(u, &mut active, &mut commands);
        fallbacks += usize::from(report.solved_by == SolvedBy::Clarabel);
        times.push(
            time_each(
                p,
                &Method::ActiveSet(Default::default()),
                u,
                50,
                &Cancel::never(),
            )
            .unwrap()[0],
        );
    }
    let (median, p90) = median_p90(times);
    println!(
        "ill-conditioned class (k = 4..12, m = 4..8, {} problems): median {:.0} ns, p90 {:.0} ns per solve, fallback rate {:.1}% ({fallbacks})\n",
        cases.len(),
        median * 1e9,
        p90 * 1e9,
        100.0 * fallbacks as f64 / cases.len() as f64
    );
}

fn bench_ill_conditioned(c: &mut Criterion) {
    let cases = ill_conditioned(20);
    let solvers: Vec<(ActiveSetSolver, &[f64])> = cases
        .iter()
        .map(|(p, u)| (ActiveSetSolver::new(p), u.as_slice()))
        .collect();
    let mut group = c.benchmark_group("allocation_ill");
    group.throughput(Throughput::Elements(solvers.len() as u64));
    let mut commands = vec![0.0; 8];
    group.bench_function("active_set_cold", |b| {
        b.iter(|| {
            for (solver, u) in &solvers {
                let m = solver.problem().actuator_count();
                let mut active = ActiveSet::cold(m);
                black_box(solver.solve_unchecked(black_box(u), &mut active, &mut commands[..m]));
            }
        })
    });
    group.finish();
}

criterion_group!(
    benches,
    report_targets,
    bench_allocation,
    bench_ill_conditioned
);
criterion_main!(benches);
