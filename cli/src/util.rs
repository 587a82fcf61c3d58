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

/// A file of the source tree (`robots/...`), found from the current
/// directory or above the binary (`target/release/sdrs` in a source tree).
pub fn bundled(rel: &str) -> anyhow::Result<std::path::PathBuf> {
    let rel = Path::new(rel);
    let cwd = std::env::current_dir().ok();
    let exe = std::env::current_exe().ok();
    cwd.iter()
        .chain(exe.iter())
        .flat_map(|p| p.ancestors())
        .map(|d| d.join(rel))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            anyhow::anyhow!(
                "the bundled file {} was not found from the current directory or the binary's location",
                rel.display()
            )
        })
}
