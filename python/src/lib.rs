//! `sdrs._sdrs`: the Python extension module of the SDRS core (PyO3).
//!
//! Classes: [`scene::PyScene`] (`sdrs.Scene`: load, simulate, design /
//! controller / physics vectors, adjoint gradients of a loss),
//! [`task::PyTask`] (`sdrs.Task`: a co-design task's spaces, evaluation,
//! the rollout/backward pair behind `sdrs.torch.rollout`, the Rust
//! optimizer), [`trajectory::PyTrajectory`] (numpy views of a run).
//! Functions: `import_robot`, `calibrate`, `num_threads`.
//!
//! Every long computation runs with the GIL released (`Python::detach`), so
//! Python threads (and Ray's worker threads) run meanwhile; the core's rayon
//! pool is used as from the CLI. Errors are `sdrs.SdrsError` carrying the
//! core's message (file, element, what is wrong).

mod eval;
mod params;
mod scene;
mod task;
mod trajectory;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use std::path::PathBuf;

create_exception!(
    sdrs,
    SdrsError,
    PyException,
    "An error of the SDRS core: a bad scene, task or import input (the message names the file and the element), a failed simulation step or backward pass."
);

/// `e` and its causes, `: `-separated, each once (a cause whose text the
/// message already contains is not repeated), as the `sdrs` CLI prints them.
pub(crate) fn cause_chain(e: &dyn std::error::Error) -> String {
    let mut msg = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !msg.contains(&text) {
            msg = format!("{msg}: {text}");
        }
        cause = c.source();
    }
    msg
}

/// A Python `SdrsError` with `e`'s message.
pub(crate) fn err(e: impl std::fmt::Display) -> PyErr {
    SdrsError::new_err(e.to_string())
}

/// Imports a robot (URDF + meshes, or one OBJ/STL/DAE mesh) into a
/// convex-hull scene YAML at `out`, exactly as `sdrs import INPUT --out OUT`
/// with the same options (hull OBJs go to `<out stem>_meshes/`). Returns
/// `out`. Existing outputs are never replaced unless `force=True`.
#[pyfunction]
#[pyo3(signature = (input, out, *, decomposer="vhacd", max_hulls=16, resolution=64,
    threshold=None, designable=None, mass="urdf", density=1000.0, report=None,
    force=false, bridge=true, ties="shared_vertex", base="auto", ground=None, contact=true,
    hold=true, pose=None))]
// Arguments kept separate: a Python function with keyword arguments mirroring `sdrs import`'s flags (PyO3 maps each argument to a keyword).
#[allow(clippy::too_many_arguments)]
fn import_robot(
    py: Python<'_>,
    input: PathBuf,
    out: PathBuf,
    decomposer: &str,
    max_hulls: usize,
    resolution: u32,
    threshold: Option<f64>,
    designable: Option<Vec<String>>,
    mass: &str,
    density: f64,
    report: Option<PathBuf>,
    force: bool,
    bridge: bool,
    ties: &str,
    base: &str,
    ground: Option<bool>,
    contact: bool,
    hold: bool,
    pose: Option<std::collections::BTreeMap<String, f64>>,
) -> PyResult<PathBuf> {
    fn pick<T: std::str::FromStr<Err = String>>(what: &str, s: &str) -> PyResult<T> {
        s.parse()
            .map_err(|_| SdrsError::new_err(format!("import_robot: {what}: unknown value \"{s}\"")))
    }
    let decomposer: sdrs::import::Decomposer = pick("decomposer", decomposer)?;
    let options = sdrs::import::ImportOptions {
        decomposer,
        max_hulls: max_hulls.max(1),
        resolution,
        threshold: threshold.unwrap_or(sdrs::import::ImportOptions::default_threshold(decomposer)),
        designable,
        mass: pick("mass", mass)?,
        density,
        bridge_gaps: bridge,
        ties: pick::<sdrs::import::connectivity::Ties>("ties", &ties.replace('_', "-")).map_err(
            |_| SdrsError::new_err(format!("import_robot: ties: unknown value \"{ties}\"")),
        )?,
        ..Default::default()
    };
    let job = sdrs::import::ImportJob {
        report,
        force,
        options,
        base: pick("base", base)?,
        ground,
        contact,
        hold,
        pose: pose.unwrap_or_default().into_iter().collect(),
        ..sdrs::import::ImportJob::new(input, out.clone())
    };
    py.detach(|| sdrs::import::run_job(&job)).map_err(err)?;
    Ok(out)
}

/// Names the physical effect missing from a scene given measured data,
/// fits it and writes `calibrated.yaml`, `calibrated.xml`, `calibration.json`, `report.md` and
/// plots into `out`, exactly as `sdrs calibrate SCENE --measured CSV --out
/// OUT` (`measured`: a path, or a list of paths for several recordings
/// fitted with one parameter set, as `--measured` repeated; `effects`:
/// candidate names, default all applicable; `holdout`: the fraction of
/// each recording, at the end, held out for scoring; `topic`: the MCAP
/// logs' JointState topic, default `/joint_states`; `rename`: a dict
/// mapping a log's joint name to a scene coordinate, `""` to ignore it, as
/// `--rename LOG=COORD`; `fit_contact_resolution`: fit the contact model's `s`,
/// `κ` first and never name them, as `--fit-contact-resolution`). Returns the
/// contents of `calibration.json` as a dict (verdict, effect, parameters,
/// gaps before/after, ranking …). GIL released.
#[pyfunction]
#[pyo3(signature = (scene, measured, out, *, effects=None, holdout=0.3, topic=None, rename=None, fit_contact_resolution=false))]
#[allow(clippy::too_many_arguments)] // Python keyword arguments, one per CLI option
fn calibrate<'py>(
    py: Python<'py>,
    scene: PathBuf,
    measured: &Bound<'py, PyAny>,
    out: PathBuf,
    effects: Option<Vec<String>>,
    holdout: f64,
    topic: Option<String>,
    rename: Option<std::collections::BTreeMap<String, String>>,
    fit_contact_resolution: bool,
) -> PyResult<Bound<'py, PyAny>> {
    // A single path (str or os.PathLike) or a non-empty list of them.
    let measured: Vec<PathBuf> = match measured.extract::<PathBuf>() {
        Ok(p) => vec![p],
        Err(_) => measured.extract::<Vec<PathBuf>>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "calibrate(): measured must be a path or a list of paths",
            )
        })?,
    };
    let Some((first, more)) = measured.split_first() else {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "calibrate(): measured is an empty list (give at least one recording)",
        ));
    };
    let (first, more) = (first.clone(), more.to_vec());
    let json = py
        .detach(|| {
            let mut opts = sdrs::calibrate::CalibrateOptions::new(
                scene,
                first,
                out,
                effects.as_deref(),
                holdout,
            )?;
            opts.more_measured = more;
            opts.fit_contact_resolution = fit_contact_resolution;
            sdrs::calibrate::check_resolution_names(
                effects.as_deref(),
                opts.fit_contact_resolution,
            )?;
            opts.log = sdrs::calibrate::mcap_log::LogMapping {
                topic,
                rename: rename.unwrap_or_default().into_iter().collect(),
            };
            let hooks = sdrs::calibrate::Hooks {
                plots: Some(&sdrs_cli::svg::calibration::CalibrationPlots),
                model: Some(&sdrs_cli::calibrated_mjcf::CalibratedMjcf),
                report: Some(&sdrs_cli::calibration_report::CalibrationReport),
                ..Default::default()
            };
            let r = sdrs::calibrate::run_with(&opts, &hooks)?;
            Ok::<_, sdrs::calibrate::CalibrateError>(serde_json::to_string(&r))
        })
        .map_err(err)?
        .map_err(err)?;
    py.import("json")?.call_method1("loads", (json,))
}

/// Threads of the core's rayon pool (contact and friction terms run on it;
/// `RAYON_NUM_THREADS` sets it before the first simulation). Results are
/// bitwise the same for the same thread count.
#[pyfunction]
fn num_threads() -> usize {
    rayon::current_num_threads()
}

#[pymodule]
fn _sdrs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SdrsError", m.py().get_type::<SdrsError>())?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<task::PyTask>()?;
    m.add_class::<task::PyRollout>()?;
    m.add_class::<trajectory::PyTrajectory>()?;
    m.add_function(wrap_pyfunction!(import_robot, m)?)?;
    m.add_function(wrap_pyfunction!(num_threads, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    Ok(())
}
