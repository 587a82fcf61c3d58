//! Progress of long library operations (decomposing an import's links,
//! calibration's candidate fits), reported to whoever runs them: the library
//! calls a [`Progress`] it is given and draws nothing itself. The `sdrs`
//! binary passes a terminal progress bar (`cli/src/progress.rs`); library
//! users and the Python package pass [`Silent`].

/// An observer of one operation's progress, told how many units of work
/// there are, which one is under way and when each is done. Every method
/// defaults to doing nothing. `Sync`: units may finish on several threads.
pub trait Progress: Sync {
    /// `len` units of `what` (e.g. `"links"`) are about to be done.
    fn start(&self, _len: u64, _what: &str) {}
    /// The unit now under way (e.g. a link's name).
    fn message(&self, _msg: &str) {}
    /// One more unit is done.
    fn inc(&self) {}
    /// The operation is over (done, or given up on an error).
    fn finish(&self) {}
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {}
