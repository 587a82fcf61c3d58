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

/// A Python `SdrsError` with `e`'s full cause chain.
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
    force=false, bridge=true, ties="shared_vertex", base="auto", ground=false, contact=true,
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
    ground: bool,
    contact: bool,
    hold: bool,
    pose: Option<std::collections::BTreeMap<String, f64>>,
) -> PyResult<PathBuf> {
    use clap::ValueEnum;
    let pick = |what: &str, s: &str| {
        SdrsError::new_err(format!("import_robot: {what}: unknown value \"{s}\""))
    };
    let args = sdrs::import::cli::ImportArgs {
        input,
        out: out.clone(),
        decomposer: ValueEnum::from_str(decomposer, true)
            .map_err(|_| pick("decomposer", decomposer))?,
        max_hulls,
        resolution,
        threshold,
        hull_points: Default::default(),
        designable,
        mass: ValueEnum::from_str(mass, true).map_err(|_| pick("mass", mass))?,
        density,
        report,
        force,
        no_bridge: !bridge,
        ties: ValueEnum::from_str(&ties.replace('_', "-"), true).map_err(|_| pick("ties", ties))?,
        quiet: true,
        base: ValueEnum::from_str(base, true).map_err(|_| pick("base", base))?,
        ground,
        no_contact: !contact,
        no_hold: !hold,
        pose: pose.unwrap_or_default().into_iter().collect(),
    };
    py.detach(|| sdrs::import::cli::run_import(&args))
        .map_err(|e| SdrsError::new_err(format!("{e:#}")))?;
    Ok(out)
}

/// Names the physical effect missing from a scene given measured data,
/// fits it and writes `calibrated.yaml`, `calibration.json`, `report.md` and
/// plots into `out`, exactly as `sdrs calibrate SCENE --measured CSV --out
/// OUT` (`effects`: candidate names, default all applicable; `holdout`: the
/// fraction of the data, at the end, held out for scoring). Returns the
/// contents of `calibration.json` as a dict (verdict, effect, parameters,
/// gaps before/after, ranking …). GIL released.
#[pyfunction]
#[pyo3(signature = (scene, measured, out, *, effects=None, holdout=0.3))]
fn calibrate<'py>(
    py: Python<'py>,
    scene: PathBuf,
    measured: PathBuf,
    out: PathBuf,
    effects: Option<Vec<String>>,
    holdout: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let args = sdrs::calibrate::CalibrateArgs {
        scene,
        measured,
        out,
        effects,
        holdout,
        quiet: true,
    };
    let json = py
        .detach(|| {
            let opts = sdrs::calibrate::CalibrateOptions::from_args(&args)?;
            let r = sdrs::calibrate::run(&opts)?;
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
