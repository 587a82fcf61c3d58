//! Update rules.

use super::task::{DesignNorm, RadiusRule};
use nalgebra::DVector;

/// The paper's trust-region projected-gradient step for one block:
/// `argmin_Δ gᵀΔ  s.t. ‖Δ‖ ≤ r, lo ≤ x + Δ ≤ hi`.
///
/// KKT: `Δ(ν) = clamp(−g/ν, lo − x, hi − x)` for a multiplier `ν > 0`;
/// `‖Δ(ν)‖` is non-increasing in `ν`, so either the box alone binds
/// (`ν → 0`, the box corner of the descent orthant, if within the ball) or
/// `ν` solves `‖Δ(ν)‖ = r`, found by bisection on `log ν`. Exact up to the
/// bisection tolerance; no external solver.
pub fn trust_region_step(
    g: &DVector<f64>,
    x: &DVector<f64>,
    lo: &DVector<f64>,
    hi: &DVector<f64>,
    r: f64,
) -> DVector<f64> {
    let n = g.len();
    let delta = |nu: f64| -> DVector<f64> {
        DVector::from_fn(n, |i, _| {
            let d = if g[i] == 0.0 { 0.0 } else { -g[i] / nu };
            d.clamp(lo[i] - x[i], hi[i] - x[i])
        })
    };
    if g.norm() == 0.0 || r <= 0.0 {
        return DVector::zeros(n);
    }
    let corner = delta(1e-300);
    if corner.norm() <= r {
        return corner;
    }
    // ‖Δ(ν)‖ = r: bracket in log ν.
    let (mut a, mut b) = ((g.norm() / r).ln() - 60.0, (g.norm() / r).ln() + 1.0);
    while delta(b.exp()).norm() > r {
        b += 5.0;
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if delta(m.exp()).norm() > r {
            a = m;
        } else {
            b = m;
        }
        if b - a < 1e-13 {
            break;
        }
    }
    delta(b.exp())
}

/// The design step of the trust region in the max-norm:
/// `argmin_Δ gᵀΔ  s.t. max_i |Δ_i| ≤ r, lo ≤ x + Δ ≤ hi`, separable:
/// `Δ_i = clamp(−r sign(g_i), lo_i − x_i, hi_i − x_i)` (0 where `g_i = 0`).
pub fn trust_region_step_max(
    g: &DVector<f64>,
    x: &DVector<f64>,
    lo: &DVector<f64>,
    hi: &DVector<f64>,
    r: f64,
) -> DVector<f64> {
    DVector::from_fn(g.len(), |i, _| {
        let d = if g[i] > 0.0 {
            -r
        } else if g[i] < 0.0 {
            r
        } else {
            0.0
        };
        d.clamp(lo[i] - x[i], hi[i] - x[i])
    })
}

/// Which blocks the next trust-region trial moves ([`RadiusRule::Split`];
/// always `Joint` under the other rules).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// Both blocks.
    #[default]
    Joint,
    /// The design alone.
    Design,
    /// The controller alone.
    Controller,
}

/// Trust-region radii of the two blocks after the trials so far, and the
/// phase of the next trial. Stored in checkpoints.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Radii {
    /// Design radius `r_d` (m).
    pub design: f64,
    /// Controller radius `r_c` (controller parameter units).
    pub controller: f64,
    /// Blocks the next trial moves.
    pub phase: Phase,
}

/// Task steps `(ᾱ_d, ᾱ_c)` and the radius rule: what [`Radii::after`] needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusSettings {
    pub rule: RadiusRule,
    pub step_design: f64,
    pub step_controller: f64,
}

impl Radii {
    /// The start: `(ᾱ_d, ᾱ_c)`, joint.
    pub fn new(s: &RadiusSettings) -> Self {
        Radii {
            design: s.step_design,
            controller: s.step_controller,
            phase: Phase::Joint,
        }
    }

    /// The trial steps at iterate `(d, c)` with gradients `(g_d, g_c)` and
    /// design box `[lo, hi]`: `Δd = TR(g_d, r_d)` in the design norm `norm`
    /// ([`trust_region_step`], [`trust_region_step_max`]; zero in the
    /// controller phase) and `Δc = −r_c g_c/‖g_c‖` (zero in the design phase
    /// or if `g_c = 0`).
    pub fn trial(
        &self,
        (g_d, g_c): (&DVector<f64>, &DVector<f64>),
        (d, lo, hi): (&DVector<f64>, &DVector<f64>, &DVector<f64>),
        norm: DesignNorm,
    ) -> (DVector<f64>, DVector<f64>) {
        let dd = match (self.phase, norm) {
            (Phase::Controller, _) => DVector::zeros(d.len()),
            (_, DesignNorm::Euclidean) => trust_region_step(g_d, d, lo, hi, self.design),
            (_, DesignNorm::Max) => trust_region_step_max(g_d, d, lo, hi, self.design),
        };
        let n = g_c.norm();
        let dc = if n > 0.0 && self.phase != Phase::Design {
            -self.controller * g_c / n
        } else {
            DVector::zeros(g_c.len())
        };
        (dd, dc)
    }

    /// The radii and phase after a trial that moved the design (`moved.0`:
    /// the projected trial design differs from the iterate's) and/or the
    /// controller (`moved.1`) and was `accepted` or not (rules on
    /// [`RadiusRule`]'s variants).
    pub fn after(self, s: &RadiusSettings, moved: (bool, bool), accepted: bool) -> Radii {
        let reset_like = |r: Radii| Radii {
            design: s.rule.next(r.design, s.step_design, accepted),
            controller: s.rule.next(r.controller, s.step_controller, accepted),
            phase: Phase::Joint,
        };
        if s.rule != RadiusRule::Split {
            return reset_like(self);
        }
        match (self.phase, accepted) {
            (Phase::Joint, false) if moved.0 && moved.1 => Radii {
                phase: Phase::Design,
                ..self
            },
            (Phase::Joint, _) => reset_like(self),
            (Phase::Design, ok) => Radii {
                design: if ok { s.step_design } else { 0.5 * self.design },
                phase: Phase::Controller,
                ..self
            },
            (Phase::Controller, _) if !moved.1 => Radii {
                phase: Phase::Joint,
                ..self
            },
            (Phase::Controller, true) => Radii {
                controller: s.step_controller,
                phase: Phase::Joint,
                ..self
            },
            (Phase::Controller, false) => Radii {
                controller: 0.5 * self.controller,
                ..self
            },
        }
    }
}

/// Whether a trust-region trial that left the iterate bitwise unchanged
/// (`no_op`: the projected trial design and controller equal the iterate's,
/// the step rounding away or the gradient being zero), tried in `phase`,
/// means that no later trial can move either: the run has converged at
/// the current iterate.
///
/// Such a trial has the iterate's loss, so it is rejected (acceptance needs
/// a strictly lower loss), and a rejection never grows a radius; a step
/// that rounds away at radius `r` rounds away at `r/2` (coordinate by
/// coordinate `|r u_i| < ½ ulp(x_i)` holds for the smaller radius too, and
/// the projection onto the box keeps an unchanged coordinate unchanged).
/// In the *joint* phase (every rule but `split` is always joint) both
/// blocks were tried at their radii, so every later trial, joint or single
/// block, is a no-op. In `split`'s *controller* phase a rejection keeps the
/// phase, so every later trial is the same controller no-op. Only a no-op
/// in the *design* phase is not final: the controller phase comes next
/// with its own radius.
pub fn no_op_is_final(no_op: bool, phase: Phase) -> bool {
    no_op && phase != Phase::Design
}

/// `g` rescaled to Euclidean norm at most `max`: `g · min(1, max/‖g‖)`
/// (`g` itself when `max` is `None`).
pub fn clip_norm(g: &DVector<f64>, max: Option<f64>) -> std::borrow::Cow<'_, DVector<f64>> {
    let norm = g.norm();
    match max {
        Some(m) if norm > m => std::borrow::Cow::Owned(g * (m / norm)),
        _ => std::borrow::Cow::Borrowed(g),
    }
}

/// The sum of `parts`, each rescaled to norm at most `max`:
/// `Σ_j p_j · min(1, max/‖p_j‖)`, summed in order (`sum` itself when `max`
/// is `None` or there are no parts; `sum` is `Σ_j p_j`).
pub fn clip_parts<'a>(
    sum: &'a DVector<f64>,
    parts: &[DVector<f64>],
    max: Option<f64>,
) -> std::borrow::Cow<'a, DVector<f64>> {
    match max {
        Some(_) if !parts.is_empty() => {
            let mut out = DVector::zeros(sum.len());
            for p in parts {
                out += clip_norm(p, max).as_ref();
            }
            std::borrow::Cow::Owned(out)
        }
        _ => std::borrow::Cow::Borrowed(sum),
    }
}

/// Adam state for one block.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adam {
    pub lr: f64,
    pub beta1: f64,
    pub beta2: f64,
    pub eps: f64,
    m: DVector<f64>,
    v: DVector<f64>,
    t: i32,
}

impl Adam {
    /// Standard settings: β₁ = 0.9, β₂ = 0.999, ε = 1e-8.
    pub fn new(n: usize, lr: f64) -> Self {
        Adam {
            lr,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            m: DVector::zeros(n),
            v: DVector::zeros(n),
            t: 0,
        }
    }

    /// The step `Δ` for gradient `g`.
    pub fn step(&mut self, g: &DVector<f64>) -> DVector<f64> {
        self.step_scaled(g, 1.0)
    }

    /// The step `Δ` for gradient `g` at the learning rate `scale · lr`
    /// (the moments are updated as by [`Adam::step`]).
    pub fn step_scaled(&mut self, g: &DVector<f64>, scale: f64) -> DVector<f64> {
        let lr = scale * self.lr;
        self.t += 1;
        self.m = self.beta1 * &self.m + (1.0 - self.beta1) * g;
        self.v = self.beta2 * &self.v + (1.0 - self.beta2) * g.component_mul(g);
        let mh = &self.m / (1.0 - self.beta1.powi(self.t));
        let vh = &self.v / (1.0 - self.beta2.powi(self.t));
        DVector::from_fn(g.len(), |i, _| -lr * mh[i] / (vh[i].sqrt() + self.eps))
    }
}

/// The cosine decay of `optimizer.step_decay`: the factor on the learning
/// rate at iteration `it` (1-based) of `iters`,
/// `f + (1 − f)(1 + cos(π (it − 1)/(iters − 1)))/2` — 1 at the first
/// iteration, `f` at the last (1 throughout for `None` or a one-iteration
/// run).
pub fn decay_factor(final_fraction: Option<f64>, it: usize, iters: usize) -> f64 {
    match final_fraction {
        Some(f) if iters > 1 => {
            let t = (it.clamp(1, iters) - 1) as f64 / (iters - 1) as f64;
            f + (1.0 - f) * 0.5 * (1.0 + (std::f64::consts::PI * t).cos())
        }
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_no_op_trial_is_final_except_in_the_design_phase() {
        for phase in [Phase::Joint, Phase::Controller] {
            assert!(no_op_is_final(true, phase));
            assert!(!no_op_is_final(false, phase));
        }
        assert!(!no_op_is_final(true, Phase::Design));
        // A no-op stays a no-op at half the radius: the step of a tiny
        // radius rounds away at 1.0 and so does half of it.
        let (x, u) = (1.0_f64, 0.6_f64);
        let r = 1e-17;
        assert_eq!(x + r * u, x);
        assert_eq!(x + 0.5 * r * u, x);
    }

    /// Clipping bounds the norm and keeps the direction; with it, one
    /// gradient spike 1e6 times the others no longer shrinks Adam's later
    /// steps (without it, 70 iterations on they are below 1 % of the
    /// learning rate: the spike still dominates the second moment).
    #[test]
    fn clipping_keeps_adam_moving_after_a_gradient_spike() {
        let g = DVector::from_vec(vec![3e-4, -4e-4]);
        assert_eq!(clip_norm(&g, None).as_ref(), &g);
        assert_eq!(clip_norm(&g, Some(1.0)).as_ref(), &g);
        let spike = &g * 1e6;
        let c = clip_norm(&spike, Some(1e-3));
        assert!((c.norm() - 1e-3).abs() < 1e-15);
        assert!((c.as_ref() / c.norm() - &g / g.norm()).norm() < 1e-15);
        let run = |clip: Option<f64>| {
            let mut adam = Adam::new(2, 1e-2);
            let mut last = 0.0;
            for k in 0..80 {
                let gk = if k == 10 { &g * 1e6 } else { g.clone() };
                last = adam.step(&clip_norm(&gk, clip)).norm();
            }
            last
        };
        let free = run(None);
        let clipped = run(Some(1e-3));
        eprintln!("last step: unclipped {free:e}, clipped {clipped:e} (lr 1e-2)");
        assert!(free < 1e-2 * 1e-2, "unclipped step {free}");
        assert!(clipped > 0.2 * 1e-2, "clipped step {clipped}");
    }

    /// `step_decay`'s factor: 1 at the first iteration, the fraction at the
    /// last, non-increasing in between, 1 throughout without a fraction or
    /// for a one-iteration run; and with it, Adam on a noisy bowl
    /// (`g = 2x + 0.5 sin(2.39996 k)`, lr 0.05, 500 iterations from x = 1)
    /// ends near the bottom, where the constant rate keeps moving at the
    /// step's scale (rule, set before the run: the decayed run's mean |x|
    /// over its last 50 iterates at most a fifth of the constant run's).
    #[test]
    fn cosine_decay_lets_adam_settle_where_a_constant_rate_keeps_moving() {
        assert_eq!(decay_factor(Some(0.01), 1, 500), 1.0);
        assert!((decay_factor(Some(0.01), 500, 500) - 0.01).abs() < 1e-15);
        assert!((decay_factor(Some(0.2), 3, 5) - 0.6).abs() < 1e-15);
        assert_eq!(decay_factor(None, 250, 500), 1.0);
        assert_eq!(decay_factor(Some(0.01), 1, 1), 1.0);
        let f: Vec<f64> = (1..=500)
            .map(|k| decay_factor(Some(0.01), k, 500))
            .collect();
        assert!(f.windows(2).all(|w| w[1] <= w[0]));
        let run = |decay: Option<f64>| {
            let mut adam = Adam::new(1, 0.05);
            let mut x = DVector::from_vec(vec![1.0]);
            let mut tail = 0.0;
            for k in 1..=500usize {
                let g = x.map(|v| 2.0 * v + 0.5 * (2.39996 * k as f64).sin());
                x += adam.step_scaled(&g, decay_factor(decay, k, 500));
                if k > 450 {
                    tail += x[0].abs() / 50.0;
                }
            }
            tail
        };
        let (constant, decayed) = (run(None), run(Some(0.01)));
        eprintln!("mean |x| over the last 50: constant {constant:e}, decayed {decayed:e}");
        assert!(decayed <= 0.2 * constant, "{decayed} vs {constant}");
    }

    /// Per-part clipping: without a bound (or parts) the sum itself; with
    /// one, the sum of the parts each clipped (a 1e6 spike in one part no
    /// longer hides the other's direction).
    #[test]
    fn clip_parts_clips_each_part_before_the_sum() {
        let a = DVector::from_vec(vec![3e-4, 0.0]);
        let b = DVector::from_vec(vec![0.0, 4e2]);
        let sum = &a + &b;
        assert_eq!(
            clip_parts(&sum, &[a.clone(), b.clone()], None).as_ref(),
            &sum
        );
        assert_eq!(clip_parts(&sum, &[], Some(1e-3)).as_ref(), &sum);
        let c = clip_parts(&sum, &[a.clone(), b.clone()], Some(1e-3));
        assert_eq!(c[0], 3e-4);
        assert!((c[1] - 1e-3).abs() < 1e-18);
        // The plain sum clipped to the same norm keeps 7.5e-10 of `a`.
        let s = clip_norm(&sum, Some(1e-3));
        assert!(s[0] < 1e-9);
        // Non-binding: bitwise the sum of the parts.
        let n = clip_parts(&sum, &[a, b], Some(1e300));
        assert_eq!(n.as_ref(), &sum);
    }

    /// The two radius rules on a rippled bowl `f(x) = ‖x‖² + a Σ cos(xᵢ/λ)`
    /// (a = 0.1, λ = 0.01; exact gradient), from (3, 2) with step 0.3, 200
    /// trials of the trust-region iteration (accept iff f decreases): the
    /// adaptive radius shrinks to the ripple's scale and collapses in a
    /// ripple's local minimum well up the bowl (measured f ≈ 1.89, radius
    /// < 1e-40); resetting the radius to the step after every accepted
    /// trial crosses the ripples along the trend and ends near the bottom
    /// (f ≈ −0.12; the lowest value is −0.2). The spider's controller-only
    /// run stalled the first way (notes/locomotion-feet-and-radius.md).
    #[test]
    fn reset_radius_crosses_a_ripple_where_the_adaptive_radius_collapses() {
        let (a, lam) = (0.1, 0.01);
        let f = |x: &DVector<f64>| x.iter().map(|v| v * v + a * (v / lam).cos()).sum::<f64>();
        let grad = |x: &DVector<f64>| x.map(|v| 2.0 * v - a / lam * (v / lam).sin());
        let run = |rule: RadiusRule| {
            let (lo, hi) = (DVector::repeat(2, -1e9), DVector::repeat(2, 1e9));
            let mut x = DVector::from_vec(vec![3.0, 2.0]);
            let mut r = 0.3;
            for _ in 0..200 {
                let t = &x + trust_region_step(&grad(&x), &x, &lo, &hi, r);
                let ok = f(&t) < f(&x);
                if ok {
                    x = t;
                }
                r = rule.next(r, 0.3, ok);
            }
            (f(&x), r)
        };
        let (fa, ra) = run(RadiusRule::Adaptive);
        let (fr, _) = run(RadiusRule::Reset);
        eprintln!("adaptive: f {fa} radius {ra:e}; reset: f {fr}");
        assert!(fa > 1.5 && ra < 1e-30, "adaptive f {fa} r {ra}");
        assert!(fr < 0.0, "reset f {fr}");
    }

    /// `n` trust-region trials (accept iff the loss decreases) of `rule` on
    /// `f(d, c)` with gradient `grad`, from `(d, c)`, steps `(ᾱ_d, ᾱ_c)`, no
    /// box: the final iterate, the radii after every trial and the number
    /// of accepted trials.
    #[allow(clippy::type_complexity)]
    fn trials(
        rule: RadiusRule,
        (step_design, step_controller): (f64, f64),
        f: &dyn Fn(&DVector<f64>, &DVector<f64>) -> f64,
        grad: &dyn Fn(&DVector<f64>, &DVector<f64>) -> (DVector<f64>, DVector<f64>),
        (mut d, mut c): (DVector<f64>, DVector<f64>),
        n: usize,
    ) -> (DVector<f64>, DVector<f64>, Vec<Radii>, usize) {
        let s = RadiusSettings {
            rule,
            step_design,
            step_controller,
        };
        let (lo, hi) = (
            DVector::repeat(d.len(), -1e9),
            DVector::repeat(d.len(), 1e9),
        );
        let mut r = Radii::new(&s);
        let (mut log, mut accepted) = (Vec::new(), 0);
        for _ in 0..n {
            let (gd, gc) = grad(&d, &c);
            let (dd, dc) = r.trial((&gd, &gc), (&d, &lo, &hi), DesignNorm::Euclidean);
            let (td, tc) = (&d + &dd, &c + &dc);
            let ok = f(&td, &tc) < f(&d, &c);
            r = r.after(&s, (td != d, tc != c), ok);
            if ok {
                (d, c) = (td, tc);
                accepted += 1;
            }
            log.push(r);
        }
        (d, c, log, accepted)
    }

    /// A stiff design block `D(d) = 10³ d²` from `d = 10⁻³` with the step
    /// ᾱ_d = 1 (every design step above ~2·10⁻³ raises the loss by far more
    /// than any controller step lowers it) next to a controller bowl
    /// `‖c‖²` from (3, 2) with ᾱ_c = 0.5; 200 trials. Under `reset` every
    /// rejection halves both radii, so each accepted trial comes at
    /// `r_c ≈ ᾱ_c/256` and the controller barely moves (measured ‖c‖ ≈ 3.5);
    /// under `split` the controller backtracks on its own scale and reaches
    /// the bottom (measured ‖c‖ ≈ 3e-8; asserted < 0.05). The design itself
    /// gains nothing under either rule here (measured d: 1e-3 → 1e-3 under
    /// `split`, → 4.9e-3 under `reset`, whose controller decrease pays for
    /// design steps that raise `D`); asserted: `D` does not rise under
    /// `split`, and its joint trials are accepted (radius back at ᾱ_d).
    #[test]
    fn split_radius_keeps_the_controller_moving_where_a_stiff_design_throttles_reset() {
        let f = |d: &DVector<f64>, c: &DVector<f64>| 1e3 * d.norm_squared() + c.norm_squared();
        let grad = |d: &DVector<f64>, c: &DVector<f64>| (2e3 * d, 2.0 * c);
        let start = (
            DVector::from_element(1, 1e-3),
            DVector::from_vec(vec![3.0, 2.0]),
        );
        let run = |rule| trials(rule, (1.0, 0.5), &f, &grad, start.clone(), 200);
        let (dr, cr, _, nr) = run(RadiusRule::Reset);
        let (ds, cs, log, ns) = run(RadiusRule::Split);
        eprintln!(
            "reset: |c| {} d {} ({nr} accepted); split: |c| {} d {} ({ns} accepted)",
            cr.norm(),
            dr[0],
            cs.norm(),
            ds[0]
        );
        assert!(cr.norm() > 3.0, "reset |c| {}", cr.norm());
        assert!(cs.norm() < 0.05, "split |c| {}", cs.norm());
        assert!(f(&ds, &cs) < 0.01 * f(&dr, &cr));
        assert!(
            1e3 * ds[0] * ds[0] <= 1e-3,
            "split D {}",
            1e3 * ds[0] * ds[0]
        );
        // Both single-block phases ran.
        assert!(log.iter().any(|r| r.phase == Phase::Design));
        assert!(log.iter().any(|r| r.phase == Phase::Controller));
    }

    /// With a design block that cannot move (no design variables, as
    /// `--design off`, or a zero design gradient) `split` is `reset`, trial
    /// for trial and bitwise (the rippled bowl of the test above).
    #[test]
    fn split_radius_is_reset_when_the_design_does_not_move() {
        let (a, lam) = (0.1, 0.01);
        let ripple = |x: &DVector<f64>| x.iter().map(|v| v * v + a * (v / lam).cos()).sum::<f64>();
        let f = |_: &DVector<f64>, c: &DVector<f64>| ripple(c);
        let gc = |c: &DVector<f64>| c.map(|v| 2.0 * v - a / lam * (v / lam).sin());
        let grad = |d: &DVector<f64>, c: &DVector<f64>| (d.map(|_| 0.0), gc(c));
        for nd in [0, 3] {
            let start = (
                DVector::from_element(nd, 0.2),
                DVector::from_vec(vec![3.0, 2.0]),
            );
            let run = |rule| trials(rule, (0.05, 0.3), &f, &grad, start.clone(), 200);
            let (_, cr, lr, nr) = run(RadiusRule::Reset);
            let (_, cs, ls, ns) = run(RadiusRule::Split);
            assert_eq!((cr, nr), (cs, ns));
            assert_eq!(lr, ls);
            assert!(nr > 20, "{nr} accepted");
        }
    }

    #[test]
    fn trust_region_step_is_optimal_on_ball_and_box() {
        // Ball binding: step is −r g/‖g‖ when the box is far.
        let g = DVector::from_vec(vec![3.0, -4.0]);
        let x = DVector::zeros(2);
        let big = DVector::from_vec(vec![10.0, 10.0]);
        let d = trust_region_step(&g, &x, &(-&big), &big, 0.5);
        assert!((d - DVector::from_vec(vec![-0.3, 0.4])).norm() < 1e-9);
        // Box binding on one coordinate: the rest of the radius goes to the other.
        let lo = DVector::from_vec(vec![-0.1, -10.0]);
        let d = trust_region_step(&g, &x, &lo, &big, 0.5);
        assert!((d[0] + 0.1).abs() < 1e-9);
        assert!((d.norm() - 0.5).abs() < 1e-9 && d[1] > 0.0);
        // Brute force: no feasible point on a fine grid does better.
        let best = (0..=400)
            .flat_map(|i| {
                (0..=400).map(move |j| (-0.1 + 0.2 * i as f64 / 400.0, -0.5 + j as f64 / 400.0))
            })
            .filter(|(a, b)| a * a + b * b <= 0.25)
            .map(|(a, b)| 3.0 * a - 4.0 * b)
            .fold(f64::INFINITY, f64::min);
        assert!(g.dot(&d) <= best + 1e-9);
        // Box corner inside the ball.
        let small = DVector::from_vec(vec![0.01, 0.01]);
        let d = trust_region_step(&g, &x, &(-&small), &small, 0.5);
        assert!((d - DVector::from_vec(vec![-0.01, 0.01])).norm() < 1e-12);
    }

    /// The max-norm step minimises `gᵀΔ` over `max|Δ_i| ≤ r` within the
    /// bounds (checked against a grid of the feasible square), moves every
    /// coordinate with a non-zero gradient by `r` where the bounds allow,
    /// and leaves a zero-gradient coordinate alone.
    #[test]
    fn max_norm_step_is_optimal_on_its_box() {
        let g = DVector::from_vec(vec![3.0, -4.0, 0.0]);
        let x = DVector::from_vec(vec![0.0, 0.0, 0.0]);
        let lo = DVector::from_vec(vec![-1.0, -1.0, -1.0]);
        let hi = DVector::from_vec(vec![1.0, 0.2, 1.0]);
        let d = trust_region_step_max(&g, &x, &lo, &hi, 0.5);
        assert_eq!(d, DVector::from_vec(vec![-0.5, 0.2, 0.0]));
        let best = (0..=200)
            .flat_map(|i| {
                (0..=200).map(move |j| (-0.5 + i as f64 / 200.0, -0.5 + j as f64 / 200.0))
            })
            .filter(|(_, b)| *b <= 0.2)
            .map(|(a, b)| 3.0 * a - 4.0 * b)
            .fold(f64::INFINITY, f64::min);
        assert!(g.dot(&d) <= best + 1e-12);
        // Against the Euclidean step of the same radius: n = 100 equal
        // components move by r each, not r/√n.
        let g = DVector::repeat(100, 1.0);
        let (x, big) = (DVector::zeros(100), DVector::repeat(100, 1e3));
        let dm = trust_region_step_max(&g, &x, &(-&big), &big, 4e-3);
        let de = trust_region_step(&g, &x, &(-&big), &big, 4e-3);
        assert!((dm.amax() - 4e-3).abs() < 1e-15);
        assert!((de.amax() - 4e-4).abs() < 1e-12);
    }
}
