//! `sdrs calibrate`: options and the whole run (the command-line arguments
//! are the application's, `cli/src/calibrate.rs`).

use super::analysis::analyse;
use super::data::Measured;
use super::mcap_log::LogMapping;
use super::problem::Problem;
use super::problem::Simulated;
use super::report::{self, CalibrationResult};
use super::select::{SelectOptions, select};
use super::{CalibrateError, candidates};
use crate::energy::effects::EffectKind;
use crate::progress::{Progress, Silent};
use crate::scene::Scene;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of a calibration run.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    pub scene: PathBuf,
    /// The (first) measured recording, simulated from the scene's initial
    /// state.
    pub measured: PathBuf,
    /// Further recordings fitted with the same parameters, each simulated
    /// from its first sample ([`super::recordings`]). Default none.
    pub more_measured: Vec<PathBuf>,
    /// Output directory (created; files in it are replaced atomically; no
    /// file is written when the run fails).
    pub out: PathBuf,
    /// Candidate effect kinds (default: all of [`EffectKind::ALL`]).
    pub effects: Vec<EffectKind>,
    /// Held-out fraction, in (0, 1). Default 0.3.
    pub holdout: f64,
    /// Fitting and selection options (defaults: [`SelectOptions::default`]).
    pub select: SelectOptions,
    /// How MCAP logs among the measured files map to the scene (topic,
    /// joint renames; default `/joint_states`, names as they are).
    pub log: LogMapping,
    /// With contact, fit the contact model's resolution (`s`, `κ`) before
    /// the selection and never offer it as an effect
    /// ([`super::nuisance`]). Default `false` (they are kept as given and
    /// `contact_s`, `contact_kappa` compete as candidates): the two-stage
    /// fit absorbs part of real effects on contact-rich data (the slider's
    /// hidden-effect suite: 10 of 16 named instead of 16, session 6).
    pub fit_contact_resolution: bool,
}

impl CalibrateOptions {
    /// The options of `sdrs calibrate scene --measured measured --out out`
    /// with `effects` named (`None`: all) and the given held-out fraction;
    /// unknown effect names are errors.
    pub fn new(
        scene: PathBuf,
        measured: PathBuf,
        out: PathBuf,
        effects: Option<&[String]>,
        holdout: f64,
    ) -> Result<Self, CalibrateError> {
        Ok(CalibrateOptions {
            scene,
            measured,
            more_measured: Vec::new(),
            out,
            effects: effect_kinds(effects)?,
            holdout,
            select: SelectOptions::default(),
            log: LogMapping::default(),
            fit_contact_resolution: false,
        })
    }
}

/// With the contact resolution fitted as a setting (`fit`,
/// [`super::nuisance`]), naming `contact_s` or `contact_kappa` among the
/// candidate effects is an error saying how to make them candidates.
pub fn check_resolution_names(names: Option<&[String]>, fit: bool) -> Result<(), CalibrateError> {
    let kinds = super::nuisance::KINDS.map(|k| k.name());
    match names
        .into_iter()
        .flatten()
        .find(|n| fit && kinds.contains(&n.as_str()))
    {
        Some(n) => Err(CalibrateError::Effects {
            msg: format!(
                "`{n}` is the contact model's resolution: it is fitted before the selection and never named as an effect; drop --fit-contact-resolution (Python: fit_contact_resolution=False) to make it a candidate"
            ),
        }),
        None => Ok(()),
    }
}

/// The effect kinds `names` lists (`None`: all of [`EffectKind::ALL`]; the
/// [`EffectKind::OPT_IN`] ones only when named); an unknown name is an
/// error listing the known ones.
pub fn effect_kinds(names: Option<&[String]>) -> Result<Vec<EffectKind>, CalibrateError> {
    let Some(names) = names else {
        return Ok(EffectKind::ALL.to_vec());
    };
    names
        .iter()
        .map(|n| {
            EffectKind::from_name(n.trim()).ok_or_else(|| CalibrateError::Effects {
                msg: format!(
                    "unknown effect \"{n}\" (effects: {})",
                    EffectKind::ALL
                        .iter()
                        .chain(&EffectKind::OPT_IN)
                        .map(|k| k.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            })
        })
        .collect()
}

/// Draws calibration's SVG plots: the application's (`cli/src/svg`); the
/// core draws nothing. Errors are messages (the plot is not written).
pub trait PlotWriter: Sync {
    /// Channel `c` of `m`: the measured samples, the simulation `before`
    /// (as given) and `after` (calibrated), the held-out window from
    /// `split_t` (s) on shaded.
    fn channel_svg(
        &self,
        m: &Measured,
        c: usize,
        before: &Simulated,
        after: &Simulated,
        split_t: f64,
    ) -> Result<String, String>;
    /// The residuals (simulated − measured) of every channel, before and
    /// after.
    fn residuals_svg(
        &self,
        m: &Measured,
        before: &Simulated,
        after: &Simulated,
    ) -> Result<String, String>;
}

/// Writes the calibrated scene in another format: the application's
/// (`calibrated.xml` for MuJoCo, `cli/src/calibrated_mjcf.rs`); the core
/// writes only `calibrated.yaml`.
pub trait ModelWriter: Sync {
    /// The file name, its contents, and a `report.md` section (what was
    /// mapped and what has no equivalent) for `scene`, the scene with the
    /// fitted effects at their Δt → 0 values (`parameters` of
    /// `calibration.json`: the physical estimate, for an engine with its
    /// own step). Errors are messages (nothing is written).
    fn write(&self, scene: &Scene) -> Result<(String, Vec<u8>, String), String>;
}

/// Writes `report.html`: the application's
/// (`cli/src/calibration_report.rs`); the core writes only `report.md`.
pub trait ReportWriter: Sync {
    /// The page of result `r` (scene file `scene`, measured files
    /// `measured`), with `plots` (`(file name, SVG)`, the plots written
    /// beside it) inline. Errors are messages (nothing is written).
    fn html(
        &self,
        r: &CalibrationResult,
        scene: &str,
        measured: &str,
        plots: &[(String, String)],
    ) -> Result<String, String>;
}

/// What a calibration run reports to and asks of its caller.
#[derive(Clone, Copy)]
pub struct Hooks<'a> {
    /// Told about the candidate fits (one unit per fit). Default [`Silent`].
    pub progress: &'a dyn Progress,
    /// Draws `channel_<name>.svg` and `residuals.svg`; `None` (the default)
    /// writes no plots.
    pub plots: Option<&'a dyn PlotWriter>,
    /// Writes the calibrated model in another format (`calibrated.xml`);
    /// `None` (the default) writes none.
    pub model: Option<&'a dyn ModelWriter>,
    /// Writes `report.html` (with the plots, when `plots` draws them);
    /// `None` (the default) writes none.
    pub report: Option<&'a dyn ReportWriter>,
}

impl Default for Hooks<'_> {
    fn default() -> Self {
        Hooks {
            progress: &Silent,
            plots: None,
            model: None,
            report: None,
        }
    }
}

/// A file-name-safe version of a channel name (`arm/elbow` → `arm_elbow`).
pub fn file_stem(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Output files: name in the output directory and contents.
pub type Files = Vec<(String, Vec<u8>)>;

/// Computes the calibration without writing anything; returns the result
/// and the output files.
pub fn calibrate(opts: &CalibrateOptions) -> Result<(CalibrationResult, Files), CalibrateError> {
    calibrate_with(opts, &Hooks::default())
}

/// [`calibrate`] with progress reports and plots ([`Hooks`]).
pub fn calibrate_with(
    opts: &CalibrateOptions,
    hooks: &Hooks,
) -> Result<(CalibrationResult, Files), CalibrateError> {
    let progress = hooks.progress;
    let t0 = Instant::now();
    if !(opts.holdout > 0.0 && opts.holdout < 1.0) {
        return Err(CalibrateError::Holdout(opts.holdout));
    }
    let scene = Scene::load(&opts.scene)?;
    let measured = Measured::load_with(&opts.measured, &scene.model, &opts.log)?;
    let split = super::recordings::split_of(&measured, opts.holdout)?;
    // The scene as given must simulate over the whole data.
    let steps = (measured.duration() / scene.settings.dt).ceil() as usize + 1;
    crate::sim::run::run(&mut scene.simulator(), steps, |_| {}).map_err(|source| {
        CalibrateError::Simulation {
            path: opts.scene.clone(),
            source,
        }
    })?;
    let others = load_others(opts, &scene)?;
    let pb = Problem {
        scene: &scene,
        measured: &measured,
        split,
        others: &others,
    };
    let fitted = match opts.fit_contact_resolution {
        true => super::nuisance::fit_resolution(&pb, &opts.select.fit),
        false => None,
    };
    let (scene, resolution) = match &fitted {
        Some((sc, r)) => (sc, Some(r.clone())),
        None => (&scene, None),
    };
    let pb = Problem { scene, ..pb };
    let kinds: Vec<EffectKind> = (opts.effects.iter().copied())
        .filter(|k| !(opts.fit_contact_resolution && super::nuisance::KINDS.contains(k)))
        .collect();
    let cands = candidates::candidates(scene, &kinds);
    let sel = select(
        &pb,
        cands,
        &opts.select,
        &|n| progress.start(n as u64, "candidate fits"),
        &|| progress.inc(),
    );
    progress.finish();
    let sel = sel.ok_or_else(|| CalibrateError::Output {
        path: opts.scene.clone(),
        msg: "the scene as given could not be simulated".into(),
    })?;
    let after_sim = sel
        .chosen
        .map(|i| &sel.ranking[i].sim)
        .unwrap_or(&sel.baseline.sim);
    let before = analyse(&measured, &sel.baseline.sim, split);
    let after = analyse(&measured, after_sim, split);
    let mut res = report::result(&pb, &sel, before, after, opts.holdout);
    res.simulations += resolution.as_ref().map_or(0, |c| c.simulations);
    res.contact_resolution = resolution;
    let mut files = output_files(opts, scene, &res)?;
    if let Some(w) = hooks.model {
        model_file(opts, &pb, &sel, w, &mut files)?;
    }
    if let Some(plots) = hooks.plots {
        files.extend(plot_files(opts, plots, &measured, &sel, &res)?);
    }
    if let Some(w) = hooks.report {
        let svgs: Vec<(String, String)> = files
            .iter()
            .filter(|(n, _)| n.ends_with(".svg"))
            .map(|(n, b)| (n.clone(), String::from_utf8_lossy(b).into_owned()))
            .collect();
        let scene_name = opts.scene.display().to_string();
        let html = w
            .html(&res, &scene_name, &measured_list(opts), &svgs)
            .map_err(|msg| CalibrateError::Output {
                path: opts.out.join("report.html"),
                msg,
            })?;
        files.push(("report.html".into(), html.into_bytes()));
    }
    let inputs: Vec<&PathBuf> = [&opts.scene, &opts.measured]
        .into_iter()
        .chain(&opts.more_measured)
        .collect();
    for (name, _) in &files {
        let p = opts.out.join(name);
        if inputs.iter().any(|i| same_file(&p, i)) {
            return Err(CalibrateError::WouldOverwriteInput { path: p });
        }
    }
    res.seconds = t0.elapsed().as_secs_f64();
    Ok((res, files))
}

/// Appends the [`ModelWriter`]'s file (and its `report.md` section) for
/// the scene with the chosen effects at their Δt → 0 values.
fn model_file(
    opts: &CalibrateOptions,
    pb: &Problem,
    sel: &super::select::Selection,
    w: &dyn ModelWriter,
    files: &mut Files,
) -> Result<(), CalibrateError> {
    let specs = sel.chosen.map_or_else(Vec::new, |i| {
        let s = &sel.ranking[i];
        s.candidate
            .specs(sel.extrapolated.as_ref().unwrap_or(&s.fit.params))
    });
    let err = |msg: String| CalibrateError::Output {
        path: opts.out.join("calibrated.xml"),
        msg,
    };
    let sc = pb
        .scene_with(&specs)
        .ok_or_else(|| err("the fitted effects do not apply to the scene".into()))?;
    let (name, bytes, section) = w.write(&sc).map_err(err)?;
    if let Some(md) = files.iter_mut().find(|(n, _)| n == "report.md") {
        md.1.extend_from_slice(section.as_bytes());
    }
    files.push((name, bytes));
    Ok(())
}

/// The further recordings of `opts` ([`super::recordings::load`]); a file
/// given twice is an error.
fn load_others(
    opts: &CalibrateOptions,
    scene: &Scene,
) -> Result<Vec<super::problem::Recording>, CalibrateError> {
    let mut seen = vec![&opts.measured];
    let mut out = Vec::new();
    for p in &opts.more_measured {
        if seen.iter().any(|q| *q == p || same_file(q, p)) {
            return Err(CalibrateError::Recording {
                path: p.clone(),
                msg: "given twice as --measured (each recording counts once)".into(),
            });
        }
        seen.push(p);
        out.push(super::recordings::load(p, scene, opts.holdout, &opts.log)?);
    }
    Ok(out)
}

/// The measured files of `opts`, comma separated (for headers).
fn measured_list(opts: &CalibrateOptions) -> String {
    std::iter::once(&opts.measured)
        .chain(&opts.more_measured)
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// `calibrated.yaml`, `calibration.json` and `report.md`.
fn output_files(
    opts: &CalibrateOptions,
    scene: &Scene,
    res: &CalibrationResult,
) -> Result<Files, CalibrateError> {
    let mut files: Files = Vec::new();
    let mut spec = scene.spec.clone();
    spec.effects.extend(res.effects.iter().cloned());
    let yaml = serde_yaml::to_string(&spec).map_err(|e| CalibrateError::Output {
        path: opts.out.join("calibrated.yaml"),
        msg: e.to_string(),
    })?;
    let header = format!(
        "# Written by `sdrs calibrate` from {} and {}: the scene plus the fitted effects.\n",
        opts.scene.display(),
        measured_list(opts)
    );
    files.push((
        "calibrated.yaml".into(),
        format!("{header}{yaml}").into_bytes(),
    ));
    let json = serde_json::to_string_pretty(res).map_err(|e| CalibrateError::Output {
        path: opts.out.join("calibration.json"),
        msg: e.to_string(),
    })?;
    files.push(("calibration.json".into(), json.into_bytes()));
    let mut md = report::markdown(res, &opts.scene.display().to_string(), &measured_list(opts));
    md.push_str(&super::recordings::markdown(&res.recordings));
    md.push_str(&super::identifiability::markdown(
        &res.identifiability,
        res.candidate.as_deref(),
    ));
    if let Some(r) = &res.residual_regression {
        md.push_str(&super::residual::markdown(r));
    }
    files.push(("report.md".into(), md.into_bytes()));
    Ok(files)
}

/// The SVG plots (of the first recording).
fn plot_files(
    opts: &CalibrateOptions,
    plots: &dyn PlotWriter,
    measured: &Measured,
    sel: &super::select::Selection,
    res: &CalibrationResult,
) -> Result<Files, CalibrateError> {
    let plot_err = |name: &str, msg: String| CalibrateError::Output {
        path: opts.out.join(name),
        msg,
    };
    let after_sim = sel
        .chosen
        .map(|i| &sel.ranking[i].sim)
        .unwrap_or(&sel.baseline.sim);
    let mut files = Files::new();
    for c in 0..measured.channels.len() {
        let name = format!("channel_{}.svg", file_stem(&measured.channels[c].name));
        let svg = plots
            .channel_svg(measured, c, &sel.baseline.sim, after_sim, res.split_time)
            .map_err(|m| plot_err(&name, m))?;
        files.push((name, svg.into_bytes()));
    }
    let svg = plots
        .residuals_svg(measured, &sel.baseline.sim, after_sim)
        .map_err(|m| plot_err("residuals.svg", m))?;
    files.push(("residuals.svg".into(), svg.into_bytes()));
    Ok(files)
}

/// Writes `files` into `dir`: a new directory is filled under a temporary
/// name and renamed into place; in an existing one each file is replaced
/// atomically.
pub fn write_files(dir: &Path, files: &[(String, Vec<u8>)]) -> Result<(), CalibrateError> {
    let io = |path: &Path, e: std::io::Error| CalibrateError::Output {
        path: path.to_path_buf(),
        msg: e.to_string(),
    };
    if dir.exists() {
        for (name, bytes) in files {
            crate::files::write_atomic(&dir.join(name), bytes).map_err(|e| {
                CalibrateError::Output {
                    path: dir.join(name),
                    msg: e.to_string(),
                }
            })?;
        }
        return Ok(());
    }
    let parent = dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).map_err(|e| io(parent, e))?;
    let stem = dir
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "calibration".into());
    let tmp = parent.join(format!(".{stem}.tmp{}", std::process::id()));
    let res = (|| {
        std::fs::create_dir_all(&tmp)?;
        for (name, bytes) in files {
            std::fs::write(tmp.join(name), bytes)?;
        }
        std::fs::rename(&tmp, dir)
    })();
    if let Err(e) = res {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(io(dir, e));
    }
    Ok(())
}

/// Runs a calibration and writes its outputs (nothing is written on error).
pub fn run(opts: &CalibrateOptions) -> Result<CalibrationResult, CalibrateError> {
    run_with(opts, &Hooks::default())
}

/// [`run`] with progress reports and plots ([`Hooks`]).
pub fn run_with(
    opts: &CalibrateOptions,
    hooks: &Hooks,
) -> Result<CalibrationResult, CalibrateError> {
    let (res, files) = calibrate_with(opts, hooks)?;
    write_files(&opts.out, &files)?;
    Ok(res)
}
