//! Counters of the time step (rapier's `counters/`): the stage timers that
//! partition a step's wall time into typed stages ([`Stage`]), and the
//! diagnostics each step reports. They sit below `energy` and `sim`, which
//! both write into them, so neither depends on the other for them.

pub mod ccd;
pub mod step;
pub mod timers;

pub use ccd::CcdStats;
pub use step::{NewtonReport, StepDiagnostics, StepWork};
pub use timers::{Stage, StageTime, StageTimers};
