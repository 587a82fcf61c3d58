//! Helpers shared by the verbs: progress bars and output-path checks.

use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

/// A progress bar over `n` steps, hidden when `quiet` (or not on a terminal).
pub fn progress(n: usize, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new(n as u64);
    pb.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} steps ({eta} left)",
        )
        .expect("static template"),
    );
    pb
}

/// Whether two paths name the same existing file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
