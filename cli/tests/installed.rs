//! An `sdrs` binary away from any source tree (as `cargo install --path cli`
//! leaves it) imports MJCF with the helper scripts it carries, and a Python
//! without the `mujoco` package gets an error naming it and the install
//! command (issue 32, item 4).

use crate::support;

use support::{root, scratch_dir};

const MODEL: &str = r#"<mujoco model="installed"><worldbody>
  <geom name="floor" type="plane" size="5 5 0.1"/>
  <body name="a" pos="0 0 0.5"><freejoint/><geom type="box" size="0.1 0.1 0.1"/>
    <body name="b" pos="0.3 0 0"><joint type="hinge" axis="0 1 0"/><geom type="sphere" size="0.05"/></body>
  </body></worldbody></mujoco>"#;

/// Runs `cmd`, retrying while the kernel reports the executable busy: the
/// two tests copy a binary (or write a script) and run it at the same time,
/// and a copy's write descriptor, inherited by the other test's child
/// between its fork and exec, makes `exec` fail with `ETXTBSY` until that
/// child has exec'd (seen once in a full local run).
fn output(cmd: &mut std::process::Command) -> std::process::Output {
    for _ in 0..50 {
        match cmd.output() {
            Err(e) if e.kind() == std::io::ErrorKind::ExecutableFileBusy => {
                std::thread::sleep(std::time::Duration::from_millis(20))
            }
            r => return r.unwrap(),
        }
    }
    cmd.output().unwrap()
}

/// The binary copied into a scratch folder, the model next to it, and the
/// command run there with no `SDRS_ROOT`.
fn installed(dir: &std::path::Path) -> std::process::Command {
    let bin = dir.join("bin/sdrs");
    std::fs::create_dir_all(bin.parent().unwrap()).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_sdrs"), &bin).unwrap();
    std::fs::write(dir.join("model.xml"), MODEL).unwrap();
    let mut cmd = std::process::Command::new(bin);
    cmd.current_dir(dir).env_remove("SDRS_ROOT").args([
        "import",
        "model.xml",
        "--out",
        "model.yaml",
        "-q",
    ]);
    cmd
}

#[test]
fn a_binary_outside_the_source_tree_imports_mjcf_with_its_own_helpers() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("installed-ok");
    assert!(
        !dir.ancestors()
            .any(|d| d.join("tools/helpers/mjcf_dump.py").is_file()),
        "the scratch folder must not be inside a source tree"
    );
    let out = output(installed(&dir).env("SDRS_PYTHON", root().join(".venv/bin/python")));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let scene = std::fs::read_to_string(dir.join("model.yaml")).unwrap();
    assert!(scene.contains("free"), "{scene}");
}

#[test]
fn a_python_without_mujoco_gets_the_package_name_and_install_command() {
    if support::skip_without_venv() {
        return;
    }
    let dir = scratch_dir("installed-missing");
    // The venv's interpreter without its site-packages: no mujoco.
    let wrapper = dir.join("python-bare");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\nexec {} -S \"$@\"\n",
            root().join(".venv/bin/python").display()
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    let out = output(installed(&dir).env("SDRS_PYTHON", &wrapper));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("missing Python package: mujoco") && err.contains("-m pip install mujoco"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}
