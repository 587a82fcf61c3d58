//! Helper processes and temporary folders that do not outlive `sdrs`: the
//! [`HelperRunner`] the binary registers with the core
//! (`sdrs::import::python::set_helper_runner`).
//!
//! - A helper ([`Runner::output`]) is started with `PR_SET_PDEATHSIG =
//!   SIGKILL` (Linux), so the kernel kills it when `sdrs` dies for any
//!   reason, even `SIGKILL`; and it is registered, so that on
//!   `SIGINT`/`SIGTERM`/`SIGHUP` the handler kills it at once. (The kernel
//!   sends that signal when the *thread* that started the helper ends; the
//!   import starts helpers from rayon's worker threads, which live as long
//!   as the process.)
//! - A temporary folder the core creates for a helper is registered
//!   ([`Runner::create_folder`]) and removed by the same handler when `sdrs`
//!   is interrupted, before it exits with `128 + signal` (130 for `SIGINT`;
//!   `ctrlc` does not say which signal came, so 130 is used for all). The
//!   core removes it itself when it is done with it.
//!
//! The handler is installed the first time a helper or folder is registered;
//! if another handler was installed first (`sdrs simulate`'s), ours is not
//! (the kernel's parent-death signal still stops the helper, but the folder
//! stays).

use sdrs::import::python::HelperRunner;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, Once};

static CHILDREN: Mutex<Vec<u32>> = Mutex::new(Vec::new());
static FOLDERS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
static HANDLER: Once = Once::new();

fn install_handler() {
    HANDLER.call_once(|| {
        let _ = ctrlc::set_handler(|| {
            cleanup();
        });
    });
}

/// Kills every registered helper, removes every registered folder and
/// exits with 130. The folder list stays locked until the exit, so a
/// folder that another thread is about to create ([`Runner::create_folder`]
/// creates and registers under the same lock) is never made: a worker
/// that went on to its next mesh once left two folders behind
/// (`child_cleanup`, seen in CI).
fn cleanup() {
    if let Ok(children) = CHILDREN.lock() {
        for &pid in children.iter() {
            #[cfg(unix)]
            // SAFETY: sending a signal to a process id has no memory effects.
            unsafe {
                libc::kill(pid as libc::pid_t, libc::SIGKILL);
            }
            #[cfg(not(unix))]
            let _ = pid;
        }
    }
    let folders = FOLDERS.lock();
    if let Ok(folders) = &folders {
        for f in folders.iter() {
            let _ = std::fs::remove_dir_all(f);
        }
    }
    std::process::exit(130);
}

/// The `sdrs` binary's helper runner (see the module doc).
pub struct Runner;

impl HelperRunner for Runner {
    fn output(&self, mut cmd: Command) -> std::io::Result<Output> {
        install_handler();
        #[cfg(target_os = "linux")]
        {
            use std::os::unix::process::CommandExt;
            // SAFETY: prctl is async-signal-safe; nothing else runs between
            // fork and exec here.
            unsafe {
                cmd.pre_exec(|| {
                    if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) != 0 {
                        return Err(std::io::Error::last_os_error());
                    }
                    Ok(())
                });
            }
        }
        cmd.stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped());
        let child = cmd.spawn()?;
        let pid = child.id();
        if let Ok(mut c) = CHILDREN.lock() {
            c.push(pid);
        }
        let out = child.wait_with_output();
        if let Ok(mut c) = CHILDREN.lock() {
            c.retain(|&p| p != pid);
        }
        out
    }

    fn create_folder(&self, path: &Path) -> std::io::Result<()> {
        install_handler();
        let mut f = FOLDERS
            .lock()
            .map_err(|_| std::io::Error::other("the temporary-folder list is poisoned"))?;
        std::fs::create_dir_all(path)?;
        f.push(path.to_path_buf());
        Ok(())
    }

    fn forget_folder(&self, path: &Path) {
        if let Ok(mut f) = FOLDERS.lock() {
            f.retain(|p| p != path);
        }
    }
}
