//! Tests of the factorisation's fast paths against its general code. A file of its own: they draw
//! problems from `crate::fixtures`, which builds allocators, so inside `factorisation.rs` they
//! would close an import circle (checked by `tests/architecture.rs`).

use crate::allocation::factorisation::FreeSetFactor;
use crate::allocation::scaling::{ScaledLeastSquares, BIG_WORK, N, ROWS, SMALL_WORK};
use crate::fixtures::{ill_conditioned_allocation, Rng};

/// The step from a factorisation made beforehand (the solver's all-free factor) and from
/// the 4-row instance equals the step of the general code, bit for bit: the same
/// operations on the same numbers, in the same order (the solver's answers depend on it).
#[test]
fn stored_factor_and_four_row_instance_give_the_general_step_exactly() {
    let mut rng = Rng(32);
    for case in 0..200 {
        let (problem, _) = ill_conditioned_allocation(&mut rng, (case % 13) as i32);
        let scaled = ScaledLeastSquares::new(&problem);
        assert_eq!(scaled.rows, 4);
        let m = scaled.m;
        let mut r = [0.0; ROWS];
        let mut t = [0.0; N];
        for x in &mut r[..4] {
            *x = rng.normal();
        }
        for x in &mut t[..m] {
            *x = rng.uniform(0.0, 2.0);
        }
        // All columns, then a random subset of at least one.
        let all: Vec<usize> = (0..m).collect();
        let some: Vec<usize> = (0..m).filter(|_| rng.below(3) > 0).collect();
        for free in [all, some] {
            if free.is_empty() {
                continue;
            }
            let mut general = [0.0; N];
            let rank = scaled.lsq_step::<BIG_WORK, 0>(&free, &r, &t, &mut general);
            let mut factor = FreeSetFactor::<SMALL_WORK>::empty();
            scaled.factor_free_set::<SMALL_WORK, 0>(&free, &mut factor);
            let mut stored = [0.0; N];
            let stored_rank =
                scaled.factored_step::<SMALL_WORK, 4>(&free, &factor, &r, &t, &mut stored);
            let mut unrolled = [0.0; N];
            scaled.lsq_step::<SMALL_WORK, 4>(&free, &r, &t, &mut unrolled);
            assert_eq!(stored_rank, rank);
            for i in 0..m {
                assert_eq!(stored[i].to_bits(), general[i].to_bits(), "case {case}");
                assert_eq!(unrolled[i].to_bits(), general[i].to_bits(), "case {case}");
            }
        }
    }
}
