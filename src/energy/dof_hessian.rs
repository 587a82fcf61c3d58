//! The coordinate part of a term's Hessian, `∂²E/∂θ²` of the terms written
//! directly in generalized coordinates (PD, joint limits, mimic ties,
//! coordinate effects): a diagonal and a short list of off-diagonal entries.
//!
//! These terms touch `O(|θ|)` entries, so a dense `|θ|×|θ|` buffer (cleared
//! at every Hessian evaluation: 512 kB at 256 coordinates) is replaced by
//! this sparse one, indexed like a matrix (`h[(k, l)] += v`). The assembler
//! writes it into the step Hessian ([`crate::sim::assemble`]).

use std::ops::{Index, IndexMut};

/// Sparse symmetric-by-construction coordinate Hessian (see the module
/// documentation). Off-diagonal entries are kept in the order first
/// written; a writer of `(k, l)` writes `(l, k)` too.
#[derive(Clone, Debug, Default)]
pub struct DofHessian {
    diag: Vec<f64>,
    off: Vec<((usize, usize), f64)>,
}

const ZERO: f64 = 0.0;

impl DofHessian {
    /// An all-zero `n × n` coordinate Hessian.
    pub fn zeros(n: usize) -> Self {
        DofHessian {
            diag: vec![0.0; n],
            off: Vec::new(),
        }
    }

    /// Number of coordinates.
    pub fn nrows(&self) -> usize {
        self.diag.len()
    }

    /// Sets every entry to zero (keeps the size).
    pub fn clear(&mut self) {
        self.diag.fill(0.0);
        self.off.clear();
    }

    /// The diagonal `h_kk`.
    pub fn diagonal(&self) -> &[f64] {
        &self.diag
    }

    /// The written off-diagonal entries `((k, l), h_kl)`, `k ≠ l`.
    pub fn off_diagonal(&self) -> &[((usize, usize), f64)] {
        &self.off
    }

    fn check(&self, k: usize, l: usize) {
        let n = self.diag.len();
        assert!(
            k < n && l < n,
            "DofHessian index ({k}, {l}) out of range for {n}×{n}"
        );
    }
}

impl Index<(usize, usize)> for DofHessian {
    type Output = f64;

    fn index(&self, (k, l): (usize, usize)) -> &f64 {
        self.check(k, l);
        if k == l {
            return &self.diag[k];
        }
        self.off
            .iter()
            .find(|(at, _)| *at == (k, l))
            .map_or(&ZERO, |(_, v)| v)
    }
}

impl IndexMut<(usize, usize)> for DofHessian {
    fn index_mut(&mut self, (k, l): (usize, usize)) -> &mut f64 {
        self.check(k, l);
        if k == l {
            return &mut self.diag[k];
        }
        let at = match self.off.iter().position(|(at, _)| *at == (k, l)) {
            Some(i) => i,
            None => {
                self.off.push(((k, l), 0.0));
                self.off.len() - 1
            }
        };
        &mut self.off[at].1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    /// Random writes give the same matrix as a dense buffer, and `clear`
    /// zeroes it.
    #[test]
    fn matches_a_dense_buffer() {
        let n = 7;
        let mut sparse = DofHessian::zeros(n);
        let mut dense = DMatrix::<f64>::zeros(n, n);
        let writes = [
            (0, 0, 1.5),
            (2, 5, -0.25),
            (5, 2, -0.25),
            (2, 5, 3.0),
            (6, 6, 2.0),
            (0, 0, 1.0),
        ];
        for &(k, l, v) in &writes {
            sparse[(k, l)] += v;
            dense[(k, l)] += v;
        }
        for k in 0..n {
            for l in 0..n {
                assert_eq!(
                    sparse[(k, l)].to_bits(),
                    dense[(k, l)].to_bits(),
                    "({k}, {l})"
                );
            }
        }
        assert_eq!(sparse.off_diagonal().len(), 2);
        sparse.clear();
        assert!((0..n).all(|k| (0..n).all(|l| sparse[(k, l)] == 0.0)));
        assert!(sparse.off_diagonal().is_empty());
    }

    #[test]
    #[should_panic(expected = "out of range")]
    fn out_of_range_index_names_the_entry() {
        let h = DofHessian::zeros(3);
        let _ = h[(1, 3)];
    }
}
