//! Terms of the per-step objective `O(θ^{t+1})` (paper, eq. `SDRS`).
//!
//! Every term implements [`Energy`]. Terms that depend on link poses write
//! their value, gradient `∂E/∂A_i` (3×4) and pose Hessian blocks (12×12)
//! into an [`EnergyAccumulator`]; terms that depend on the coordinates
//! directly (the PD controller) write `∂E/∂θ` and `∂²E/∂θ²`. The assembler
//! (`sim::assemble`) contracts the pose quantities with the kinematic
//! derivatives, so a term never sees the kinematic tree.
//!
//! Inertia, gravity and PD are here; contact, friction and calibration
//! effects ([`effects`]) plug in the same way.

pub mod contact;
pub mod dof_hessian;
pub mod effects;
pub mod friction;
pub mod gravity;
pub mod inertia;
pub mod joint_limit;
pub mod mimic;
pub mod pairs;
pub mod pd;
pub mod pd_pose;
pub mod vjp;

pub use crate::control::PdTarget;
pub use contact::ContactEnergy;
pub use dof_hessian::DofHessian;
pub use friction::FrictionEnergy;
pub use gravity::Gravity;
pub use inertia::Inertia;
pub use joint_limit::JointLimits;
pub use mimic::MimicTies;
pub use pd::PdController;

use crate::kinematics::Kinematics;
use crate::math::Pose;
use crate::model::Model;
use nalgebra::{DVector, Matrix3x4, Matrix4, SMatrix, Vector3};

/// 12×12 Hessian block over `vec(A_i)`.
pub type PoseHessian = SMatrix<f64, 12, 12>;

/// Which derivatives an evaluation must produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Need {
    Value,
    Gradient,
    Hessian,
}

/// Error from an energy term (a term never panics on bad numbers).
#[derive(Debug, Clone, thiserror::Error)]
pub enum EnergyError {
    #[error("{term}: {msg}")]
    Failed { term: &'static str, msg: String },
}

/// Everything a term may read about the time step being solved.
pub struct StepContext<'a> {
    pub model: &'a Model,
    /// Time step Δt (s).
    pub dt: f64,
    /// Time at the end of the step, `t^{t+1}` (s).
    pub time: f64,
    /// Gravity (m/s²), world frame.
    pub gravity: Vector3<f64>,
    /// Link poses at `t` (`A^t`).
    pub poses_prev: &'a [Pose],
    /// Link poses at `t−1` (`A^{t−1}`).
    pub poses_prev2: &'a [Pose],
    /// Coordinates at `t` (`θ^t`).
    pub q_prev: &'a DVector<f64>,
    /// Coordinates at `t−1` (`θ^{t−1}`, in the charts of `q_prev`).
    pub q_prev2: &'a DVector<f64>,
    /// PD targets for this step (`u^t`).
    pub targets: &'a [PdTarget],
    /// Free root joints whose six `targets` (from `first`) are one pose
    /// target ([`pd_pose`]).
    pub pose_targets: &'a [crate::control::PoseTarget],
    /// Whether terms time their own sub-stages (the contact term's broad
    /// phase and collision detection): the simulator's timers are detailed
    /// ([`crate::counters::StageTimers::set_detailed`]). Without it no term
    /// reads the clock inside an evaluation.
    pub timed: bool,
}

/// Output buffers for the terms; reused across evaluations.
#[derive(Clone, Debug)]
pub struct EnergyAccumulator {
    pub value: f64,
    /// `∂E/∂A_i` per link.
    pub link_grad: Vec<Matrix3x4<f64>>,
    /// Diagonal pose Hessian blocks `∂²E/∂A_i²`.
    pub link_hess: Vec<PoseHessian>,
    /// Whether `link_hess[i]` was written since the last reset.
    pub link_hess_set: Vec<bool>,
    /// Structured diagonal pose Hessian blocks `W_i ⊗ I₃` (`W_i` 4×4
    /// symmetric, link-local homogeneous coordinates): the form of every
    /// term that is a sum of isotropic vertex quadratics (inertia). The
    /// assembler contracts these in O(|θ|²) through subtree composites.
    pub link_moment: Vec<Matrix4<f64>>,
    /// Whether any `link_moment` was written since the last reset.
    pub link_moment_set: bool,
    /// Off-diagonal pose Hessian blocks `∂²E/∂A_i∂A_j` (`i ≠ j`, each
    /// unordered pair once; the assembler adds the transpose).
    pub pair_hess: Vec<(usize, usize, PoseHessian)>,
    /// Where each link pair's block is in `pair_hess`: the terms that write
    /// pair blocks ([`pairs::scatter_pair`]: contact and friction) merge
    /// theirs into one block per link pair, so the assembler contracts each
    /// pair once.
    pair_slots: std::collections::BTreeMap<(usize, usize), usize>,
    /// `∂E/∂θ` from terms written directly in coordinates.
    pub dof_grad: DVector<f64>,
    /// `∂²E/∂θ²` from terms written directly in coordinates (sparse: a
    /// diagonal and a few off-diagonal entries).
    pub dof_hess: DofHessian,
}

impl EnergyAccumulator {
    pub fn new(model: &Model) -> Self {
        let n = model.links.len();
        let m = model.ndof();
        EnergyAccumulator {
            value: 0.0,
            link_grad: vec![Matrix3x4::zeros(); n],
            link_hess: vec![PoseHessian::zeros(); n],
            link_hess_set: vec![false; n],
            link_moment: vec![Matrix4::zeros(); n],
            link_moment_set: false,
            pair_hess: Vec::new(),
            pair_slots: std::collections::BTreeMap::new(),
            dof_grad: DVector::zeros(m),
            dof_hess: DofHessian::zeros(m),
        }
    }

    /// Clears the buffers for an evaluation with the given needs.
    pub fn reset(&mut self, need: Need) {
        self.value = 0.0;
        if need >= Need::Gradient {
            self.link_grad.iter_mut().for_each(|g| g.fill(0.0));
            self.dof_grad.fill(0.0);
        }
        if need >= Need::Hessian {
            // The blocks themselves are not cleared: the first `add_link_hess` of an
            // evaluation overwrites its block, and every reader checks `link_hess_set`.
            self.link_hess_set.iter_mut().for_each(|set| *set = false);
            if self.link_moment_set {
                self.link_moment.iter_mut().for_each(|m| m.fill(0.0));
                self.link_moment_set = false;
            }
            self.pair_hess.clear();
            self.pair_slots.clear();
            self.dof_hess.clear();
        }
    }

    /// Adds to the diagonal pose Hessian block of link `i`. The first write of an
    /// evaluation stores `0 + h` (the bits a cleared block `+= h` would give, signed zeros
    /// included), so [`EnergyAccumulator::reset`] need not zero the blocks.
    pub fn add_link_hess(&mut self, i: usize, h: &PoseHessian) {
        if self.link_hess_set[i] {
            self.link_hess[i] += h;
        } else {
            self.link_hess[i].zip_apply(h, |e, x| *e = 0.0 + x);
            self.link_hess_set[i] = true;
        }
    }
}

/// The links' world twists along a step direction `dir`
/// ([`Kinematics::twist_direction`]), computed on first use: most line searches have no
/// pair in range, and then no term asks.
pub struct StepTwists<'a> {
    model: &'a Model,
    kin: &'a Kinematics,
    dir: &'a DVector<f64>,
    twists: Option<Vec<Matrix3x4<f64>>>,
}

impl<'a> StepTwists<'a> {
    /// Twists of `dir` from the kinematics `kin` (first order or higher).
    pub fn new(model: &'a Model, kin: &'a Kinematics, dir: &'a DVector<f64>) -> Self {
        StepTwists {
            model,
            kin,
            dir,
            twists: None,
        }
    }

    /// One `[Ω | v]` per link (see [`Kinematics::twist_direction`]).
    pub fn get(&mut self) -> &[Matrix3x4<f64>] {
        let (model, kin, dir) = (self.model, self.kin, self.dir);
        self.twists.get_or_insert_with(|| {
            let mut t = Vec::new();
            kin.twist_direction(model, dir, &mut t);
            t
        })
    }
}

/// What a term of the step objective is, for the step's bookkeeping (the
/// work balance of [`crate::counters::StepWork`]) and for callers that keep
/// or drop terms by role (calibration keeps only [`TermKind::Inertia`]).
/// A term's [`Energy::name`] is for people (errors, timers); its kind is
/// what code matches on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TermKind {
    /// Kinetic term `½ Σ ρ ‖X^{t+1} − 2X^t + X^{t−1}‖² / Δt²`.
    Inertia,
    /// Gravity's potential.
    Gravity,
    /// A controller's energy (the PD term).
    Controller,
    /// A contact barrier (ours or the IPC baseline's).
    Contact,
    /// A friction potential (ours or the IPC baseline's).
    Friction,
    /// Anything else (joint limits, mimic couplings, calibration effects).
    Other,
}

/// One term of the step objective.
pub trait Energy: Send + Sync {
    /// Short name used in errors and stage timers.
    fn name(&self) -> &'static str;

    /// The term's role (see [`TermKind`]); `Other` unless overridden.
    fn kind(&self) -> TermKind {
        TermKind::Other
    }

    /// Called once per time step before the Newton solve (lagged quantities,
    /// warm starts).
    fn begin_step(
        &mut self,
        _ctx: &StepContext,
        _kin_prev: &Kinematics,
    ) -> Result<(), EnergyError> {
        Ok(())
    }

    /// After an accepted step: adds the term's statistics at the accepted
    /// state (its last evaluation) and sub-stage times.
    fn report(
        &mut self,
        _d: &mut crate::counters::StepDiagnostics,
        _timers: &mut crate::counters::StageTimers,
    ) {
    }

    /// Why the last evaluation was infeasible (`+∞`), naming the elements
    /// involved and how to fix it; `None` when this term was finite.
    fn explain_infeasible(&self, _model: &Model) -> Option<String> {
        None
    }

    /// Adjoint product: adds `∂Φ/∂x` for `Φ = Σ_i ⟨δA_i, ∂E/∂A_i⟩ + λᵀ∂E/∂θ`
    /// (see [`vjp`]) at `θ^t = q`, with `begin_step` already run
    /// for this step. Terms that cannot differentiate a quantity name it in
    /// `out.unavailable`; the default supports nothing.
    fn vjp(
        &mut self,
        _ctx: &StepContext,
        _q: &DVector<f64>,
        _kin: &Kinematics,
        _dir: &crate::energy::vjp::AdjointDirection,
        out: &mut crate::energy::vjp::VjpAccumulator,
    ) -> Result<(), EnergyError> {
        out.unavailable.push(self.name());
        Ok(())
    }

    /// Largest fraction `α ∈ (0, 1]` of the Newton step `q → q + dq` along
    /// which this term stays finite (collision-free), for continuous
    /// collision detection (IPC's CCD line-search filter). `kin` holds the
    /// kinematics at `q`; `charts` are the rotation-vector chart centres
    /// needed to evaluate kinematics at other points of the segment. Newton's
    /// line search starts backtracking at the minimum over all terms.
    /// Default `1.0` (no bound: the search then behaves exactly as without
    /// this method).
    fn max_step(
        &mut self,
        _ctx: &StepContext,
        _q: &DVector<f64>,
        _dq: &DVector<f64>,
        _kin: &Kinematics,
        _charts: &[nalgebra::Matrix3<f64>],
    ) -> Result<f64, EnergyError> {
        Ok(1.0)
    }

    /// Whether [`Energy::certify_step`] checks anything (continuous
    /// collision detection on). The simulator then certifies each step's
    /// path (see [`crate::sim::Simulator::step`]). Default false.
    fn certifies(&self) -> bool {
        false
    }

    /// Continuous collision detection of the segment `q → q + α dq` that
    /// the line search accepted: the largest `α' ≤ α` such that the term
    /// stays finite (collision-free) at *every* point of `[q, q + α' dq]`,
    /// not only at its end. `charts` are the rotation-vector chart centres
    /// of the step; `start`, when given, the kinematics at `q` (poses only,
    /// [`KinOrder::Pose`](crate::kinematics::KinOrder), with `charts`: the
    /// step's kinematics at `θ^t` when `q = θ^t`). Adds nothing to the
    /// objective. Default `α` (no check).
    // Arguments kept separate: trait method mirroring `ccd::certify`'s inputs (the step's state at the line-search trial); a term uses a few of them.
    #[allow(clippy::too_many_arguments)]
    fn certify_step(
        &mut self,
        _ctx: &StepContext,
        _q: &DVector<f64>,
        _start: Option<&Kinematics>,
        _dq: &DVector<f64>,
        alpha: f64,
        _charts: &[nalgebra::Matrix3<f64>],
    ) -> Result<f64, EnergyError> {
        Ok(alpha)
    }

    /// The term's barrier pairs along a step, for Newton's line model
    /// ([`crate::sim::line_model`]): one [`crate::contact::PlaneLine`] per pair in range
    /// at the term's last evaluation, along the links' world twists per unit step
    /// ([`StepTwists`]: a point `X` of link `i` moves at `twists[i] [X; 1]`). `kin` holds the
    /// poses of the point the line starts from; a term whose last evaluation was elsewhere
    /// returns `false` (no model for this line search). Terms without pairs are part of the
    /// model's quadratic remainder: the default adds nothing and returns `true`.
    fn line_pairs(
        &mut self,
        _ctx: &StepContext,
        _kin: &Kinematics,
        _twists: &mut StepTwists,
        _out: &mut Vec<crate::contact::PlaneLine>,
    ) -> bool {
        true
    }

    /// Adds the term's value and requested derivatives at `θ^{t+1} = q`
    /// (kinematics `kin` already evaluated at `q`). A value of `+∞` marks an
    /// infeasible configuration; derivatives may then be left unset.
    fn accumulate(
        &mut self,
        ctx: &StepContext,
        q: &DVector<f64>,
        kin: &Kinematics,
        need: Need,
        acc: &mut EnergyAccumulator,
    ) -> Result<(), EnergyError>;
}
