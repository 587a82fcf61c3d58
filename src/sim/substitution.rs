//! Forward and back substitution with a Cholesky factor for one right-hand
//! side, `x ← (L Lᵀ)⁻¹ x` (the refinement sweeps of
//! [`super::linear_solve`]).
//!
//! For one vector of a 64-coordinate block, faer's blocked triangular solve
//! (a recursion over sub-blocks with a matrix–vector product at each level)
//! spent most of its time in dispatch and bookkeeping: the two solves are
//! `m²` multiply–adds in all. Here they are two plain loops over the
//! contiguous columns of the column-major factor:
//!
//! - `L y = b`, column by column: `y_j ← y_j / l_jj`, then
//!   `y_{j+1..m} −= y_j l_{j+1..m, j}` (an axpy; entry `i` accumulates its
//!   terms in the order `j = 0, 1, …` whatever the vector width);
//! - `Lᵀ x = y`, row `i` of `Lᵀ` is column `i` of `L`:
//!   `x_i ← (y_i − Σ_{k>i} l_ki x_k) / l_ii`, the dot product in four
//!   interleaved partial sums (lane `r` takes `k ≡ r mod 4`, summed
//!   `(s₀ + s₁) + (s₂ + s₃)`, then the tail): a fixed order, so it
//!   vectorizes without reassociation.
//!
//! No fused multiply–add is used, so the AVX2 path (chosen at run time where
//! the CPU has it) and the baseline SSE2 path give **bitwise the same**
//! result. The result differs from faer's in round-off only (another
//! summation order; both are backward stable).

use faer::Mat;

/// `inv[j] = 1 / l_jj` for the factor in the leading `m × m` block of `l`
/// (computed once per factorization; the solves then multiply, keeping a
/// division off their critical path).
pub fn inverse_diagonal(l: &Mat<f64>, m: usize, inv: &mut Vec<f64>) {
    inv.clear();
    inv.extend((0..m).map(|j| 1.0 / l.col_as_slice(j)[j]));
}

/// `x[..m] ← (L Lᵀ)⁻¹ x[..m]` for the lower-triangular factor in the
/// leading `m × m` block of `l` (column-major; the strict upper triangle is
/// not read), `inv` from [`inverse_diagonal`].
pub fn cholesky_solve(l: &Mat<f64>, inv: &[f64], m: usize, x: &mut [f64]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked above).
        unsafe { solve_avx2(l, inv, m, x) };
        return;
    }
    solve_generic(l, inv, m, x);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn solve_avx2(l: &Mat<f64>, inv: &[f64], m: usize, x: &mut [f64]) {
    solve_generic(l, inv, m, x);
}

#[inline(always)]
fn solve_generic(l: &Mat<f64>, inv: &[f64], m: usize, x: &mut [f64]) {
    let (x, inv) = (&mut x[..m], &inv[..m]);
    // L y = b.
    for j in 0..m {
        let col = &l.col_as_slice(j)[j + 1..m];
        let yj = x[j] * inv[j];
        x[j] = yj;
        for (xi, &lij) in x[j + 1..].iter_mut().zip(col) {
            *xi -= yj * lij;
        }
    }
    // Lᵀ x = y. The term of `x_{i+1}` (computed just before) is subtracted
    // last, and the dot product runs from the far end: the rest of row `i`
    // does not wait for `x_{i+1}`.
    if m == 0 {
        return;
    }
    x[m - 1] *= inv[m - 1];
    for i in (0..m - 1).rev() {
        let col = &l.col_as_slice(i)[i + 1..m];
        let far = dot_from_end(&col[1..], &x[i + 2..]);
        x[i] = ((x[i] - far) - col[0] * x[i + 1]) * inv[i];
    }
}

/// `Σ a_k b_k` from the far end: four interleaved partial sums over the
/// chunks of four counted from the end (lane `r` of chunk `c` is
/// `k = len − 4(c + 1) + r`), summed `(s₀ + s₁) + (s₂ + s₃)`, then the
/// leading remainder from its last entry to its first: a fixed order, so it
/// vectorizes without reassociation.
#[inline(always)]
fn dot_from_end(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let k = a.len().min(b.len());
    let (a, b) = (&a[..k], &b[..k]);
    let head = k % 4;
    let (ah, at) = a.split_at(head);
    let (bh, bt) = b.split_at(head);
    for (p, q) in at.chunks_exact(4).zip(bt.chunks_exact(4)).rev() {
        let (p, q): (&[f64; 4], &[f64; 4]) = (p.try_into().unwrap(), q.try_into().unwrap());
        for r in 0..4 {
            s[r] += p[r] * q[r];
        }
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for (p, q) in ah.iter().zip(bh).rev() {
        t += p * q;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::reborrow::ReborrowMut;
    use rand::{RngExt, SeedableRng};

    /// A random lower-triangular factor with a dominant positive diagonal
    /// in an `n × n` buffer (the solver's scratch is larger than a block).
    fn random_factor(rng: &mut rand_chacha::ChaCha8Rng, m: usize, n: usize) -> Mat<f64> {
        let mut l = Mat::<f64>::zeros(n, n);
        for j in 0..m {
            for i in j..m {
                l[(i, j)] = if i == j {
                    1.0 + rng.random_range(0.0..2.0)
                } else {
                    rng.random_range(-0.5..0.5)
                };
            }
            // Garbage above the diagonal and below `m`: must not be read.
            for i in 0..j {
                l[(i, j)] = f64::NAN;
            }
        }
        l
    }

    #[test]
    fn substitution_matches_faer_and_both_paths_agree_bitwise() {
        use faer::linalg::triangular_solve as tri;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for m in [0, 1, 2, 3, 4, 5, 7, 8, 13, 31, 64, 65, 100] {
            let l = random_factor(&mut rng, m, m + 3);
            let b: Vec<f64> = (0..m + 3).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut inv = Vec::new();
            inverse_diagonal(&l, m, &mut inv);
            let mut x = b.clone();
            cholesky_solve(&l, &inv, m, &mut x);
            assert_eq!(&x[m..], &b[m..], "entries past m untouched");
            let mut y = b.clone();
            solve_generic(&l, &inv, m, &mut y);
            assert_eq!(x, y, "m = {m}: dispatched path differs from the baseline");
            // faer's blocked solve of the same system.
            let lr = l.as_ref().submatrix(0, 0, m, m);
            let mut r = Mat::<f64>::from_fn(m, 1, |i, _| b[i]);
            tri::solve_lower_triangular_in_place(lr, r.as_mut().rb_mut(), faer::Par::Seq);
            tri::solve_upper_triangular_in_place(
                lr.transpose(),
                r.as_mut().rb_mut(),
                faer::Par::Seq,
            );
            let scale = (0..m).map(|i| r[(i, 0)].abs()).fold(0.0, f64::max);
            for i in 0..m {
                assert!(
                    (x[i] - r[(i, 0)]).abs() <= 1e-12 * scale,
                    "m = {m}, i = {i}: {} vs {}",
                    x[i],
                    r[(i, 0)]
                );
            }
        }
    }

    /// Timing against faer (not run by default):
    /// `cargo test --release --lib sim::substitution -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timing_against_faer() {
        use faer::linalg::triangular_solve as tri;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(6);
        for (m, reps) in [(64, 200_000), (128, 50_000), (256, 10_000)] {
            let n = 256;
            let l = random_factor(&mut rng, m, n);
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let mut x = b.clone();
            let mut inv = Vec::new();
            inverse_diagonal(&l, m, &mut inv);
            let t = std::time::Instant::now();
            for _ in 0..reps {
                x[..m].copy_from_slice(&b[..m]);
                cholesky_solve(&l, &inv, m, &mut x);
                std::hint::black_box(&mut x);
            }
            let ours = t.elapsed().as_secs_f64() / reps as f64;
            let lr = l.as_ref().submatrix(0, 0, m, m);
            let mut r = Mat::<f64>::zeros(n, 1);
            let t = std::time::Instant::now();
            for _ in 0..reps {
                for i in 0..m {
                    r[(i, 0)] = b[i];
                }
                let mut v = r.as_mut().submatrix_mut(0, 0, m, 1);
                tri::solve_lower_triangular_in_place(lr, v.rb_mut(), faer::Par::Seq);
                tri::solve_upper_triangular_in_place(lr.transpose(), v.rb_mut(), faer::Par::Seq);
                std::hint::black_box(&mut r);
            }
            let faer = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "m = {m}: substitution {:.3} µs, faer {:.3} µs per solve pair",
                ours * 1e6,
                faer * 1e6
            );
        }
    }
}
