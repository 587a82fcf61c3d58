//! The Newton step's linear algebra (paper, `Forward Simulation`: "the
//! Hessian is eigen-decomposed and its eigenvalues clamped").
//!
//! The step is `Δ = −Ĥ⁻¹ g`, where `Ĥ` has the eigenvectors of the
//! symmetric step Hessian `H` and eigenvalues `max(λ, c)` (`c` =
//! [`crate::sim::NewtonOptions::eig_clamp`]; with `abs`, `max(|λ|, c)`).
//! Three observations make it cheap:
//!
//! 1. **Blocks.** `H` is split into the connected components of its
//!    sparsity graph (robots or chains not in contact are independent): the
//!    eigendecomposition of a block-diagonal matrix is the union of its
//!    blocks', so each block is solved alone (exact).
//! 2. **Cholesky first.** If `H_B − c I` has a Cholesky factorization, every
//!    eigenvalue of the block `H_B` exceeds `c`, clamping changes nothing,
//!    `Ĥ_B = H_B`, and the step is a Cholesky solve with `H_B` (two
//!    `m³/3` factorizations instead of a `~9 m³` eigendecomposition). Only
//!    blocks whose shifted Cholesky fails are eigen-decomposed.
//! 3. **Blocked, SIMD kernels, no allocation.** Blocks of up to 64
//!    coordinates are factored by [`super::small_cholesky`], larger ones and
//!    the self-adjoint eigendecomposition by `faer` (blocked, vectorized;
//!    sequential, so results are bitwise reproducible); the refinement's
//!    triangular solves are [`super::substitution`]'s; every buffer —
//!    the gathered block, eigenvectors, eigenvalues, the kernels' work
//!    space — lives in [`BlockSolver`] and is reused across iterations and
//!    steps (it grows only when the problem does).

use super::small_cholesky::SMALL_CHOLESKY_MAX;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor as llt;
use faer::linalg::evd;
use faer::reborrow::ReborrowMut;
use faer::{Mat, MatMut, MatRef, Par};
use nalgebra::{DMatrix, DVector};

/// Counts of the solver's work since creation (diagnostics, benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LinearSolveStats {
    /// Blocks solved (over all calls).
    pub blocks: u64,
    /// Of those, blocks that needed the eigendecomposition (the shifted
    /// Cholesky failed: an eigenvalue `≤ c`).
    pub eigen_blocks: u64,
    /// Calls with at least one eigen-decomposed block.
    pub eigen_solves: u64,
    /// Calls.
    pub solves: u64,
    /// Blocks solved with a shifted Cholesky ([`Mode::Shift`]).
    pub shifted_blocks: u64,
    /// Factorization attempts of [`Mode::Shift`].
    pub shift_attempts: u64,
    /// Solves with the shifted factor in the refinement of positive
    /// definite blocks (see `BlockSolver::refine`).
    pub refine_sweeps: u64,
    /// Positive-definite blocks whose refinement did not converge and were
    /// factored a second time.
    pub refine_fallbacks: u64,
    /// Blocks already converged (`‖g_B‖∞` below the `settled` bound of
    /// [`BlockSolver::direction`]) that got a zero step instead of a solve.
    pub settled_blocks: u64,
}

/// Work space of one block solve: the gathered block / its factor,
/// eigenvectors, eigenvalues, two vectors and the kernels' memory, sized for
/// blocks of up to `dim` coordinates (grown on demand, never shrunk).
struct BlockScratch {
    /// Gathered block / its factor (capacity `dim × dim`).
    work: Mat<f64>,
    /// Eigenvectors of an eigen-decomposed block.
    vecs: Mat<f64>,
    /// Eigenvalues; also the previous iterate of [`BlockScratch::refine`].
    vals: Mat<f64>,
    /// `1 / l_jj` of the factor in `work` ([`super::substitution`]).
    inv_diag: Vec<f64>,
    /// Right-hand side / solution of a block, and a second vector.
    rhs: Mat<f64>,
    tmp: Mat<f64>,
    /// Work space of the kernels, sized for `dim`.
    mem: Option<MemBuffer>,
    dim: usize,
}

impl Default for BlockScratch {
    fn default() -> Self {
        BlockScratch {
            work: Mat::new(),
            vecs: Mat::new(),
            vals: Mat::new(),
            inv_diag: Vec::new(),
            rhs: Mat::new(),
            tmp: Mat::new(),
            mem: None,
            dim: 0,
        }
    }
}

/// What one block solve did (for the in-order replay of a parallel solve,
/// see [`BlockSolver::direction`]).
#[derive(Clone, Copy, Debug, Default)]
struct BlockRecord {
    /// Eigen-decomposed.
    eigen: bool,
    /// Entered [`BlockScratch::shifted_factor`], which reads the running
    /// shift `τ₀`: its result depends on the blocks before it.
    read_shift: bool,
    /// The running shift after the block.
    shift_out: f64,
    /// The block's counters.
    stats: LinearSolveStats,
}

/// Total `Σ m_b³` (flops of the blocks' factorizations, up to a constant)
/// from which the blocks of one solve are spread over the thread pool.
/// **Off by default** (`usize::MAX`): on the shared 2-core machine the
/// benchmarks run on (load 3–7 from other builds), handing the four
/// 64-coordinate blocks of the 32-link chains to a second thread made the
/// linear solve 1.5–4× *slower* (0.55–0.63 → 0.86–2.4 ms per step; the
/// worker waits for a core). Set the environment variable
/// `SDRS_PARALLEL_SOLVE_MIN_CUBES` (e.g. `400000`: four 46-coordinate
/// blocks) to turn it on where cores are free; results are bitwise the same
/// either way.
pub const PARALLEL_MIN_CUBES: usize = usize::MAX;

/// [`PARALLEL_MIN_CUBES`], or `SDRS_PARALLEL_SOLVE_MIN_CUBES` when set.
fn parallel_min_cubes() -> usize {
    std::env::var("SDRS_PARALLEL_SOLVE_MIN_CUBES")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(PARALLEL_MIN_CUBES)
}

/// Tile edge of [`BlockScratch::gather`] (coordinates).
const GATHER_TILE: usize = 16;

/// Block-wise clamped Newton solver with persistent scratch.
pub struct BlockSolver {
    /// Union–find parents over coordinates.
    parent: Vec<usize>,
    /// Coordinates grouped by block (ascending within a block; blocks in the
    /// order of their smallest coordinate).
    order: Vec<usize>,
    /// Block `b` is `order[starts[b]..starts[b + 1]]`.
    starts: Vec<usize>,
    /// Per-block cursor used while grouping.
    cursor: Vec<usize>,
    /// Scratch of the sequential path (and of the in-order replay).
    main: BlockScratch,
    /// One scratch per chunk of a parallel solve.
    workers: Vec<BlockScratch>,
    /// Per-block records and solutions (in `order`) of a parallel solve.
    records: Vec<BlockRecord>,
    sols: Vec<f64>,
    /// Chunk bounds (in blocks) of a parallel solve.
    bounds: Vec<usize>,
    /// Last successful shift `τ` of [`Mode::Shift`] (0: none yet).
    last_shift: f64,
    /// [`parallel_min_cubes`] (tests lower or raise it).
    parallel_min_cubes: usize,
    /// Row bounds of the next partition only ([`BlockSolver::bound_rows`];
    /// empty: every row).
    row_end: Vec<usize>,
    pub stats: LinearSolveStats,
}

impl Default for BlockSolver {
    fn default() -> Self {
        BlockSolver {
            parent: Vec::new(),
            order: Vec::new(),
            starts: Vec::new(),
            cursor: Vec::new(),
            main: BlockScratch::default(),
            workers: Vec::new(),
            records: Vec::new(),
            sols: Vec::new(),
            bounds: Vec::new(),
            last_shift: 0.0,
            parallel_min_cubes: parallel_min_cubes(),
            row_end: Vec::new(),
            stats: LinearSolveStats::default(),
        }
    }
}

impl Clone for BlockSolver {
    /// Scratch is not state: a clone starts empty.
    fn clone(&self) -> Self {
        BlockSolver {
            stats: self.stats,
            ..Default::default()
        }
    }
}

impl std::fmt::Debug for BlockSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockSolver")
            .field("dim", &self.main.dim)
            .field("stats", &self.stats)
            .finish()
    }
}

/// What a block solve does when `H_B − c I` is not positive definite.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Clamped eigen step (`abs`: absolute-value projection).
    Clamped { abs: bool },
    /// Cholesky of `H_B + τ I` with the smallest `τ = τ₀ 4^k` that
    /// factors (Nocedal & Wright, Alg. 3.3; `τ₀` from the block's last
    /// shift, else `max(2c, 1e-6 max_i |h_ii|)`): a positive-definite model,
    /// Cholesky-only. The step differs from the clamped eigen step, the
    /// converged point does not (Newton stops on `‖∇O‖∞`).
    Shift,
}

impl BlockSolver {
    /// Groups the coordinates into the connected components of the
    /// sparsity graph of `h`: a non-zero entry `(i, j)`, `i ≥ j`, joins `i`
    /// and `j`.
    ///
    /// Only the lower triangle is read: `h` is a Hessian, **structurally
    /// symmetric** (every term writes `(k, l)` and `(l, k)` together, with
    /// the same additions in the same order, so an entry cancels to an
    /// exact zero only together with its mirror). Halving the scan matters:
    /// at 256 coordinates the matrix is 512 kB, read once per Newton
    /// iteration, and the scan is memory-bound.
    fn partition(&mut self, h: &DMatrix<f64>) {
        let n = h.nrows();
        let p = &mut self.parent;
        p.clear();
        p.extend(0..n);
        let bound = (self.row_end.len() == n).then_some(&self.row_end[..]);
        // The lower triangle, column by column (contiguous; the transposed
        // read `h[(j, i)]` strided by `n` and dominated this scan). The
        // components do not depend on the order in which edges are joined,
        // and each root is the smallest index of its component, so the
        // grouping below is the same whatever the order.
        // (Plain slices: nalgebra's generic matrix iterator does not
        // vectorize and cost more than the scan itself.)
        join_nonzeros(h.as_slice(), n, bound, p);
        self.row_end.clear();
        // Roots are the smallest index of their block; count sizes per root.
        self.cursor.clear();
        self.cursor.resize(n + 1, 0);
        for i in 0..n {
            let r = find(p, i);
            p[i] = r;
            self.cursor[r] += 1;
        }
        // Block starts in root order; then place coordinates.
        self.starts.clear();
        let mut acc = 0;
        for r in 0..n {
            let size = self.cursor[r];
            if size > 0 {
                self.starts.push(acc);
                self.cursor[r] = acc;
                acc += size;
            }
        }
        self.starts.push(n);
        self.order.clear();
        self.order.resize(n, 0);
        for (i, &r) in p.iter().enumerate() {
            self.order[self.cursor[r]] = i;
            self.cursor[r] += 1;
        }
    }

    /// Declares that in the matrix of the **next** call only (a direction
    /// or a solve), the rows `i ≥ ends[j]` of column `j` are zero (the
    /// step Hessian's [`super::envelope::ColumnEnvelope`]): the partition's
    /// scan skips them. The blocks found are the same.
    pub fn bound_rows(&mut self, ends: &[usize]) {
        self.row_end.clear();
        self.row_end.extend_from_slice(ends);
    }

    /// `dir = −Ĥ⁻¹ g` (see the module documentation). `h` must be symmetric
    /// up to round-off (the average of `h_ij` and `h_ji` is used).
    pub fn clamped_direction(
        &mut self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        clamp: f64,
        abs: bool,
        dir: &mut DVector<f64>,
    ) {
        self.direction(h, g, clamp, Mode::Clamped { abs }, 0.0, dir)
    }

    /// `dir = −B⁻¹ g` with `B = H` on blocks where `H − c I` is positive
    /// definite and the `mode`'s positive-definite model elsewhere.
    ///
    /// **Settled blocks.** A block whose gradient is already below `settled`
    /// (`‖g_B‖∞ < settled`; Newton passes its stopping tolerance, `0`
    /// disables) gets `dir_B = 0` without a factorization: it already meets
    /// the stopping test, and being independent of the other blocks (no
    /// Hessian coupling) its gradient does not move while they do, to first
    /// order. In a step where one pair of chains needs ten iterations the
    /// others are not re-factored ten times. The converged point then
    /// differs from the one with every block re-solved by at most that
    /// block's last Newton step, `‖H_B⁻¹ g_B‖`, below the tolerance's scale.
    ///
    /// **Independent blocks in parallel** (off by default, see
    /// [`PARALLEL_MIN_CUBES`]). When there are several blocks and
    /// `Σ m_b³ ≥` the threshold, the blocks are cut into one
    /// contiguous chunk per pool thread, balanced by `m_b³`
    /// ([`crate::geometry::parallel::balanced_bounds`]), and each chunk is
    /// solved with its own scratch. A block's result depends on nothing
    /// outside it except the running shift `τ₀` of [`Mode::Shift`], which
    /// the sequential loop carries from block to block. The chunks start
    /// from the shift at the call's start; then the blocks are replayed in
    /// order, and a block that read the shift (entered the shifted
    /// factorization) while the in-order running shift differs is solved
    /// again, sequentially, with the right one. The result — directions,
    /// the shift carried to the next call and the counters — is therefore
    /// bitwise the sequential one for any thread count.
    pub fn direction(
        &mut self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        clamp: f64,
        mode: Mode,
        settled: f64,
        dir: &mut DVector<f64>,
    ) {
        self.partition(h);
        self.stats.solves += 1;
        let nb = self.starts.len() - 1;
        let cubes = |b: usize| (self.starts[b + 1] - self.starts[b]).pow(3);
        let total: usize = (0..nb).map(cubes).sum();
        let threads = rayon::current_num_threads();
        let mut any_eigen = false;
        if nb < 2 || threads < 2 || total < self.parallel_min_cubes {
            // Sized for the whole problem, as the scratch always was: the
            // blocks' column stride (and so the kernels' arithmetic) is
            // then the same on every path.
            self.main.reserve(g.len());
            for b in 0..nb {
                let idx = &self.order[self.starts[b]..self.starts[b + 1]];
                if is_settled(g, idx, settled) {
                    self.stats.blocks += 1;
                    self.stats.settled_blocks += 1;
                    idx.iter().for_each(|&i| dir[i] = 0.0);
                    continue;
                }
                let mut stats = LinearSolveStats::default();
                let rec =
                    self.main
                        .solve_block(h, g, idx, clamp, mode, &mut self.last_shift, &mut stats);
                self.stats.add(&stats);
                any_eigen |= rec;
                for (a, &i) in idx.iter().enumerate() {
                    dir[i] = self.main.rhs[(a, 0)];
                }
            }
        } else {
            any_eigen = self.direction_parallel(h, g, clamp, mode, settled, dir, threads);
        }
        if any_eigen {
            self.stats.eigen_solves += 1;
        }
    }

    /// The parallel path of [`BlockSolver::direction`].
    // Arguments kept separate: private solver method: the matrix, right-hand side and output plus the clamp settings of one Newton iteration.
    #[allow(clippy::too_many_arguments)]
    fn direction_parallel(
        &mut self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        clamp: f64,
        mode: Mode,
        settled: f64,
        dir: &mut DVector<f64>,
        threads: usize,
    ) -> bool {
        use rayon::prelude::*;
        let nb = self.starts.len() - 1;
        let starts = &self.starts;
        let order = &self.order;
        crate::geometry::parallel::balanced_bounds(
            (0..nb).map(|b| (starts[b + 1] - starts[b]).pow(3)),
            threads,
            &mut self.bounds,
        );
        self.workers.resize_with(threads, BlockScratch::default);
        self.records.clear();
        self.records.resize(nb, BlockRecord::default());
        self.sols.clear();
        self.sols.resize(order.len(), 0.0);
        let shift0 = self.last_shift;
        let n = g.len();
        // Chunk j owns blocks bounds[j]..bounds[j + 1], i.e. the
        // coordinates starts[bounds[j]]..starts[bounds[j + 1]] of `order`.
        let mut rec_parts: Vec<&mut [BlockRecord]> = Vec::with_capacity(threads);
        let mut sol_parts: Vec<&mut [f64]> = Vec::with_capacity(threads);
        {
            let (mut recs, mut sols) = (&mut self.records[..], &mut self.sols[..]);
            for j in 0..threads {
                let (b0, b1) = (self.bounds[j], self.bounds[j + 1]);
                let (r, rest) = recs.split_at_mut(b1 - b0);
                let (s, srest) = sols.split_at_mut(starts[b1] - starts[b0]);
                rec_parts.push(r);
                sol_parts.push(s);
                recs = rest;
                sols = srest;
            }
        }
        let bounds = &self.bounds;
        self.workers
            .par_iter_mut()
            .zip(rec_parts)
            .zip(sol_parts)
            .enumerate()
            .for_each(|(j, ((sc, recs), sols))| {
                let (b0, b1) = (bounds[j], bounds[j + 1]);
                if b0 == b1 {
                    return;
                }
                sc.reserve(n);
                let mut shift = shift0;
                for (k, b) in (b0..b1).enumerate() {
                    let idx = &order[starts[b]..starts[b + 1]];
                    let mut rec = BlockRecord::default();
                    let off = starts[b] - starts[b0];
                    if is_settled(g, idx, settled) {
                        rec.stats.blocks += 1;
                        rec.stats.settled_blocks += 1;
                        recs[k] = rec;
                        sols[off..off + idx.len()].fill(0.0);
                        continue;
                    }
                    let before = shift;
                    rec.eigen = sc.solve_block(h, g, idx, clamp, mode, &mut shift, &mut rec.stats);
                    rec.read_shift = rec.stats.shift_attempts > 0;
                    rec.shift_out = shift;
                    // Later blocks of this chunk start from the chunk's
                    // start shift too (the replay fixes what differs).
                    shift = before;
                    recs[k] = rec;
                    for a in 0..idx.len() {
                        sols[off + a] = sc.rhs[(a, 0)];
                    }
                }
            });
        // In-order replay.
        let mut any_eigen = false;
        let mut shift = shift0;
        for b in 0..nb {
            let (s, e) = (self.starts[b], self.starts[b + 1]);
            let idx = &self.order[s..e];
            let mut rec = self.records[b];
            if rec.read_shift && shift != shift0 {
                self.main.reserve(n);
                rec = BlockRecord::default();
                rec.eigen =
                    self.main
                        .solve_block(h, g, idx, clamp, mode, &mut shift, &mut rec.stats);
                for (a, &i) in idx.iter().enumerate() {
                    dir[i] = self.main.rhs[(a, 0)];
                }
            } else {
                if rec.read_shift {
                    shift = rec.shift_out;
                }
                for (a, &i) in idx.iter().enumerate() {
                    dir[i] = self.sols[s + a];
                }
            }
            self.stats.add(&rec.stats);
            any_eigen |= rec.eigen;
        }
        self.last_shift = shift;
        any_eigen
    }

    /// `vᵀ H v` over the blocks of the last [`BlockSolver::direction`]'s
    /// partition of `h` (entries between blocks are exactly zero), skipping
    /// blocks where `v` is zero (settled ones): `Σ_B v_Bᵀ H_BB v_B`.
    pub fn block_quadratic_form(&self, h: &DMatrix<f64>, v: &DVector<f64>) -> f64 {
        let mut sum = 0.0;
        for b in 0..self.starts.len().saturating_sub(1) {
            let idx = &self.order[self.starts[b]..self.starts[b + 1]];
            if idx.iter().all(|&i| v[i] == 0.0) {
                continue;
            }
            for &j in idx {
                let col = h.column(j);
                let hv: f64 = idx.iter().map(|&i| col[i] * v[i]).sum();
                sum += v[j] * hv;
            }
        }
        sum
    }

    /// `x = H⁻¹ b` block by block with Cholesky (the adjoint's solve with
    /// the unmodified Hessian at a converged step). `false` when a block is
    /// not positive definite (`x` is then unspecified; the caller falls
    /// back to a pivoted LU).
    pub fn spd_solve(&mut self, h: &DMatrix<f64>, b: &DVector<f64>, x: &mut DVector<f64>) -> bool {
        self.partition(h);
        let sc = &mut self.main;
        sc.reserve(b.len());
        for k in 0..self.starts.len() - 1 {
            let idx = &self.order[self.starts[k]..self.starts[k + 1]];
            let m = idx.len();
            sc.gather(h, idx, 0.0);
            if !sc.cholesky_faer(m) {
                return false;
            }
            for (a, &i) in idx.iter().enumerate() {
                sc.rhs[(a, 0)] = b[i];
            }
            let l = sc.work.as_ref().submatrix(0, 0, m, m);
            let mut r = sc.rhs.as_mut().submatrix_mut(0, 0, m, 1);
            cholesky_solve(l, r.rb_mut());
            for (a, &i) in idx.iter().enumerate() {
                x[i] = sc.rhs[(a, 0)];
            }
        }
        true
    }
}

impl LinearSolveStats {
    fn add(&mut self, o: &LinearSolveStats) {
        self.blocks += o.blocks;
        self.eigen_blocks += o.eigen_blocks;
        self.eigen_solves += o.eigen_solves;
        self.solves += o.solves;
        self.shifted_blocks += o.shifted_blocks;
        self.shift_attempts += o.shift_attempts;
        self.refine_sweeps += o.refine_sweeps;
        self.refine_fallbacks += o.refine_fallbacks;
        self.settled_blocks += o.settled_blocks;
    }
}

impl BlockScratch {
    /// Sizes every buffer for problems of dimension `n` (no-op when large
    /// enough already).
    fn reserve(&mut self, n: usize) {
        if n <= self.dim && self.mem.is_some() {
            return;
        }
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            llt::cholesky_in_place_scratch::<f64>(n, par, Default::default()),
            evd::self_adjoint_evd_scratch::<f64>(
                n,
                evd::ComputeEigenvectors::Yes,
                par,
                Default::default(),
            ),
        ]);
        self.mem = Some(MemBuffer::new(req));
        self.work = Mat::zeros(n, n);
        self.vecs = Mat::zeros(n, n);
        self.vals = Mat::zeros(n, 1);
        self.inv_diag = Vec::with_capacity(n);
        self.rhs = Mat::zeros(n, 1);
        self.tmp = Mat::zeros(n, 1);
        self.dim = n;
    }

    /// Copies block `idx` of `(h + hᵀ)/2 − shift I` into `work` (lower
    /// triangle).
    ///
    /// In square tiles of [`GATHER_TILE`] coordinates: the mirrored read
    /// `h[(j, i)]` walks a row of the column-major `h` (stride `n`), and
    /// inside a tile the rows it touches stay in cache across the tile's
    /// columns. Each entry is the same `0.5 (h_ij + h_ji)` whatever the
    /// traversal, so the block is bitwise the untiled one.
    fn gather(&mut self, h: &DMatrix<f64>, idx: &[usize], shift: f64) {
        let m = idx.len();
        if m == 0 {
            return;
        }
        let n = h.nrows();
        let hs = h.as_slice();
        // Ascending distinct coordinates spanning `m` values: `s, s+1, …`
        // (a chain's block). Then both reads are plain strided walks.
        let contiguous = idx[m - 1] - idx[0] == m - 1;
        let s = idx[0];
        for b0 in (0..m).step_by(GATHER_TILE) {
            let b1 = (b0 + GATHER_TILE).min(m);
            for a0 in (b0..m).step_by(GATHER_TILE) {
                let a1 = (a0 + GATHER_TILE).min(m);
                for b in b0..b1 {
                    let jb = idx[b];
                    let (hcol, w) = (&hs[jb * n..(jb + 1) * n], self.work.col_as_slice_mut(b));
                    let a_start = a0.max(b);
                    if a_start >= a1 {
                        continue;
                    }
                    // h_ij: column jb, row ia; h_ji: column ia, row jb.
                    if contiguous {
                        let direct = &hcol[s + a_start..s + a1];
                        let mut at = (s + a_start) * n + jb;
                        for (wa, &d) in w[a_start..a1].iter_mut().zip(direct) {
                            *wa = 0.5 * (d + hs[at]);
                            at += n;
                        }
                    } else {
                        for a in a_start..a1 {
                            let ia = idx[a];
                            w[a] = 0.5 * (hcol[ia] + hs[ia * n + jb]);
                        }
                    }
                    if a_start == b {
                        w[b] -= shift;
                    }
                }
            }
        }
    }

    /// One block `idx`; its direction is left in `rhs[..m]`. Returns
    /// whether it was eigen-decomposed. `last_shift` is the running shift
    /// of [`Mode::Shift`]; counters go to `stats`.
    // Arguments kept separate: private solver method: one diagonal block's inputs, output and counters; called per block per iteration.
    #[allow(clippy::too_many_arguments)]
    fn solve_block(
        &mut self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        idx: &[usize],
        clamp: f64,
        mode: Mode,
        last_shift: &mut f64,
        stats: &mut LinearSolveStats,
    ) -> bool {
        let m = idx.len();
        stats.blocks += 1;
        for (a, &i) in idx.iter().enumerate() {
            self.rhs[(a, 0)] = -g[i];
        }
        // Shifted Cholesky: succeeds iff λ_min(H_B) > c.
        self.gather(h, idx, clamp);
        let pd = self.cholesky(m);
        if pd && self.refine(m, clamp, stats) {
            return false;
        }
        let mut solved = pd && {
            stats.refine_fallbacks += 1;
            self.gather(h, idx, 0.0);
            self.cholesky(m)
        };
        if !solved && mode == Mode::Shift {
            solved = self.shifted_factor(h, idx, clamp, last_shift, stats);
        }
        if solved {
            super::substitution::inverse_diagonal(&self.work, m, &mut self.inv_diag);
            let x = &mut self.rhs.col_as_slice_mut(0)[..m];
            super::substitution::cholesky_solve(&self.work, &self.inv_diag, m, x);
        } else {
            stats.eigen_blocks += 1;
            self.gather(h, idx, 0.0);
            let abs = matches!(mode, Mode::Clamped { abs: true });
            self.eigen_solve(m, clamp, abs);
        }
        !solved
    }

    /// `rhs ← H_B⁻¹ rhs` from the factor `L Lᵀ = A = H_B − c I` in `work`,
    /// without factoring `H_B` itself: `H_B x = b ⇔ A x = b − c x`, iterated
    /// as `x_{k+1} = A⁻¹ (b − c x_k)` (error contracts by `ρ = c/λ_min(A)`,
    /// `≤ 1e-3/λ` per sweep for the step Hessians, whose smallest
    /// eigenvalues are `~m/Δt²` ≫ `c` — measured `ρ ≈ 1e-5…3e-4` on the
    /// 32-link chains; one `m²` solve each, [`super::substitution`], instead
    /// of an `m³/3` factorization).
    ///
    /// Stops at the first `x_k` (`k ≥ 1`) with
    ///
    /// - `d_k = ‖x_k − x_{k−1}‖∞ ≤ 4ε‖x_k‖∞` (converged to round-off), or
    ///   `d_k` no longer shrinking below `1e-13‖x_k‖∞` (round-off); or
    /// - **predicted correction** (`k ≥ 2`): with the observed contraction
    ///   `r = d_k / d_{k−1} ≤ ½`, the remaining error of `x_k` is about
    ///   `d_k r / (1 − r) ≤ 2 d_k r`; stop when that is below the solve's
    ///   own round-off scale, `ε κ̂ ‖x_k‖∞` with `κ̂ = max_j l_jj² / min_j l_jj²`
    ///   (the Cholesky pivots `l_jj²` lie in `[λ_min(A), λ_max(A)]`, so
    ///   `κ̂ ≤ κ(A)`: a lower bound of the condition number, i.e. a
    ///   conservative scale; never below `4ε`). Further sweeps would change
    ///   `x` by less than the rounding of the solve itself. On the 32-link
    ///   chains this takes 3 sweeps where the first test alone took 5.
    ///
    /// `false` (rhs restored to `b`) after 30 sweeps, for `λ_min(H_B) ≲ 2c`.
    fn refine(&mut self, m: usize, clamp: f64, stats: &mut LinearSolveStats) -> bool {
        super::substitution::inverse_diagonal(&self.work, m, &mut self.inv_diag);
        let (lo, hi) = self
            .inv_diag
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| {
                (lo.min(v.abs()), hi.max(v.abs()))
            });
        // κ̂ = (max l_jj / min l_jj)² = (max 1/l_jj / min 1/l_jj)².
        let kappa = (hi / lo) * (hi / lo);
        let scale = (f64::EPSILON * kappa).max(4.0 * f64::EPSILON);
        let b = &mut self.tmp.col_as_slice_mut(0)[..m];
        let x = &mut self.rhs.col_as_slice_mut(0)[..m];
        let prev = &mut self.vals.col_as_slice_mut(0)[..m];
        b.copy_from_slice(x);
        let mut last = f64::INFINITY;
        for sweep in 0..30 {
            super::substitution::cholesky_solve(&self.work, &self.inv_diag, m, x);
            stats.refine_sweeps += 1;
            let (mut diff, mut size) = (0.0f64, 0.0f64);
            for (xa, pa) in x.iter().zip(prev.iter_mut()) {
                diff = diff.max((xa - *pa).abs());
                size = size.max(xa.abs());
                *pa = *xa;
            }
            // (The first sweep has no previous iterate to compare with.)
            if sweep > 0 {
                let r = diff / last;
                if diff <= 4.0 * f64::EPSILON * size
                    || (diff >= last && diff <= 1e-13 * size)
                    || (sweep > 1 && r <= 0.5 && 2.0 * diff * r <= scale * size)
                {
                    return true;
                }
                last = diff;
            }
            for ((xa, &ba), &pa) in x.iter_mut().zip(b.iter()).zip(prev.iter()) {
                *xa = ba - clamp * pa;
            }
        }
        x.copy_from_slice(b);
        false
    }

    /// [`Mode::Shift`]: factors `H_B + τ I` into `work` for the smallest
    /// `τ = τ₀ 4^k` (`k < 40`) that is positive definite; `false` if none.
    fn shifted_factor(
        &mut self,
        h: &DMatrix<f64>,
        idx: &[usize],
        clamp: f64,
        last_shift: &mut f64,
        stats: &mut LinearSolveStats,
    ) -> bool {
        let m = idx.len();
        let dmax = idx.iter().map(|&i| h[(i, i)].abs()).fold(0.0, f64::max);
        let floor = (2.0 * clamp).max(1e-6 * dmax);
        let mut tau = if *last_shift > 0.0 {
            (0.25 * *last_shift).max(floor)
        } else {
            floor
        };
        for _ in 0..40 {
            stats.shift_attempts += 1;
            self.gather(h, idx, -tau);
            if self.cholesky(m) {
                *last_shift = tau;
                stats.shifted_blocks += 1;
                return true;
            }
            tau *= 4.0;
        }
        false
    }

    /// In-place Cholesky of the leading `m × m` block of `work` (lower
    /// triangle); `false` when a pivot is not positive. Blocks of up to
    /// [`SMALL_CHOLESKY_MAX`] coordinates use [`super::small_cholesky`],
    /// larger ones faer's blocked factorization.
    fn cholesky(&mut self, m: usize) -> bool {
        if m <= SMALL_CHOLESKY_MAX {
            return super::small_cholesky::cholesky_in_place(&mut self.work, m);
        }
        self.cholesky_faer(m)
    }

    /// faer's in-place Cholesky of the leading `m × m` block of `work`
    /// (the adjoint's [`BlockSolver::spd_solve`] keeps it for every size).
    fn cholesky_faer(&mut self, m: usize) -> bool {
        let stack = MemStack::new(self.mem.as_mut().expect("reserved"));
        let a = self.work.as_mut().submatrix_mut(0, 0, m, m);
        llt::cholesky_in_place(a, Default::default(), Par::Seq, stack, Default::default()).is_ok()
    }

    /// `rhs ← U diag(1 / max(λ, c)) Uᵀ rhs` (`|λ|` with `abs`) for the
    /// block gathered in `work`.
    fn eigen_solve(&mut self, m: usize, clamp: f64, abs: bool) {
        let stack = MemStack::new(self.mem.as_mut().expect("reserved"));
        let a = self.work.as_ref().submatrix(0, 0, m, m);
        let u = self.vecs.as_mut().submatrix_mut(0, 0, m, m);
        let s = self
            .vals
            .as_mut()
            .submatrix_mut(0, 0, m, 1)
            .col_mut(0)
            .as_diagonal_mut();
        let ok = evd::self_adjoint_evd(a, s, Some(u), Par::Seq, stack, Default::default());
        if ok.is_err() {
            // The QR iteration did not converge (not seen in practice):
            // fall back to a steepest-descent step scaled by `1/c`, a
            // descent direction the line search can shorten.
            for a in 0..m {
                self.rhs[(a, 0)] /= clamp.max(f64::MIN_POSITIVE);
            }
            return;
        }
        let u = self.vecs.as_ref().submatrix(0, 0, m, m);
        // tmp = Uᵀ rhs, scaled.
        for k in 0..m {
            let mut c = 0.0;
            let col = u.col(k);
            for a in 0..m {
                c += col[a] * self.rhs[(a, 0)];
            }
            let lam = self.vals[(k, 0)];
            let lam = if abs { lam.abs() } else { lam };
            self.tmp[(k, 0)] = c / lam.max(clamp);
        }
        for a in 0..m {
            self.rhs[(a, 0)] = 0.0;
        }
        for k in 0..m {
            let c = self.tmp[(k, 0)];
            let col = u.col(k);
            for a in 0..m {
                self.rhs[(a, 0)] += col[a] * c;
            }
        }
    }
}

/// Root of `i` in the union–find forest `c`, halving the path.
fn find(c: &mut [usize], mut i: usize) -> usize {
    while c[i] != i {
        c[i] = c[c[i]];
        i = c[i];
    }
    i
}

/// The scan of [`BlockSolver::partition`]: joins `i` and `j` in the
/// union–find forest `p` for every non-zero `h_ij`, `i ≥ j`, of the
/// column-major `n × n` matrix `h`. Runs with AVX-512 or AVX2 where the CPU
/// has them (only comparisons: the same unions on every path; measured at
/// N = 32: 16.2 µs per call for the previous scan, 6.2 µs with AVX2, about
/// a fifth less again with AVX-512).
fn join_nonzeros(h: &[f64], n: usize, bound: Option<&[usize]>, p: &mut [usize]) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU supports AVX-512F (checked above).
        unsafe { join_nonzeros_avx512(h, n, bound, p) };
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU supports AVX2 (checked above).
        unsafe { join_nonzeros_avx2(h, n, bound, p) };
        return;
    }
    join_nonzeros_generic(h, n, bound, p);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn join_nonzeros_avx512(h: &[f64], n: usize, bound: Option<&[usize]>, p: &mut [usize]) {
    join_nonzeros_generic(h, n, bound, p);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn join_nonzeros_avx2(h: &[f64], n: usize, bound: Option<&[usize]>, p: &mut [usize]) {
    join_nonzeros_generic(h, n, bound, p);
}

#[inline(always)]
fn join_nonzeros_generic(h: &[f64], n: usize, bound: Option<&[usize]>, p: &mut [usize]) {
    if n == 0 {
        return;
    }
    for (j, col) in h.chunks_exact(n).enumerate() {
        let mut rj = find(p, j);
        // Entry `(i, j)` needs a union only when non-zero and `i` is not
        // already known to be in `j`'s component (`p[i] == rj`: path
        // compression makes this the common case inside a dense block).
        // Fixed chunks of 8 are tested branch-free first: all zero (most of
        // the matrix when robots are apart), then none needing a union (the
        // rest); both tests vectorize.
        let end = bound.map_or(n, |b| b[j].clamp(j, n));
        let mut chunks = col[j..end].chunks_exact(8);
        let mut base = j;
        for c in &mut chunks {
            let c: &[f64; 8] = c.try_into().expect("chunk of 8");
            if !c.iter().fold(false, |b, &v| b | (v != 0.0)) {
                base += 8;
                continue;
            }
            let pc: &[usize; 8] = p[base..base + 8].try_into().expect("chunk of 8");
            let busy = c
                .iter()
                .zip(pc)
                .fold(false, |b, (&v, &pi)| b | ((v != 0.0) & (pi != rj)));
            if busy {
                rj = join_column(p, c, base, rj);
            }
            base += 8;
        }
        rj = join_column(p, chunks.remainder(), base, rj);
        let _ = rj;
    }
}

/// Joins `base + k` with the component of root `rj` for every non-zero
/// `c[k]`; returns the (possibly smaller) root.
#[inline(always)]
fn join_column(p: &mut [usize], c: &[f64], base: usize, mut rj: usize) -> usize {
    for (k, &v) in c.iter().enumerate() {
        let i = base + k;
        if v != 0.0 && p[i] != rj {
            let a = find(p, i);
            if a != rj {
                let r = a.min(rj);
                p[a.max(rj)] = r;
                rj = r;
            }
        }
    }
    rj
}

/// `‖g_B‖∞ < settled` for block `idx` (never for `settled ≤ 0`).
fn is_settled(g: &DVector<f64>, idx: &[usize], settled: f64) -> bool {
    settled > 0.0 && idx.iter().all(|&i| g[i].abs() < settled)
}

/// `x ← (L Lᵀ)⁻¹ x` for a lower-triangular factor `L`.
fn cholesky_solve(l: MatRef<'_, f64>, mut x: MatMut<'_, f64>) {
    use faer::linalg::triangular_solve as tri;
    tri::solve_lower_triangular_in_place(l, x.rb_mut(), Par::Seq);
    tri::solve_upper_triangular_in_place(l.transpose(), x.rb_mut(), Par::Seq);
}

#[cfg(test)]
#[path = "linear_solve_tests.rs"]
mod tests;
