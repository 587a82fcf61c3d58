//! Where a coordinate Hessian can be non-zero.
//!
//! The step Hessian of a kinematic tree is branch-sparse: entry `(k, l)` is
//! structurally non-zero only when one coordinate's joint is an ancestor (or
//! the same joint) of the other's, when a contact or friction pair couples
//! the two links' ancestor paths, or when a coordinate term (mimic ties)
//! writes it. A [`HessEnvelope`] records, per column `j`, one row interval
//! `lo_j..hi_j` outside which every entry of the matrix it describes is
//! exactly zero (a superset of the non-zeros; intervals, not exact sets, so
//! that clearing and scanning are contiguous walks of the column-major
//! storage). With depth-first coordinate numbering a column's interval is
//! its tree's coordinate range: four independent 64-coordinate chains cover
//! a quarter of the 256 × 256 matrix.

use nalgebra::DMatrix;
use std::ops::Range;

/// Per-column row intervals covering every non-zero of an `n × n` matrix.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct HessEnvelope {
    /// First row that may be non-zero, per column (`lo > hi`: none).
    lo: Vec<usize>,
    /// One past the last row that may be non-zero, per column.
    hi: Vec<usize>,
    /// Whether the whole matrix may be non-zero (contents unknown).
    full: bool,
}

impl HessEnvelope {
    /// The envelope of the `n × n` zero matrix.
    pub fn empty(n: usize) -> Self {
        HessEnvelope {
            lo: vec![usize::MAX; n],
            hi: vec![0; n],
            full: false,
        }
    }

    /// Order `n` of the matrix described.
    pub fn len(&self) -> usize {
        self.lo.len()
    }

    /// Whether the matrix described is `0 × 0`.
    pub fn is_empty(&self) -> bool {
        self.lo.is_empty()
    }

    /// Whether every entry may be non-zero.
    pub fn is_full(&self) -> bool {
        self.full
    }

    /// Forgets everything: every entry may be non-zero.
    pub fn set_full(&mut self) {
        self.full = true;
    }

    /// Back to the zero matrix's envelope (the order is kept).
    pub fn clear(&mut self) {
        self.lo.fill(usize::MAX);
        self.hi.fill(0);
        self.full = false;
    }

    /// Resizes to order `n` and clears.
    pub fn reset(&mut self, n: usize) {
        self.lo.resize(n, usize::MAX);
        self.hi.resize(n, 0);
        self.clear();
    }

    /// Rows of column `j` that may be non-zero.
    #[inline]
    pub fn rows(&self, j: usize) -> Range<usize> {
        if self.full {
            0..self.lo.len()
        } else if self.lo[j] >= self.hi[j] {
            0..0
        } else {
            self.lo[j]..self.hi[j]
        }
    }

    /// Adds the rows `rows` of column `col`.
    #[inline]
    pub fn cover_rows(&mut self, rows: Range<usize>, col: usize) {
        if rows.start < rows.end {
            self.lo[col] = self.lo[col].min(rows.start);
            self.hi[col] = self.hi[col].max(rows.end);
        }
    }

    /// Adds the entry `(row, col)`.
    #[inline]
    pub fn cover(&mut self, row: usize, col: usize) {
        self.cover_rows(row..row + 1, col);
    }

    /// Adds every entry the other envelope covers.
    pub fn union(&mut self, other: &HessEnvelope) {
        if other.full {
            self.full = true;
            return;
        }
        for j in 0..self.lo.len().min(other.lo.len()) {
            self.lo[j] = self.lo[j].min(other.lo[j]);
            self.hi[j] = self.hi[j].max(other.hi[j]);
        }
    }

    /// Sets every entry of `m` that the envelope covers to zero; with the
    /// envelope describing `m`, `m` is then the zero matrix.
    pub fn zero(&self, m: &mut DMatrix<f64>) {
        let n = m.nrows();
        if self.full || self.lo.len() != m.ncols() || n != m.ncols() {
            m.fill(0.0);
            return;
        }
        for (j, col) in m.as_mut_slice().chunks_exact_mut(n.max(1)).enumerate() {
            col[self.rows(j)].fill(0.0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Clearing over the envelope of what was written gives the zero
    /// matrix; columns never covered are not touched.
    #[test]
    fn zeroing_the_envelope_clears_what_was_covered() {
        let n = 7;
        let mut m = DMatrix::<f64>::zeros(n, n);
        let mut e = HessEnvelope::empty(n);
        for &(r, c) in &[(0, 0), (3, 1), (1, 3), (6, 6), (2, 6), (5, 4)] {
            m[(r, c)] = 1.0 + r as f64;
            e.cover(r, c);
        }
        assert_eq!(e.rows(6), 2..7);
        assert_eq!(e.rows(2), 0..0);
        let mut sentinel = m.clone();
        sentinel[(0, 2)] = 9.0; // outside the envelope
        e.zero(&mut m);
        assert!(m.iter().all(|&v| v == 0.0));
        e.zero(&mut sentinel);
        assert_eq!(sentinel[(0, 2)], 9.0);
        assert_eq!(sentinel.iter().filter(|&&v| v != 0.0).count(), 1);
        let mut f = HessEnvelope::empty(n);
        f.union(&e);
        assert_eq!(f, e);
        f.set_full();
        assert_eq!(f.rows(2), 0..n);
        f.zero(&mut sentinel);
        assert!(sentinel.iter().all(|&v| v == 0.0));
    }
}
