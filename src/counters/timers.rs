//! Stage timers of the time step (fed into the summary JSON and reports),
//! indexed by the typed [`Stage`] (as MuJoCo's `mjtTimer`) and, inside
//! [`Stage::Terms`], by energy term. The timed stages partition the step's
//! wall time: no time is counted twice. A term's own sub-stage (the contact
//! term's broad phase) is carved out of the term's time by the term itself
//! in its `report` hook ([`StageTimers::carve`]).
//!
//! The evaluations inside the Newton solve (kinematics, each energy term,
//! assembly), the terms' own sub-stages (the contact term's broad phase and
//! collision detection) and the line search (its remainder after the
//! evaluations and collision detection) are timed only when the timers are
//! *detailed*
//! ([`StageTimers::set_detailed`]; off by default): that costs 3 + (number
//! of terms) clock readings per evaluation, measured at 7 % of the
//! calibration suite's CPU time on a small robot (2026-11-29, a VM whose
//! clock reading takes ≈ 50 ns). `sdrs simulate`, `sdrs bench` and the
//! chain benchmark turn it on; without it those stages are absent from the
//! report and the other stages are timed as before.

use serde::Serialize;
use std::time::{Duration, Instant};

/// A stage of the time step. The tree ([`Stage::parent`]):
///
/// ```text
/// Step ─┬─ BeginStep
///       ├─ Newton ─┬─ Kinematics
///       │          ├─ Terms ── (one timer per energy term) ── BroadPhase
///       │          ├─ Assembly
///       │          ├─ LinearSolve
///       │          └─ LineSearch ── Ccd
///       └─ Accept
/// ```
///
/// `Step`, `Newton` and `Terms` are groups (their time is their children's);
/// the others are timed. Declaration order is the order of the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Stage {
    /// The whole step (group).
    Step,
    /// Targets, lagged data and warm starts of the step (`begin_step` hooks).
    BeginStep,
    /// The Newton solve (group).
    Newton,
    /// Forward kinematics and its derivatives at each evaluation.
    Kinematics,
    /// The energy terms' evaluations (group; one timer per term).
    Terms,
    /// Broad phase of contact candidates (inside the contact term's evaluations).
    BroadPhase,
    /// Pose-space to joint-space assembly of gradient and Hessian (with the
    /// accumulator's reset).
    Assembly,
    /// The Newton direction (factorization and solve).
    LinearSolve,
    /// The line search, less the evaluations it runs (timed in their stages).
    LineSearch,
    /// Continuous collision detection of line-search segments.
    Ccd,
    /// Accepting `θ^{t+1}`: diagnostics, the terms' reports, state update.
    Accept,
}

impl Stage {
    /// Every stage, in report order.
    pub const ALL: [Stage; 11] = [
        Stage::Step,
        Stage::BeginStep,
        Stage::Newton,
        Stage::Kinematics,
        Stage::Terms,
        Stage::BroadPhase,
        Stage::Assembly,
        Stage::LinearSolve,
        Stage::LineSearch,
        Stage::Ccd,
        Stage::Accept,
    ];

    /// The name in reports and the summary JSON.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Step => "step",
            Stage::BeginStep => "begin_step",
            Stage::Newton => "newton",
            Stage::Kinematics => "kinematics",
            Stage::Terms => "terms",
            Stage::BroadPhase => "broad_phase",
            Stage::Assembly => "assembly",
            Stage::LinearSolve => "linear_solve",
            Stage::LineSearch => "line_search",
            Stage::Ccd => "ccd",
            Stage::Accept => "accept",
        }
    }

    /// The enclosing stage (`None` for [`Stage::Step`]).
    pub fn parent(self) -> Option<Stage> {
        match self {
            Stage::Step => None,
            Stage::BeginStep | Stage::Newton | Stage::Accept => Some(Stage::Step),
            Stage::Kinematics
            | Stage::Terms
            | Stage::Assembly
            | Stage::LinearSolve
            | Stage::LineSearch => Some(Stage::Newton),
            Stage::BroadPhase => Some(Stage::Terms),
            Stage::Ccd => Some(Stage::LineSearch),
        }
    }

    /// Groups are not timed themselves: their time is their children's.
    pub fn is_group(self) -> bool {
        matches!(self, Stage::Step | Stage::Newton | Stage::Terms)
    }
}

/// Accumulated time and calls of one timer.
#[derive(Clone, Copy, Debug, Default)]
struct Tally {
    time: Duration,
    calls: u64,
}

impl Tally {
    fn add(&mut self, d: Duration) {
        self.time += d;
        self.calls += 1;
    }
}

/// Accumulated wall time per [`Stage`] and per energy term.
#[derive(Clone, Debug, Default)]
pub struct StageTimers {
    stages: [Tally; Stage::ALL.len()],
    /// Per energy term, by its index in the simulator's term list.
    terms: Vec<(&'static str, Tally)>,
    /// The term whose `report` hook runs (see [`StageTimers::carve`]).
    reporting: Option<usize>,
    /// Whether evaluations are timed by stage and term (default `false`).
    detailed: bool,
}

/// One row of the stage breakdown (a timed stage or an energy term).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StageTime {
    pub stage: &'static str,
    pub seconds: f64,
    pub calls: u64,
}

impl StageTimers {
    /// Adds `d` to the timed stage `stage` (a group stage is a caller bug).
    pub fn add(&mut self, stage: Stage, d: Duration) {
        debug_assert!(!stage.is_group(), "{stage:?} is a group stage");
        self.stages[stage as usize].add(d);
    }

    /// Times each evaluation by stage and energy term (`true`), or not at
    /// all (`false`, the default: see the module documentation).
    pub fn set_detailed(&mut self, on: bool) {
        self.detailed = on;
    }

    /// Whether evaluations are timed by stage and term.
    pub fn detailed(&self) -> bool {
        self.detailed
    }

    /// Starts an evaluation's laps: the clock now when detailed, else `None`
    /// (no clock reading).
    pub fn start_laps(&self) -> Option<Instant> {
        self.detailed.then(Instant::now)
    }

    /// Ends a lap of an evaluation in `stage` and starts the next one (one
    /// clock reading; nothing when `mark` is `None`).
    pub fn lap(&mut self, mark: &mut Option<Instant>, stage: Stage) {
        if let Some(m) = mark {
            let now = Instant::now();
            self.add(stage, now - *m);
            *m = now;
        }
    }

    /// As [`StageTimers::lap`], into energy term number `index` (named `name`).
    pub fn lap_term(&mut self, mark: &mut Option<Instant>, index: usize, name: &'static str) {
        if let Some(m) = mark {
            let now = Instant::now();
            self.add_term(index, name, now - *m);
            *m = now;
        }
    }

    /// Runs `f`, timing it into `stage`.
    pub fn time<T>(&mut self, stage: Stage, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.add(stage, t0.elapsed());
        out
    }

    /// Adds `d` to energy term number `index` (named `name`) of [`Stage::Terms`].
    pub fn add_term(&mut self, index: usize, name: &'static str, d: Duration) {
        if self.terms.len() <= index {
            self.terms.resize(index + 1, ("", Tally::default()));
        }
        let t = &mut self.terms[index];
        t.0 = name;
        t.1.add(d);
    }

    /// Marks term `index` as the one whose `report` hook runs (`None` after it).
    pub fn set_reporting(&mut self, index: Option<usize>) {
        self.reporting = index;
    }

    /// Moves `d`, spent in `stage` inside the reporting term's evaluations,
    /// out of that term's time and into `stage`, so the timers stay a
    /// partition of the step (called from an `Energy::report` hook).
    pub fn carve(&mut self, stage: Stage, d: Duration) {
        if let Some(t) = self.reporting.and_then(|i| self.terms.get_mut(i)) {
            t.1.time = t.1.time.saturating_sub(d);
        }
        self.add(stage, d);
    }

    /// The breakdown in report order (energy terms in place of
    /// [`Stage::Terms`], in the simulator's term order); stages that never
    /// ran are left out.
    pub fn report(&self) -> Vec<StageTime> {
        let row = |stage: &'static str, t: &Tally| StageTime {
            stage,
            seconds: t.time.as_secs_f64(),
            calls: t.calls,
        };
        let mut out = Vec::new();
        for s in Stage::ALL {
            if s == Stage::Terms {
                let ran = self.terms.iter().filter(|t| t.1.calls > 0);
                out.extend(ran.map(|(name, t)| row(name, t)));
            } else if !s.is_group() && self.stages[s as usize].calls > 0 {
                out.push(row(s.name(), &self.stages[s as usize]));
            }
        }
        out
    }

    /// Zeroes every timer (the detail setting is kept).
    pub fn clear(&mut self) {
        *self = Self {
            detailed: self.detailed,
            ..Self::default()
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_form_one_tree_rooted_at_step() {
        for s in Stage::ALL {
            let mut depth = 0;
            let mut p = s;
            while let Some(up) = p.parent() {
                p = up;
                depth += 1;
                assert!(depth < Stage::ALL.len());
            }
            assert_eq!(p, Stage::Step);
            // Groups have children; every timed stage is reported under its name.
            assert!(!s.is_group() || Stage::ALL.iter().any(|c| c.parent() == Some(s)));
        }
    }

    #[test]
    fn laps_read_the_clock_only_when_detailed() {
        let mut t = StageTimers::default();
        assert!(!t.detailed());
        let mut mark = t.start_laps();
        assert!(mark.is_none());
        t.lap(&mut mark, Stage::Kinematics);
        t.lap_term(&mut mark, 0, "inertia");
        assert!(t.report().is_empty());
        t.set_detailed(true);
        let mut mark = t.start_laps();
        t.lap(&mut mark, Stage::Kinematics);
        t.lap_term(&mut mark, 0, "inertia");
        t.lap(&mut mark, Stage::Assembly);
        let names: Vec<_> = t.report().iter().map(|r| r.stage).collect();
        assert_eq!(names, ["kinematics", "inertia", "assembly"]);
        t.clear();
        assert!(t.report().is_empty() && t.detailed());
    }

    #[test]
    fn carve_keeps_a_partition_and_report_follows_the_pipeline() {
        let ms = Duration::from_millis;
        let mut t = StageTimers::default();
        t.add(Stage::Accept, ms(1));
        t.add_term(1, "contact", ms(10));
        t.add_term(0, "inertia", ms(2));
        t.add(Stage::Kinematics, ms(3));
        t.set_reporting(Some(1));
        t.carve(Stage::BroadPhase, ms(4));
        t.set_reporting(None);
        let r = t.report();
        let names: Vec<_> = r.iter().map(|r| r.stage).collect();
        assert_eq!(
            names,
            ["kinematics", "inertia", "contact", "broad_phase", "accept"]
        );
        let total: f64 = r.iter().map(|r| r.seconds).sum();
        assert!((total - 0.016).abs() < 1e-12);
        assert!((r[2].seconds - 0.006).abs() < 1e-12);
    }
}
