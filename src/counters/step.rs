//! What one time step reports: Newton's statistics, energies, momentum,
//! contact and CCD counts, and the work of each term ([`StepWork`]). Written
//! by the simulator and by energy terms' `report` hooks.

use serde::Serialize;

/// Statistics of one solve.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct NewtonReport {
    pub iters: usize,
    pub grad_inf: f64,
    pub backtracks: usize,
    /// Iterations accepted by the gradient-norm merit (value below round-off).
    pub gradient_merit_steps: usize,
    pub value: f64,
    /// The solve stalled above `tol` but within the gradient's round-off
    /// floor (`grad_floor`), and its point was accepted (see [`crate::sim::newton::minimize`]).
    pub at_floor: bool,
    /// Of those, accepted because the Newton step itself was below
    /// [`crate::sim::NewtonOptions::step_floor`] (the gradient was noise above
    /// `grad_floor`).
    pub at_step_floor: bool,
    /// Accepted line-search steps that continuous collision detection cut
    /// short (the search then ran again from the cut).
    pub ccd_cuts: usize,
    /// The gradient's round-off floor at the last iterate,
    /// `64 ε ‖H‖∞ (‖θ‖∞ + L)` (J per unit coordinate; `L` the scene's length
    /// scale from [`crate::sim::newton::Objective::length_scale`]).
    pub grad_floor: f64,
    /// Iterations whose shifted-Cholesky step ([`crate::sim::Indefinite::Shift`]) found
    /// no acceptable point and were repeated with the clamped eigen step.
    pub shift_fallbacks: usize,
    /// Accepted points evaluated gradient first ([`crate::sim::newton`],
    /// "gradient first"): the Hessian was skipped when the point met the
    /// stopping test.
    pub gradient_first: usize,
    /// Of those, points that did not meet it and were evaluated again with
    /// the Hessian (one extra gradient evaluation each).
    pub gradient_first_misses: usize,
}

/// Diagnostics of one completed step.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct StepDiagnostics {
    pub newton: NewtonReport,
    /// `½ Σ ρ ‖(X^{t+1} − X^t)/Δt‖²` (J).
    pub kinetic: f64,
    /// `−Σ ρ g·X^{t+1}` (J).
    pub potential: f64,
    /// `Σ ρ (X^{t+1} − X^t)/Δt` (kg m/s).
    pub momentum: [f64; 3],
    /// Hull pairs with non-zero contact potential at `θ^{t+1}`.
    pub contact_pairs: usize,
    /// Smallest GJK distance among broad-phase candidate pairs at `θ^{t+1}`
    /// (m; `+∞` when no pair is a candidate).
    pub min_distance: f64,
    /// Continuous collision detection of the step's Newton iterations
    /// (zero when off or without contact).
    pub ccd: super::CcdStats,
    /// Work of each non-conservative or contact term over the step, when
    /// [`crate::sim::Simulator::energy_balance`] is on (see [`StepWork`]).
    pub work: Option<StepWork>,
}

/// Work done on the system over one step by the terms other than inertia
/// and gravity (J): `W_e = −Σ_i ⟨∂E_e/∂A_i, A_i^{t+1} − A_i^t⟩ − ∂E_e/∂θ·Δθ`,
/// each term's gradient taken at `θ^{t+1}` (the point where the step's
/// optimality condition holds, so `Σ_e W_e + W_gravity` is the work the
/// implicit scheme's momentum balance sees). Read off Newton's last
/// gradient evaluation (at the accepted `θ^{t+1}`): no extra evaluation,
/// and the trajectory is the same with or without it. With `E = kinetic + gravity
/// potential`, `ΔE = W_controller + W_friction + W_contact + W_other −
/// D_num`, where `D_num ≥ 0` is the integrator's own (numerical)
/// dissipation, first order in Δt; [`crate::output::Summary`] reports it as
/// the residual of the balance.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct StepWork {
    /// PD controller (`pd`): positive when it drives the robot.
    pub controller: f64,
    /// Friction (`friction`, `ipc_friction`): ≤ 0 up to O(Δt²).
    pub friction: f64,
    /// Contact barrier (`contact`, `ipc_contact`): minus its potential's change.
    pub contact: f64,
    /// Every other term (calibration effects such as damping).
    pub other: f64,
}
