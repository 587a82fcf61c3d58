//! The initial guess of each step's Newton solve ([`Predictor`]): polynomial
//! extrapolation of the last states, `θ^{t+1}_0 = Σ_j c_j θ^{t−j}` with the
//! coefficients of the polynomial of degree `d` through the last `d + 1`
//! states, evaluated one step on: `(2, −1)` (linear), `(3, −3, 1)`
//! (quadratic), `(4, −6, 4, −1)` (cubic). A degree-`d` guess is exact when the
//! coordinates are polynomials of degree `≤ d` in time; its error is
//! `O(Δt^{d+1})` for smooth motion, but after an impact the higher
//! differences are noise, which is why [`Predictor::Adaptive`] keeps the
//! cubic only while it predicted better. Only the Newton solve's start
//! depends on it, never the solution beyond `tol`.

use super::newton::Predictor;
use super::state::SimState;
use nalgebra::DVector;

/// The quadratic extrapolation of one coordinate, `3(θ^t − θ^{t−1}) + θ^{t−2}`
/// (the parabola through the last three values, one step on).
#[inline]
fn quadratic_at(t0: f64, t1: f64, t2: f64) -> f64 {
    (t0 - t1) * 3.0 + t2
}

/// The cubic extrapolation of one coordinate, `4θ^t − 6θ^{t−1} + 4θ^{t−2} −
/// θ^{t−3}` (the cubic through the last four values, one step on).
#[inline]
fn cubic_at(t0: f64, t1: f64, t2: f64, t3: f64) -> f64 {
    4.0 * t0 - 6.0 * t1 + 4.0 * t2 - t3
}

/// The initial guess of the next step's solve ([`Predictor`]):
/// `2θ^t − θ^{t−1}` (constant generalized velocity); with
/// [`Predictor::Quadratic`] and `θ^{t−2}` known, [`quadratic_at`] (constant
/// generalized acceleration); with [`Predictor::Cubic`] and `θ^{t−3}` known
/// as well, [`cubic_at`], else the quadratic guess; with
/// [`Predictor::Adaptive`] the cubic guess when it was the closer one last
/// step ([`cubic_was_closer`]).
pub(super) fn predict_guess(state: &SimState, predictor: Predictor, guess: &mut DVector<f64>) {
    fn known(q: &Option<DVector<f64>>, n: usize) -> Option<&DVector<f64>> {
        q.as_ref().filter(|q| q.len() == n)
    }
    let n = state.q.len();
    let cubic = match predictor {
        Predictor::Cubic => true,
        Predictor::Adaptive => state.cubic_closer,
        _ => false,
    };
    let (q0, q1) = (&state.q, &state.q_prev);
    match (
        predictor,
        known(&state.q_prev2, n),
        known(&state.q_prev3, n),
    ) {
        (_, Some(q2), Some(q3)) if cubic => {
            fill(guess, n, |k| cubic_at(q0[k], q1[k], q2[k], q3[k]));
        }
        (Predictor::Quadratic | Predictor::Cubic | Predictor::Adaptive, Some(q2), _) => {
            fill(guess, n, |k| quadratic_at(q0[k], q1[k], q2[k]));
        }
        _ => {
            guess.clone_from(q0);
            guess.axpy(-1.0, q1, 2.0);
        }
    }
}

/// `guess[k] = f(k)` for `k < n`, reusing the buffer when it has `n` entries.
fn fill(guess: &mut DVector<f64>, n: usize, f: impl Fn(usize) -> f64) {
    if guess.len() != n {
        *guess = DVector::zeros(n);
    }
    for (k, g) in guess.iter_mut().enumerate() {
        *g = f(k);
    }
}

/// Whether the cubic guess of the step just solved (from `θ^t … θ^{t−3}` in
/// `state`) lies closer to its solution `q` than the quadratic guess, in
/// the max norm: `‖q − g_c‖∞ < ‖q − g_q‖∞` ([`cubic_at`], [`quadratic_at`]).
/// `false` while `θ^{t−3}` is not known.
pub(super) fn cubic_was_closer(state: &SimState, q: &DVector<f64>) -> bool {
    let (Some(q2), Some(q3)) = (&state.q_prev2, &state.q_prev3) else {
        return false;
    };
    if q2.len() != q.len() || q3.len() != q.len() {
        return false;
    }
    let (mut err_q, mut err_c) = (0.0f64, 0.0f64);
    for k in 0..q.len() {
        let (t0, t1, t2, t3) = (state.q[k], state.q_prev[k], q2[k], q3[k]);
        err_q = err_q.max((q[k] - quadratic_at(t0, t1, t2)).abs());
        err_c = err_c.max((q[k] - cubic_at(t0, t1, t2, t3)).abs());
    }
    err_c < err_q
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A state whose coordinates are `f(t)` at `t = 3, 2, 1, 0` (the current
    /// and three earlier states); `q_prev3` only when `four` is set.
    fn state_of(f: impl Fn(f64) -> [f64; 2], four: bool) -> SimState {
        let v = |t: f64| DVector::from_row_slice(&f(t));
        SimState {
            step: 3,
            time: 3.0,
            q: v(3.0),
            q_prev: v(2.0),
            q_prev2: Some(v(1.0)),
            q_prev3: four.then(|| v(0.0)),
            cubic_closer: false,
            charts: Vec::new(),
            poses: Vec::new(),
            poses_prev: Vec::new(),
        }
    }

    fn guess(state: &SimState, p: Predictor) -> DVector<f64> {
        let mut g = DVector::zeros(0);
        predict_guess(state, p, &mut g);
        g
    }

    #[test]
    fn each_guess_is_exact_on_polynomials_of_its_degree() {
        let cubic = |t: f64| [0.5 * t * t * t - t * t + 2.0, -0.25 * t * t * t + 3.0 * t];
        let quadratic = |t: f64| [1.5 * t * t - t + 0.25, -t * t + 0.5];
        let linear = |t: f64| [2.0 * t - 1.0, -0.5 * t];
        let at4 = |f: &dyn Fn(f64) -> [f64; 2]| DVector::from_row_slice(&f(4.0));
        let exact = |g: DVector<f64>, want: DVector<f64>, what: &str| {
            assert!((g - &want).amax() < 1e-12, "{what}");
        };
        let s = state_of(cubic, true);
        exact(guess(&s, Predictor::Cubic), at4(&cubic), "cubic on a cubic");
        let s = state_of(quadratic, true);
        exact(
            guess(&s, Predictor::Quadratic),
            at4(&quadratic),
            "quadratic on a quadratic",
        );
        exact(
            guess(&s, Predictor::Cubic),
            at4(&quadratic),
            "cubic on a quadratic",
        );
        let s = state_of(linear, true);
        exact(
            guess(&s, Predictor::Extrapolate),
            at4(&linear),
            "linear on a line",
        );
        // And not beyond: the quadratic guess misses a cubic by 6 a Δt³ = 3.
        let s = state_of(cubic, true);
        let miss = (guess(&s, Predictor::Quadratic) - at4(&cubic)).amax();
        assert!(
            (miss - 3.0).abs() < 1e-12,
            "quadratic on a cubic misses by {miss}"
        );
    }

    #[test]
    fn cubic_falls_back_to_quadratic_without_the_fourth_state() {
        let s = state_of(|t| [t * t, t * t * t], false);
        assert_eq!(guess(&s, Predictor::Cubic), guess(&s, Predictor::Quadratic));
        assert!(!cubic_was_closer(
            &s,
            &DVector::from_row_slice(&[16.0, 64.0])
        ));
    }

    #[test]
    fn adaptive_keeps_the_guess_that_predicted_the_last_step_better() {
        // Smooth cubic motion: the cubic guess is exact, so it is kept.
        let cubic = |t: f64| [0.5 * t * t * t, -t * t * t + t];
        let mut s = state_of(cubic, true);
        let next = DVector::from_row_slice(&cubic(4.0));
        assert!(cubic_was_closer(&s, &next));
        s.cubic_closer = true;
        assert_eq!(guess(&s, Predictor::Adaptive), guess(&s, Predictor::Cubic));
        // A stop: uniform motion θ = 0, 1, 2, 3, then the body stays at 3.
        // Both guesses say 4 (the history has no curvature): a tie, which
        // does not count as closer.
        let s = state_of(|t| if t < 3.0 { [t, 0.0] } else { [3.0, 0.0] }, true);
        let next = DVector::from_row_slice(&[3.0, 0.0]);
        assert!(!cubic_was_closer(&s, &next));
        // A rebound: θ = 0, 1, 2, 1, then 0.
        let s = state_of(
            |t| {
                if t < 2.0 {
                    [t, 0.0]
                } else {
                    [2.0 - (t - 2.0), 0.0]
                }
            },
            true,
        );
        // θ = 0, 1, 2, 1 and the next state 0: quadratic 3(1 − 2) + 1 = −2 (miss 2),
        // cubic 4 − 12 + 4 − 0 = −4 (miss 4).
        assert!(!cubic_was_closer(&s, &DVector::from_row_slice(&[0.0, 0.0])));
        let mut s = s;
        s.cubic_closer = false;
        assert_eq!(
            guess(&s, Predictor::Adaptive),
            guess(&s, Predictor::Quadratic)
        );
    }
}
