//! The Python helper scripts this binary carries (`include_str!` of
//! `tools/helpers/mjcf_dump.py` and `tools/helpers/coacd_decompose.py` at build time), so an
//! installed `sdrs` (`cargo install --path cli`) imports MJCF and runs CoACD
//! without a source tree. On first use a script is written to
//! `<temp>/sdrs-helpers-<content hash>/<name>`; an existing file there is
//! used only if its bytes are the carried ones (else it is rewritten, or a
//! folder of this process is used). The interpreter is `$SDRS_PYTHON`, a
//! source tree's `.venv`, or `python3` (see `sdrs::import::python`). The
//! helpers run through [`crate::child::Runner`].

use sdrs::import::python::{HelperSource, set_helper_runner, set_helper_source};
use std::path::{Path, PathBuf};

/// The carried scripts.
const SCRIPTS: [(&str, &str); 2] = [
    (
        "mjcf_dump.py",
        include_str!("../../tools/helpers/mjcf_dump.py"),
    ),
    (
        "coacd_decompose.py",
        include_str!("../../tools/helpers/coacd_decompose.py"),
    ),
];

/// FNV-1a (64 bit) of every carried script: the folder name changes with
/// the scripts, so two versions of `sdrs` never share a file.
fn content_hash() -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (name, text) in SCRIPTS {
        for b in name.bytes().chain(text.bytes()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

struct Embedded;

/// Writes `text` to `dir/name` (temporary file + rename) unless it is
/// already there byte for byte.
fn materialize(dir: &Path, name: &str, text: &str) -> std::io::Result<PathBuf> {
    let path = dir.join(name);
    if std::fs::read(&path).is_ok_and(|b| b == text.as_bytes()) {
        return Ok(path);
    }
    std::fs::create_dir_all(dir)?;
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, &path)?;
    Ok(path)
}

impl HelperSource for Embedded {
    fn script(&self, name: &str) -> Result<PathBuf, String> {
        let (_, text) = SCRIPTS
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| format!("this sdrs carries no helper named {name}"))?;
        let shared = std::env::temp_dir().join(format!("sdrs-helpers-{:016x}", content_hash()));
        let own = shared.with_file_name(format!(
            "sdrs-helpers-{:016x}-{}",
            content_hash(),
            std::process::id()
        ));
        materialize(&shared, name, text)
            .or_else(|_| materialize(&own, name, text))
            .map_err(|e| format!("cannot write the helper {name} to {}: {e}", own.display()))
    }
}

/// Registers the carried scripts as the helpers' source.
pub fn install() {
    set_helper_source(Box::new(Embedded));
    set_helper_runner(Box::new(crate::child::Runner));
}
