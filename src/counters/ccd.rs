//! Statistics of the articulated continuous collision detection in the
//! line search (`contact::ccd`), counted per step and per run.

use serde::Serialize;

/// CCD statistics, summed over Newton iterations (per step in
/// [`crate::sim::StepDiagnostics`], per run in the summary).
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct CcdStats {
    /// Accepted Newton segments checked.
    pub segments: usize,
    /// Hull pairs whose swept boxes overlapped and whose gap was measured.
    pub pairs_tested: usize,
    /// Of those, pairs not cleared by the cheap test (bound on relative
    /// motion below the gap) that needed conservative advancement.
    pub pairs_advanced: usize,
    /// Advancement rounds (each one kinematics evaluation and one GJK query
    /// per pair in doubt).
    pub rounds: usize,
    /// Accepted line-search steps that were cut short (the search then
    /// continued from the cut).
    pub alpha_caps: usize,
    /// Smallest step fraction `α` of a Newton direction after a cut (1 when
    /// none).
    pub min_alpha: f64,
    /// Pairs GJK could not certify as separated at a segment's start (left
    /// to the barrier; see the module docs).
    pub uncertified: usize,
    /// Steps whose straight path `θ^t → θ^{t+1}` could not be certified
    /// and that were solved again with certified line-search segments
    /// (see [`crate::sim::Simulator::step`]).
    pub fallbacks: usize,
}

impl Default for CcdStats {
    fn default() -> Self {
        CcdStats {
            segments: 0,
            pairs_tested: 0,
            pairs_advanced: 0,
            rounds: 0,
            alpha_caps: 0,
            min_alpha: 1.0,
            uncertified: 0,
            fallbacks: 0,
        }
    }
}

impl CcdStats {
    /// Adds `o` into `self`.
    pub fn merge(&mut self, o: &CcdStats) {
        self.segments += o.segments;
        self.pairs_tested += o.pairs_tested;
        self.pairs_advanced += o.pairs_advanced;
        self.rounds += o.rounds;
        self.alpha_caps += o.alpha_caps;
        self.min_alpha = self.min_alpha.min(o.min_alpha);
        self.uncertified += o.uncertified;
        self.fallbacks += o.fallbacks;
    }
}
