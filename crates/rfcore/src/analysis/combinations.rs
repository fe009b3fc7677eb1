//! Lexicographic k-combinations of 0..n, the index sets S_1 of Du et al. Section IV.A.

/// Iterator over all k-subsets of `0..n` in lexicographic order (`S_1` rows of Du eq. (10)).
#[derive(Debug, Clone)]
pub struct Combinations {
    n: usize,
    current: Vec<usize>,
    done: bool,
}

impl Combinations {
    pub fn new(n: usize, k: usize) -> Self {
        Combinations {
            n,
            current: (0..k).collect(),
            done: k > n,
        }
    }
}

impl Iterator for Combinations {
    type Item = Vec<usize>;

    fn next(&mut self) -> Option<Vec<usize>> {
        if self.done {
            return None;
        }
        let out = self.current.clone();
        let k = self.current.len();
        // Advance: find the rightmost index that can still move right.
        let mut i = k;
        loop {
            if i == 0 {
                self.done = true;
                break;
            }
            i -= 1;
            if self.current[i] < self.n - k + i {
                self.current[i] += 1;
                for j in i + 1..k {
                    self.current[j] = self.current[j - 1] + 1;
                }
                break;
            }
        }
        Some(out)
    }
}

/// Binomial coefficient n choose k (saturating; used to size enumerations before running them).
pub fn binomial(n: usize, k: usize) -> usize {
    if k > n {
        return 0;
    }
    let k = k.min(n - k);
    let mut acc: u128 = 1;
    for i in 0..k {
        acc = acc * (n - i) as u128 / (i + 1) as u128;
        if acc > usize::MAX as u128 {
            return usize::MAX;
        }
    }
    acc as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn du_example_m4_matches_s1() {
        // Du Section IV.A prints S_1 for m = 4: {123, 124, 134, 234} (1-based).
        let rows: Vec<Vec<usize>> = Combinations::new(4, 3).collect();
        assert_eq!(
            rows,
            vec![vec![0, 1, 2], vec![0, 1, 3], vec![0, 2, 3], vec![1, 2, 3]]
        );
    }

    #[test]
    fn counts_match_binomial() {
        for n in 0..9 {
            for k in 0..=n + 1 {
                assert_eq!(
                    Combinations::new(n, k).count(),
                    binomial(n, k),
                    "n={n} k={k}"
                );
            }
        }
    }

    #[test]
    fn empty_subset_is_one_combination() {
        assert_eq!(
            Combinations::new(3, 0).collect::<Vec<_>>(),
            vec![Vec::<usize>::new()]
        );
    }
}
