//! In-place Cholesky factorization `A = L Lᵀ` of small dense blocks (the
//! chain blocks of [`super::linear_solve`], 64 coordinates on the 32-link
//! chains).
//!
//! Left-looking (Crout), column by column: column `j` of `A` below the
//! diagonal is updated with the finished columns `k < j`,
//!
//! ```text
//! a_ij ← a_ij − Σ_{k<j} l_ik l_jk   (i ≥ j; k = 0, 1, … in order),
//! l_jj = √a_jj,   l_ij = a_ij / l_jj   (as a_ij · (1/l_jj)),
//! ```
//!
//! four columns `k` per pass over two target columns `j, j + 1` (each
//! loaded column `k` serves both, and each target entry stays in a register
//! for four fused multiply–adds). Each entry takes its terms in the textbook
//! order `k = 0, 1, …`, one correctly rounded `fma` each
//! ([`f64::mul_add`]), so the result does not depend on the vector width
//! or the code path: the AVX2 + FMA path (chosen at run time) and the
//! portable one give bitwise the same factor. It differs from faer's
//! blocked factorization in round-off only. Up to [`SMALL_CHOLESKY_MAX`]
//! coordinates it is faster than faer's (whose recursion and micro-kernel
//! set-up do not pay off at this size); above, faer's is used.
//!
//! Fails (returns `false`, the block partly overwritten) at the first pivot
//! `a_jj` that is not positive (or not a number), as faer's does: success
//! is the certificate `λ_min > 0` of the factored matrix, up to round-off.

use faer::Mat;

/// Largest block factored here; larger blocks use faer's blocked
/// factorization (`timing_against_faer`, this machine: m = 32 1.2 vs
/// 1.3 µs, m = 64 5.8 vs 6.9 µs, m = 96 15.5 vs 12.2 µs, copies of the
/// block included).
pub const SMALL_CHOLESKY_MAX: usize = 64;

/// Factors the leading `m × m` block of `a` (lower triangle read and
/// overwritten with `L`; the strict upper triangle is not touched).
pub fn cholesky_in_place(a: &mut Mat<f64>, m: usize) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU supports AVX2 and FMA (checked above).
        return unsafe { factor_avx2(a, m) };
    }
    factor_generic(a, m)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_avx2(a: &mut Mat<f64>, m: usize) -> bool {
    factor_generic(a, m)
}

/// The storage of `a` as one column-major slice and its column stride.
fn columns(a: &mut Mat<f64>) -> (&mut [f64], usize) {
    let (rows, cols) = (a.nrows(), a.ncols());
    let cs = a.col_stride();
    assert!(cs >= rows as isize, "column-major storage");
    let cs = cs as usize;
    let len = if cols == 0 { 0 } else { cs * (cols - 1) + rows };
    // SAFETY: an owned faer matrix stores its columns at `ptr + j·cs`,
    // `cs ≥ nrows`, in one allocation; the slice covers exactly the
    // entries up to the last one, and borrows `a` mutably.
    (
        unsafe { std::slice::from_raw_parts_mut(a.as_ptr_mut(), len) },
        cs,
    )
}

#[inline(always)]
fn factor_generic(a: &mut Mat<f64>, m: usize) -> bool {
    let (buf, cs) = columns(a);
    // Columns in pairs `(j, j + 1)`: each finished column `k < j` is loaded
    // once for both (the same multiply–adds per entry, in the same order, as
    // one column at a time).
    let mut j = 0;
    while j < m {
        let (left, right) = buf.split_at_mut(j * cs);
        let left = &*left;
        let col = |k: usize| -> &[f64] { &left[k * cs + j..k * cs + m] };
        let (cj, rest) = right.split_at_mut(cs.min(right.len()));
        let a0 = &mut cj[j..m];
        if j + 1 == m {
            // Last column alone.
            for k in 0..j {
                let c = col(k);
                let l = c[0];
                for (x, &ci) in a0.iter_mut().zip(c) {
                    *x = (-ci).mul_add(l, *x);
                }
            }
            return pivot(a0);
        }
        let a1 = &mut rest[j + 1..m];
        let mut k = 0;
        while k + 4 <= j {
            let (c0, c1, c2, c3) = (col(k), col(k + 1), col(k + 2), col(k + 3));
            // Row j of L (for column j) and row j + 1 (for column j + 1).
            let (p0, p1, p2, p3) = (c0[0], c1[0], c2[0], c3[0]);
            let (q0, q1, q2, q3) = (c0[1], c1[1], c2[1], c3[1]);
            let t = (-c0[0]).mul_add(p0, a0[0]);
            let t = (-c1[0]).mul_add(p1, t);
            let t = (-c2[0]).mul_add(p2, t);
            a0[0] = (-c3[0]).mul_add(p3, t);
            let cols = c0[1..].iter().zip(&c1[1..]).zip(&c2[1..]).zip(&c3[1..]);
            for ((x, y), (((&e0, &e1), &e2), &e3)) in
                a0[1..].iter_mut().zip(a1.iter_mut()).zip(cols)
            {
                let t = (-e0).mul_add(p0, *x);
                let t = (-e1).mul_add(p1, t);
                let t = (-e2).mul_add(p2, t);
                *x = (-e3).mul_add(p3, t);
                let u = (-e0).mul_add(q0, *y);
                let u = (-e1).mul_add(q1, u);
                let u = (-e2).mul_add(q2, u);
                *y = (-e3).mul_add(q3, u);
            }
            k += 4;
        }
        while k < j {
            let c = col(k);
            let (p, q) = (c[0], c[1]);
            a0[0] = (-c[0]).mul_add(p, a0[0]);
            for ((x, y), &ci) in a0[1..].iter_mut().zip(a1.iter_mut()).zip(&c[1..]) {
                *x = (-ci).mul_add(p, *x);
                *y = (-ci).mul_add(q, *y);
            }
            k += 1;
        }
        if !pivot(a0) {
            return false;
        }
        // Column j + 1's last term, k = j.
        let q = a0[1];
        for (y, &ci) in a1.iter_mut().zip(&a0[1..]) {
            *y = (-ci).mul_add(q, *y);
        }
        if !pivot(a1) {
            return false;
        }
        j += 2;
    }
    true
}

/// Finishes a column whose updates are done: `l_jj = √a_jj`, the rest
/// times `1/l_jj`; `false` for a pivot that is not positive.
#[inline(always)]
fn pivot(a: &mut [f64]) -> bool {
    let d = a[0];
    if d <= 0.0 || d.is_nan() {
        return false;
    }
    let ljj = d.sqrt();
    a[0] = ljj;
    let inv = 1.0 / ljj;
    for x in &mut a[1..] {
        *x *= inv;
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor as llt;
    use rand::{RngExt, SeedableRng};

    /// `B Bᵀ + s I` in the leading `m × m` block of an `n × n` matrix
    /// (the rest NaN: must not be read).
    fn random_spd(rng: &mut rand_chacha::ChaCha8Rng, m: usize, n: usize, s: f64) -> Mat<f64> {
        let b = Mat::<f64>::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
        let mut a = Mat::<f64>::from_fn(n, n, |_, _| f64::NAN);
        for j in 0..m {
            for i in 0..m {
                let mut v = if i == j { s } else { 0.0 };
                for k in 0..m {
                    v += b[(i, k)] * b[(j, k)];
                }
                a[(i, j)] = v;
            }
        }
        a
    }

    fn faer_scratch(m: usize) -> MemBuffer {
        MemBuffer::new(llt::cholesky_in_place_scratch::<f64>(
            m,
            faer::Par::Seq,
            Default::default(),
        ))
    }

    /// faer's Cholesky of the leading `m × m` block, with scratch `mem`.
    fn faer_factor_with(a: &mut Mat<f64>, m: usize, mem: &mut MemBuffer) -> bool {
        let view = a.as_mut().submatrix_mut(0, 0, m, m);
        llt::cholesky_in_place(
            view,
            Default::default(),
            faer::Par::Seq,
            MemStack::new(mem),
            Default::default(),
        )
        .is_ok()
    }

    fn faer_factor(a: &mut Mat<f64>, m: usize) -> bool {
        faer_factor_with(a, m, &mut faer_scratch(m))
    }

    #[test]
    fn factor_matches_faer_and_both_paths_agree_bitwise() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for m in [1, 2, 3, 4, 5, 7, 8, 9, 16, 31, 64, 65, 96] {
            let a = random_spd(&mut rng, m, m + 5, 0.5);
            let (mut ours, mut generic, mut theirs) = (a.clone(), a.clone(), a.clone());
            assert!(cholesky_in_place(&mut ours, m), "m = {m}");
            assert!(factor_generic(&mut generic, m));
            assert!(faer_factor(&mut theirs, m));
            let scale = (0..m).map(|j| ours[(j, j)]).fold(0.0, f64::max);
            for j in 0..m + 5 {
                for i in 0..m + 5 {
                    let (x, y) = (ours[(i, j)], generic[(i, j)]);
                    assert_eq!(
                        x.to_bits(),
                        y.to_bits(),
                        "m = {m}: paths differ at ({i}, {j})"
                    );
                    if i < j || i >= m || j >= m {
                        // Untouched: still NaN (outside the block) or the input.
                        assert_eq!(
                            x.to_bits(),
                            a[(i, j)].to_bits(),
                            "m = {m}: ({i}, {j}) written"
                        );
                    } else {
                        assert!(
                            (x - theirs[(i, j)]).abs() <= 1e-10 * scale,
                            "m = {m}: ({i}, {j}) {x} vs {}",
                            theirs[(i, j)]
                        );
                    }
                }
            }
        }
    }

    /// Not positive definite (an eigenvalue ≈ −0.1 after the shift, or a
    /// NaN on the diagonal): refused, as by faer.
    #[test]
    fn indefinite_and_nan_blocks_are_refused() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for m in [1, 5, 40, 64] {
            let mut a = random_spd(&mut rng, m, m, 0.0);
            // Smallest eigenvalue of B Bᵀ is ≥ 0; shift it below zero.
            let lam_min = {
                let d = nalgebra::DMatrix::from_fn(m, m, |i, j| a[(i, j)]);
                d.symmetric_eigenvalues().min()
            };
            for i in 0..m {
                a[(i, i)] -= lam_min + 0.1;
            }
            let mut b = a.clone();
            assert!(!cholesky_in_place(&mut a, m), "m = {m}");
            assert!(!faer_factor(&mut b, m), "m = {m} (faer)");
            let mut c = random_spd(&mut rng, m, m, 1.0);
            c[(m / 2, m / 2)] = f64::NAN;
            assert!(!cholesky_in_place(&mut c, m), "m = {m}: NaN pivot");
        }
    }

    /// Timing against faer (not run by default):
    /// `cargo test --release --lib sim::small_cholesky -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn timing_against_faer() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for m in [32, 64, 96, 128] {
            let reps = 20_000;
            let a = random_spd(&mut rng, m, 256, 1.0);
            let mut w = a.clone();
            let t = std::time::Instant::now();
            for _ in 0..reps {
                w.as_mut()
                    .submatrix_mut(0, 0, m, m)
                    .copy_from(a.as_ref().submatrix(0, 0, m, m));
                assert!(cholesky_in_place(&mut w, m));
            }
            let ours = t.elapsed().as_secs_f64() / reps as f64;
            let mut mem = faer_scratch(m);
            let t = std::time::Instant::now();
            for _ in 0..reps {
                w.as_mut()
                    .submatrix_mut(0, 0, m, m)
                    .copy_from(a.as_ref().submatrix(0, 0, m, m));
                assert!(faer_factor_with(&mut w, m, &mut mem));
            }
            let theirs = t.elapsed().as_secs_f64() / reps as f64;
            let t = std::time::Instant::now();
            for _ in 0..reps {
                w.as_mut()
                    .submatrix_mut(0, 0, m, m)
                    .copy_from(a.as_ref().submatrix(0, 0, m, m));
                std::hint::black_box(&mut w);
            }
            let copy = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "m = {m}: ours {:.2} µs, faer {:.2} µs, of which the copy {:.2} µs",
                ours * 1e6,
                theirs * 1e6,
                copy * 1e6
            );
        }
    }
}
