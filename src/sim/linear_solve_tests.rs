//! Tests of [`super`]: the block solver against whole-matrix
//! eigendecompositions, near-singular and indefinite blocks, the shift
//! mode, scratch reuse, the parallel path and the tiled gather.

use super::*;
use rand::{RngExt, SeedableRng};

/// Reference: nalgebra's eigendecomposition of the whole matrix.
/// A random symmetric `A Aᵀ + shift·I` (entries of `A` uniform in
/// ±1) and a random right-hand side, both `n`-dimensional.
fn random_system(
    rng: &mut rand_chacha::ChaCha8Rng,
    n: usize,
    shift: f64,
) -> (DMatrix<f64>, DVector<f64>) {
    let a = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
    let h = &a * a.transpose() + DMatrix::identity(n, n) * shift;
    (h, DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0)))
}

fn eigen_direction(h: &DMatrix<f64>, g: &DVector<f64>, clamp: f64, abs: bool) -> DVector<f64> {
    let eig = h.clone().symmetric_eigen();
    let mut c = eig.eigenvectors.transpose() * g;
    for (x, &l) in c.iter_mut().zip(eig.eigenvalues.iter()) {
        *x /= if abs { l.abs() } else { l }.max(clamp);
    }
    -(eig.eigenvectors * c)
}

fn solve(
    s: &mut BlockSolver,
    h: &DMatrix<f64>,
    g: &DVector<f64>,
    c: f64,
    abs: bool,
) -> DVector<f64> {
    let mut d = DVector::zeros(g.len());
    s.clamped_direction(h, g, c, abs, &mut d);
    d
}

#[test]
fn cholesky_shortcut_equals_clamped_eigen_step() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut solver = BlockSolver::default();
    for case in 0..40 {
        let n = 2 + case % 9;
        // Positive definite, indefinite and nearly singular matrices.
        let (h, g) = random_system(&mut rng, n, [3.0, -0.5, 1e-4][case % 3]);
        let clamp = 1e-3;
        for abs in [false, true] {
            let want = eigen_direction(&h, &g, clamp, abs);
            let got = solve(&mut solver, &h, &g, clamp, abs);
            assert!(
                (&got - &want).norm() <= 1e-8 * want.norm(),
                "case {case} abs {abs}"
            );
            assert!(got.dot(&g) < 0.0, "not a descent direction");
        }
    }
    // Both paths were exercised.
    assert!(solver.stats.eigen_blocks > 0);
    assert!(solver.stats.eigen_blocks < solver.stats.blocks);
}

/// Block-diagonal (after a permutation) matrices mixing a positive
/// definite block, an indefinite block, a block whose smallest
/// eigenvalue sits just above / just below the clamp, and a singular
/// one: each block takes its own path and the whole equals the clamped
/// eigen step of the whole matrix.
#[test]
fn blocks_near_singular_and_indefinite_match_whole_matrix() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let clamp = 1e-3;
    let mut solver = BlockSolver::default();
    for trial in 0..12 {
        // Eigenvalues per block.
        let spectra: [&[f64]; 5] = [
            &[5.0, 2.0, 1.0],
            &[3.0, -0.7, 0.5, -2.0],
            &[clamp * (1.0 + 1e-6), 1.0],
            &[clamp * (1.0 - 1e-6), 4.0, 2.0],
            &[0.0, 1e-14, 2.0],
        ];
        let n: usize = spectra.iter().map(|s| s.len()).sum();
        // A random permutation interleaves the blocks' coordinates.
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            perm.swap(i, rng.random_range(0..=i));
        }
        let mut h = DMatrix::zeros(n, n);
        let mut off = 0;
        for s in spectra {
            let m = s.len();
            let q = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0))
                .qr()
                .q();
            let b = &q * DMatrix::from_diagonal(&DVector::from_column_slice(s)) * q.transpose();
            for i in 0..m {
                for j in 0..m {
                    h[(perm[off + i], perm[off + j])] = b[(i, j)];
                }
            }
            off += m;
        }
        // Exact symmetry (the gather averages anyway).
        h = (&h + h.transpose()) * 0.5;
        let g = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let before = solver.stats;
        for abs in [false, true] {
            let want = eigen_direction(&h, &g, clamp, abs);
            let got = solve(&mut solver, &h, &g, clamp, abs);
            let err = (&got - &want).norm() / want.norm();
            assert!(
                err <= 1e-7,
                "trial {trial} abs {abs}: relative error {err:.1e}"
            );
            assert!(got.dot(&g) < 0.0);
        }
        // Five blocks per solve; the three with an eigenvalue ≤ c (the
        // indefinite, the just-below-clamp and the singular one) are
        // eigen-decomposed, the other two take the Cholesky path.
        assert_eq!(solver.stats.blocks - before.blocks, 10, "trial {trial}");
        assert_eq!(
            solver.stats.eigen_blocks - before.eigen_blocks,
            6,
            "trial {trial}"
        );
    }
}

/// [`Mode::Shift`]: Cholesky only; a descent direction; equal to the
/// plain Newton step where `H − c I` is positive definite; on an
/// indefinite matrix it is `−(H + τ I)⁻¹ g` with `H + τ I` positive
/// definite.
#[test]
fn shift_mode_is_cholesky_only_and_descends() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut solver = BlockSolver::default();
    for case in 0..30 {
        let n = 2 + case % 7;
        let (h, g) = random_system(&mut rng, n, [3.0, -0.5, 1e-4][case % 3]);
        let mut d = DVector::zeros(n);
        solver.direction(&h, &g, 1e-3, Mode::Shift, 0.0, &mut d);
        assert!(d.dot(&g) < 0.0, "case {case}: not a descent direction");
        let lmin = h.clone().symmetric_eigen().eigenvalues.min();
        if lmin > 1e-3 * 1.01 {
            let want = eigen_direction(&h, &g, 1e-3, false);
            assert!((&d - &want).norm() <= 1e-8 * want.norm(), "case {case}");
        } else {
            // d = −(H + τI)⁻¹ g for some τ > −λ_min: recover τ from
            // (H + τI) d = −g in the least-squares sense, check it.
            let hd = &h * &d;
            let tau = -(g.dot(&d) + hd.dot(&d)) / d.dot(&d);
            assert!(tau + lmin > 0.0, "case {case}: H + τI not PD");
            let res = (&hd + &d * tau + &g).norm();
            assert!(res <= 1e-8 * g.norm(), "case {case}: residual {res:.1e}");
        }
    }
    assert_eq!(solver.stats.eigen_blocks, 0);
    assert!(solver.stats.shifted_blocks > 0);
}

#[test]
fn spd_solve_solves_block_diagonal_systems() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let mut solver = BlockSolver::default();
    let n = 12;
    let mut h = DMatrix::zeros(n, n);
    for (lo, hi) in [(0, 5), (5, 6), (6, 12)] {
        let m = hi - lo;
        let a = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
        let b = &a * a.transpose() + DMatrix::identity(m, m) * 0.1;
        h.view_mut((lo, lo), (m, m)).copy_from(&b);
    }
    let b = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
    let mut x = DVector::zeros(n);
    assert!(solver.spd_solve(&h, &b, &mut x));
    assert!((&h * &x - &b).amax() <= 1e-12 * b.amax() * 1e3);
    // Indefinite: refused.
    h[(5, 5)] = -1.0;
    assert!(!solver.spd_solve(&h, &b, &mut x));
}

/// The tiled gather is entry for entry `0.5 (h_ij + h_ji) − shift δ_ij`
/// for blocks larger than a tile with scattered, unsorted-looking
/// coordinates and with a contiguous run of coordinates (a tile edge falls
/// inside the block in both directions).
#[test]
fn tiled_gather_is_the_symmetrized_block() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let n = 70;
    // Values not symmetric (round-off-like differences), as assembled.
    let h = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
    // Scattered coordinates, and a contiguous run (the fast path).
    let scattered: Vec<usize> = (0..n).filter(|i| i % 3 != 1).collect();
    let contiguous: Vec<usize> = (3..n - 2).collect();
    for idx in [scattered, contiguous] {
        let m = idx.len();
        assert!(m > 2 * GATHER_TILE);
        let mut sc = BlockScratch::default();
        sc.reserve(n);
        sc.gather(&h, &idx, 0.25);
        for b in 0..m {
            for a in b..m {
                let (i, j) = (idx[a], idx[b]);
                let v = 0.5 * (h[(i, j)] + h[(j, i)]) - if a == b { 0.25 } else { 0.0 };
                assert_eq!(sc.work[(a, b)].to_bits(), v.to_bits(), "entry ({a}, {b})");
            }
        }
    }
}

/// Reusing the scratch across sizes (grow, shrink) changes nothing:
/// the same input gives bitwise the same output.
#[test]
fn scratch_reuse_is_bitwise_deterministic() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let make = |rng: &mut rand_chacha::ChaCha8Rng, n: usize| random_system(rng, n, -0.3);
    let (h1, g1) = make(&mut rng, 7);
    let (h2, g2) = make(&mut rng, 40);
    let mut fresh = BlockSolver::default();
    let want = solve(&mut fresh, &h1, &g1, 1e-3, false);
    let mut reused = BlockSolver::default();
    let _ = solve(&mut reused, &h2, &g2, 1e-3, false);
    let got = solve(&mut reused, &h1, &g1, 1e-3, false);
    assert_eq!(want, got);
}

/// The parallel path (forced on small blocks, and on a pool of 3
/// threads so that chunks hold several blocks) equals the sequential
/// one bit for bit — directions, the running shift and the counters —
/// across calls, with indefinite blocks whose shifted factorization
/// reads the shift carried from the blocks before them.
#[test]
fn parallel_blocks_are_bitwise_the_sequential_solve() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let sizes = [7usize, 12, 5, 9, 16, 3, 11, 8];
    let n: usize = sizes.iter().sum();
    let mut perm: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        perm.swap(i, rng.random_range(0..=i));
    }
    let mut seq = BlockSolver {
        parallel_min_cubes: usize::MAX,
        ..Default::default()
    };
    let mut par = BlockSolver {
        parallel_min_cubes: 0,
        ..Default::default()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    for call in 0..12 {
        let mut h = DMatrix::zeros(n, n);
        let mut off = 0;
        for (b, &m) in sizes.iter().enumerate() {
            let a = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
            // Every other block indefinite (shifted), by a call-dependent amount.
            let shift = if (b + call) % 2 == 0 {
                0.5
            } else {
                -0.3 - 0.1 * b as f64
            };
            let blk = &a * a.transpose() + DMatrix::identity(m, m) * shift;
            for i in 0..m {
                for j in 0..m {
                    h[(perm[off + i], perm[off + j])] = blk[(i, j)];
                }
            }
            off += m;
        }
        let g = DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let (mut ds, mut dp) = (DVector::zeros(n), DVector::zeros(n));
        seq.direction(&h, &g, 1e-3, Mode::Shift, 0.0, &mut ds);
        pool.install(|| par.direction(&h, &g, 1e-3, Mode::Shift, 0.0, &mut dp));
        assert_eq!(ds, dp, "call {call}");
        assert_eq!(seq.last_shift.to_bits(), par.last_shift.to_bits());
        assert_eq!(seq.stats, par.stats);
    }
    assert!(seq.stats.shifted_blocks > 20);
}

/// The chunked scan of `partition` finds the connected components of the
/// non-zero pattern exactly: compared with a plain union–find over every
/// non-zero entry, on random structurally symmetric patterns (dense
/// blocks in scattered coordinates, sparse couplings between them, sizes
/// not multiples of the chunk of 8, exact zeros inside blocks).
#[test]
fn partition_is_the_components_of_the_nonzero_pattern() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
    let mut solver = BlockSolver::default();
    for case in 0..60 {
        let n = 1 + rng.random_range(0..90usize);
        let mut h = DMatrix::zeros(n, n);
        // Coordinates in random groups, each group dense with a few exact
        // zeros, plus a few random couplings.
        let groups = 1 + rng.random_range(0..6usize);
        let label: Vec<usize> = (0..n).map(|_| rng.random_range(0..groups)).collect();
        for j in 0..n {
            for i in j..n {
                let dense = label[i] == label[j] && rng.random_range(0.0..1.0) < 0.9;
                let coupling = rng.random_range(0.0..1.0) < 0.3 / n as f64;
                if i == j || dense || coupling {
                    let v = rng.random_range(-1.0..1.0);
                    h[(i, j)] = v;
                    h[(j, i)] = v;
                }
            }
        }
        if case % 5 == 0 {
            // A diagonal-only matrix: every coordinate alone.
            h = DMatrix::identity(n, n);
        }
        solver.partition(&h);
        // The dispatched scan (AVX-512 / AVX2 here) builds the same forest
        // as the portable one.
        let (mut fast, mut portable): (Vec<usize>, Vec<usize>) =
            ((0..n).collect(), (0..n).collect());
        join_nonzeros(h.as_slice(), n, None, &mut fast);
        join_nonzeros_generic(h.as_slice(), n, None, &mut portable);
        assert_eq!(fast, portable, "case {case}: scan paths differ");
        // Each column's scan cut at its last non-zero (the tightest row
        // bound an envelope can give): the same forest.
        let ends: Vec<usize> = (0..n)
            .map(|j| {
                (0..n)
                    .rev()
                    .find(|&i| h[(i, j)] != 0.0)
                    .map_or(j + 1, |i| i + 1)
            })
            .collect();
        let mut bounded: Vec<usize> = (0..n).collect();
        join_nonzeros(h.as_slice(), n, Some(&ends), &mut bounded);
        assert_eq!(bounded, fast, "case {case}: bounded scan differs");
        // Reference: union–find over all non-zeros, roots = smallest index.
        let mut p: Vec<usize> = (0..n).collect();
        for j in 0..n {
            for i in 0..n {
                if h[(i, j)] != 0.0 {
                    let (a, b) = (find(&mut p, i), find(&mut p, j));
                    p[a.max(b)] = a.min(b);
                }
            }
        }
        let mut want: Vec<Vec<usize>> = Vec::new();
        for r in 0..n {
            let blk: Vec<usize> = (0..n).filter(|&i| find(&mut p, i) == r).collect();
            if !blk.is_empty() {
                want.push(blk);
            }
        }
        let got: Vec<Vec<usize>> = (0..solver.starts.len() - 1)
            .map(|b| solver.order[solver.starts[b]..solver.starts[b + 1]].to_vec())
            .collect();
        assert_eq!(got, want, "case {case}, n = {n}");
    }
}

/// The refinement sweeps with the shifted factor (stopping on the
/// predicted correction) give `H_B⁻¹ b` to round-off: against nalgebra's
/// Cholesky of `H_B` itself, on positive-definite blocks whose smallest
/// eigenvalue ranges from `1.5c` (`ρ = c/λ_min(H_B − cI) ≥ ½`: the
/// 30-sweep fallback to a second factorization) through `30c` (`ρ ≈ 0.03`,
/// six or seven sweeps) to `10⁶c` (a few sweeps), with condition numbers
/// `10²…10⁸`. The bound is the solve's own forward error, `8 ε κ(H_B)`
/// (measured at most `0.22 ε κ`).
#[test]
fn refinement_equals_direct_solve_across_contractions() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let mut solver = BlockSolver::default();
    let c = 1e-3;
    for case in 0..48 {
        let m = [3usize, 17, 64, 100][case % 4];
        // H = Q diag(λ) Qᵀ with λ log-spaced in [λ_min, λ_max].
        let a = DMatrix::from_fn(m, m, |_, _| rng.random_range(-1.0..1.0));
        let q = a.qr().q();
        let lam_min = c * [1.5, 3.0, 30.0, 1e3, 1e6, 2.0][case % 6];
        let kappa: f64 = [1e2, 1e5, 1e8][case % 3];
        let lam = DVector::from_fn(m, |i, _| {
            lam_min * kappa.powf(i as f64 / (m - 1).max(1) as f64)
        });
        let h = &q * DMatrix::from_diagonal(&lam) * q.transpose();
        let h = (&h + h.transpose()) * 0.5;
        let g = DVector::from_fn(m, |_, _| rng.random_range(-1.0..1.0));
        let want = -h.clone().cholesky().expect("positive definite").solve(&g);
        let before = solver.stats;
        let got = solve(&mut solver, &h, &g, c, false);
        assert_eq!(
            solver.stats.eigen_blocks, before.eigen_blocks,
            "case {case}"
        );
        let err = (&got - &want).amax() / want.amax();
        let bound = 8.0 * f64::EPSILON * kappa;
        assert!(
            err <= bound,
            "case {case}: m {m}, λ_min/c {}, κ {kappa:e}: error {err:e} > {bound:e}",
            lam_min / c
        );
    }
}
