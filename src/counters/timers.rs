//! Stage timers of the time step (fed into the summary JSON and reports).
//! Stages partition the step's wall time: no stage's time is counted in
//! another (enclosing spans hand nested time over with [`StageTimers::transfer`]
//! or exclude it).

use serde::Serialize;
use std::time::{Duration, Instant};

/// Accumulated wall time per named stage, in the order stages first ran.
#[derive(Clone, Debug, Default)]
pub struct StageTimers {
    stages: Vec<(&'static str, Duration, u64)>,
}

/// One row of the stage breakdown.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct StageTime {
    pub stage: &'static str,
    pub seconds: f64,
    pub calls: u64,
}

impl StageTimers {
    /// Adds `d` to stage `name`.
    pub fn add(&mut self, name: &'static str, d: Duration) {
        // Stage names are string literals: the pointer test almost always
        // decides without comparing bytes.
        if let Some(s) = self
            .stages
            .iter_mut()
            .find(|s| std::ptr::eq(s.0, name) || s.0 == name)
        {
            s.1 += d;
            s.2 += 1;
        } else {
            self.stages.push((name, d, 1));
        }
    }

    /// Runs `f`, timing it into stage `name`.
    pub fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let out = f();
        self.add(name, t0.elapsed());
        out
    }

    /// Moves `d` from stage `from` (which timed an enclosing span) to stage
    /// `to`, so stages stay a partition of the step's time.
    pub fn transfer(&mut self, from: &'static str, to: &'static str, d: Duration) {
        if let Some(s) = self.stages.iter_mut().find(|s| s.0 == from) {
            s.1 = s.1.saturating_sub(d);
        }
        self.add(to, d);
    }

    /// The breakdown, in first-run order.
    pub fn report(&self) -> Vec<StageTime> {
        self.stages
            .iter()
            .map(|(stage, d, calls)| StageTime {
                stage,
                seconds: d.as_secs_f64(),
                calls: *calls,
            })
            .collect()
    }

    pub fn clear(&mut self) {
        self.stages.clear();
    }
}
