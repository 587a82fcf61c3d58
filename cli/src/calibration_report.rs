//! `report.html` of `sdrs calibrate`: the result for someone who would
//! rather look than read, on one self-contained page (the application's
//! [`crate::html`] writer; plots inline). Top to bottom: the verdict and
//! its reason; the gap against the model's own error (noise, integrator,
//! floor) as bars on a log scale; the plots (measured vs simulated vs
//! calibrated per channel, residuals); the fitted parameters with their
//! intervals; the ranking of the candidates; identifiability; the
//! residual force regression; each recording's gaps. Every number comes
//! from `calibration.json` ([`CalibrationResult`]); no timing is shown
//! (the page is deterministic).

use crate::html::{Cell, Page, escape, table, table_cells, text};
use sdrs::calibrate::{CalibrationResult, ReportWriter};

/// The page `sdrs calibrate` (and the Python `calibrate`) writes.
pub struct CalibrationReport;

impl ReportWriter for CalibrationReport {
    fn html(
        &self,
        r: &CalibrationResult,
        scene: &str,
        measured: &str,
        plots: &[(String, String)],
    ) -> Result<String, String> {
        Ok(page(r, scene, measured, plots))
    }
}

const CSS: &str = ".meta{color:#555}.verdict{border-radius:8px;padding:.8em 1.2em;margin:1em 0;border:2px solid}.verdict h2{margin:.2em 0}.v-effect{background:#e8f5e9;border-color:#2e7d32}.v-none{background:#e3f2fd;border-color:#1565c0}.v-unexplained{background:#fff3e0;border-color:#e65100}.big{font-size:1.15em}.bars{margin:1em 0;max-width:900px}.bar{display:grid;grid-template-columns:16em 1fr 7em;align-items:center;gap:.6em;margin:3px 0}.track{position:relative;background:#f3f3f3;height:18px}.fill{height:18px}.floorline{position:absolute;top:-3px;bottom:-3px;border-left:2px dashed #333}.num{text-align:right;font-family:monospace}tr.chosen td{background:#e8f5e9;font-weight:bold}#ranking{width:100%}#ranking td{white-space:nowrap}#ranking td:nth-child(2){text-align:left;white-space:normal}#ranking td:nth-child(7),#ranking td:nth-child(8){white-space:normal;text-align:left;font-size:.85em;max-width:16em}.wide{overflow-x:auto}.flag li{color:#b00}summary{cursor:pointer;color:#1565c0}tr.implausible td{color:#999}.rms{display:inline-block;height:10px;background:#1565c0;vertical-align:middle;margin-right:6px}.flag{color:#b00}code{background:#f3f3f3;padding:0 3px}figure svg{max-width:100%;height:auto}td{font-variant-numeric:tabular-nums}";

/// A number for a table: 4 significant digits.
fn g(x: f64) -> String {
    if !x.is_finite() {
        "—".into()
    } else {
        format!("{x:.3e}")
    }
}

/// The whole page.
pub fn page(
    r: &CalibrationResult,
    scene: &str,
    measured: &str,
    plots: &[(String, String)],
) -> String {
    let mut p = Page::new("Calibration report", CSS);
    p.raw(&format!(
        "<p class=\"meta\">Scene <code>{}</code>, measured <code>{}</code>: {} samples; training window up to t = {:.3} s, held-out window after it (holdout {}). Details: <code>report.md</code>, <code>calibration.json</code>.</p>",
        escape(scene),
        escape(measured),
        r.samples.times,
        r.split_time,
        r.holdout
    ));
    verdict(&mut p, r);
    floor(&mut p, r);
    figures(&mut p, plots);
    parameters(&mut p, r);
    ranking(&mut p, r);
    identifiability(&mut p, r);
    regression(&mut p, r);
    recordings(&mut p, r);
    p.finish()
}

/// The verdict card: what was found, the gap before and after, why.
fn verdict(p: &mut Page, r: &CalibrationResult) {
    let (class, head) = match (r.verdict.as_str(), &r.effect) {
        ("effect", Some(e)) => ("v-effect", format!("Missing effect: {e}")),
        ("unexplained", _) => (
            "v-unexplained",
            "Unexplained: a discrepancy no candidate explains".to_string(),
        ),
        _ => ("v-none", "No missing effect".to_string()),
    };
    let mut s = format!(
        "<div class=\"verdict {class}\" id=\"verdict\" data-verdict=\"{}\"><h2>Verdict: {}</h2>",
        escape(&r.verdict),
        escape(&head)
    );
    if let Some(c) = &r.candidate {
        s.push_str(&format!(
            "<p class=\"big\">candidate <code>{}</code></p>",
            escape(c)
        ));
    }
    s.push_str(&format!(
        "<p class=\"big\">held-out RMS gap {} → {} ({}); the model's error floor {}</p><p>Why: {}.</p>",
        g(r.gap_before.overall),
        g(r.gap_after.overall),
        if r.candidate.is_none() {
            "unchanged: nothing fitted".to_string()
        } else if r.gap_reduction >= 0.0 {
            format!("reduced by {:.1} %", 100.0 * r.gap_reduction)
        } else {
            format!("increased by {:.1} %", -100.0 * r.gap_reduction)
        },
        g(r.error_floor.floor),
        text(&r.reason)
    ));
    if !r.indistinguishable.is_empty() {
        s.push_str(&format!(
            "<p>Indistinguishable on these data: {}.</p>",
            r.indistinguishable
                .iter()
                .map(|c| format!("<code>{}</code>", escape(c)))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    p.raw(&(s + "</div>"));
}

/// One bar of the floor chart on a log scale from `lo` to `hi`.
fn bar(label: &str, v: f64, color: &str, lo: f64, hi: f64, floor_at: f64) -> String {
    let pos = |x: f64| 100.0 * ((x.max(lo).ln() - lo.ln()) / (hi.ln() - lo.ln())).clamp(0.0, 1.0);
    format!(
        "<div class=\"bar\"><span>{}</span><div class=\"track\"><div class=\"fill\" style=\"width:{:.2}%;background:{color}\"></div><div class=\"floorline\" style=\"left:{:.2}%\"></div></div><span class=\"num\">{}</span></div>",
        escape(label),
        if v > 0.0 { pos(v) } else { 0.0 },
        pos(floor_at),
        g(v)
    )
}

/// The gap next to the noise, the integrator error, the contact resolution
/// (scenes with contact) and the floor.
fn floor(p: &mut Page, r: &CalibrationResult) {
    let f = &r.error_floor;
    p.h2("The gap against the model's own error");
    let mut rows: Vec<(&str, f64, &str)> = vec![
        ("noise σ", f.noise, "#90a4ae"),
        ("integrator error at Δt", f.integrator, "#90a4ae"),
        (
            "integrator error in the gap",
            f.integrator_in_gap,
            "#90a4ae",
        ),
        ("error floor F", f.floor, "#455a64"),
        ("gap as given", r.gap_before.overall, "#c62828"),
        ("gap as given, Δt/2", f.gap_half_dt, "#ef9a9a"),
        ("gap calibrated", r.gap_after.overall, "#2e7d32"),
    ];
    if f.contact_s.is_some() {
        rows.insert(3, ("contact resolution (s halved)", f.contact, "#b0bec5"));
        rows.insert(
            4,
            ("contact resolution in the gap", f.contact_in_gap, "#b0bec5"),
        );
    }
    let pos: Vec<f64> = rows
        .iter()
        .map(|x| x.1)
        .filter(|v| *v > 0.0 && v.is_finite())
        .collect();
    let lo = pos.iter().copied().fold(f64::INFINITY, f64::min) / 3.0;
    let hi = pos.iter().copied().fold(0.0, f64::max) * 1.5;
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (1e-6, 1.0)
    };
    let mut s = String::from("<div class=\"bars\" id=\"floor\">");
    for (label, v, color) in rows {
        s.push_str(&bar(label, v, color, lo, hi, f.floor));
    }
    s.push_str("</div>");
    p.raw(&s);
    let ratio = |x: f64| x / f.floor.max(1e-300);
    let mut text = format!(
        "Held-out RMS, log scale; the dashed line is the floor F. The gap as given is {:.1}× the floor, calibrated {:.1}×. At Δt = {} s the gap shrinks ×{:.2} at Δt/2 (observed order {:.2}; extrapolated to Δt → 0: {}).",
        ratio(r.gap_before.overall),
        ratio(r.gap_after.overall),
        f.dt,
        f.shrink_half_dt,
        f.order,
        g(f.gap_extrapolated)
    );
    if f.floor_of != "none" {
        text.push_str(&format!(
            " The floor is that of the chosen model {} (the scene as given: {}).",
            f.floor_of,
            g(f.floor_baseline)
        ));
    }
    if let Some(dt) = f.suggested_dt {
        text.push_str(&format!(
            " Effects of the size of the noise become resolvable at Δt ≤ {dt:.2e} s."
        ));
    }
    if let Some(c) = &r.contact_resolution {
        text.push_str(&format!(
            " The contact model's resolution was fitted first (a setting of the simulator, never named as an effect; \"as given\" above is with it): {c}."
        ));
    }
    p.p(&text);
}

/// The plots, channels first, residuals last.
fn figures(p: &mut Page, plots: &[(String, String)]) {
    if plots.is_empty() {
        return;
    }
    p.h2("Measured, simulated and calibrated");
    for (name, svg) in plots.iter().filter(|(n, _)| n != "residuals.svg") {
        let ch = name.trim_start_matches("channel_").trim_end_matches(".svg");
        p.figure(
            svg,
            &format!("{ch}: measured samples (black), the scene as given (red), calibrated (blue); the held-out window shaded ({name})"),
        );
    }
    for (name, svg) in plots.iter().filter(|(n, _)| n == "residuals.svg") {
        p.figure(
            svg,
            &format!("residuals (simulated − measured), as given (faint) and calibrated ({name})"),
        );
    }
}

/// Fitted parameters with their 95 % intervals; the mass a mass scale or
/// payload adds; implausible fits.
fn parameters(p: &mut Page, r: &CalibrationResult) {
    if !r.parameters.is_empty() {
        p.h2("Fitted parameters");
        let rows: Vec<Vec<String>> = r
            .parameters
            .iter()
            .map(|(k, v)| {
                let ci = r.confidence.get(k).and_then(|c| Some((c.low?, c.high?)));
                let at_dt = r.parameters_at_dt.get(k).copied().unwrap_or(f64::NAN);
                match ci {
                    Some((a, b)) => vec![
                        k.clone(),
                        g(*v),
                        format!("[{}, {}]", g(a), g(b)),
                        format!("±{:.1} %", 50.0 * (b - a) / v.abs().max(1e-300)),
                        g(at_dt),
                    ],
                    None => vec![
                        k.clone(),
                        g(*v),
                        "not identifiable".into(),
                        "—".into(),
                        g(at_dt),
                    ],
                }
            })
            .collect();
        let header = [
            "parameter",
            "value (Δt → 0)",
            "95 % interval",
            "relative",
            "as fitted at Δt",
        ]
        .map(String::from);
        p.raw(&table("parameters", &header, &rows));
    }
    if !r.mass_changes.is_empty() {
        let items: Vec<String> = r
            .mass_changes
            .iter()
            .map(|m| {
                format!(
                    "mass of `{}` (`{}`): {} → {} kg ({:+.4} kg)",
                    m.on,
                    m.parameter,
                    g(m.before_kg),
                    g(m.after_kg),
                    m.added_kg
                )
            })
            .collect();
        p.list(&items);
    }
    if !r.implausible.is_empty() {
        p.h3("Fits outside physically plausible ranges (never chosen)");
        let items: Vec<String> = r
            .implausible
            .iter()
            .map(|i| format!("`{}`: {}", i.candidate, i.reason))
            .collect();
        p.list(&items);
    }
}

/// The candidates' ranking, the chosen one highlighted, held-out RMS as
/// bars against the scene as given.
fn ranking(p: &mut Page, r: &CalibrationResult) {
    p.h2("Candidates");
    p.p(&format!(
        "Criterion C = BIC(train) + n_ho ln(RSS_ho/n_ho); ΔC > 0 is better than the scene as given (held-out RMS {}). The bar is each candidate's held-out RMS relative to the scene as given.",
        g(r.baseline.rms_holdout)
    ));
    let base = r.baseline.rms_holdout.max(1e-300);
    let implausible = |c: &str| r.implausible.iter().any(|i| i.candidate == c);
    let rows: Vec<Vec<Cell>> = r
        .ranking
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let w = (100.0 * c.rms_holdout / base).clamp(0.0, 100.0);
            let mut notes = Vec::new();
            if r.candidate.as_deref() == Some(c.candidate.as_str()) {
                notes.push("chosen".to_string());
            }
            if implausible(&c.candidate) {
                notes.push("implausible".into());
            }
            if r.indistinguishable.contains(&c.candidate) {
                notes.push("indistinguishable".into());
            }
            if !c.unidentifiable.is_empty() {
                notes.push(format!("not identifiable: {}", c.unidentifiable.join(", ")));
            }
            let params: Vec<String> = c
                .parameters
                .iter()
                .map(|(k, v)| format!("{k} = {}", g(*v)))
                .collect();
            vec![
                Cell::Text(format!("{}", i + 1)),
                Cell::Text(c.candidate.clone()),
                Cell::Text(format!("{:.1}", c.delta_criterion)),
                Cell::Html(format!(
                    "<span class=\"rms\" style=\"width:{:.0}px\"></span>{}",
                    w,
                    g(c.rms_holdout)
                )),
                Cell::Text(g(c.rms_train)),
                Cell::Text(format!("{:.1} %", 100.0 * c.explained)),
                Cell::Text(params.join(", ")),
                Cell::Text(notes.join("; ")),
            ]
        })
        .collect();
    let header = [
        "#",
        "candidate",
        "ΔC",
        "held-out RMS",
        "train RMS",
        "explained",
        "parameters",
        "notes",
    ]
    .map(String::from);
    p.raw("<div class=\"wide\">");
    p.raw(&table_cells("ranking", &header, &rows, |k| {
        let c = &r.ranking[k].candidate;
        if r.candidate.as_deref() == Some(c.as_str()) {
            "chosen"
        } else if implausible(c) {
            "implausible"
        } else {
            ""
        }
    }));
    p.raw("</div>");
}

/// One line per candidate: condition number, or what is not identifiable
/// and what to excite.
fn identifiability(p: &mut Page, r: &CalibrationResult) {
    if r.identifiability.is_empty() {
        return;
    }
    p.h2("Identifiability (before fitting)");
    let bad = r
        .identifiability
        .iter()
        .filter(|i| !i.unidentifiable.is_empty())
        .count();
    p.p(&format!(
        "Each candidate's scaled Gauss–Newton matrix at its start: {} of {} candidates identifiable on these data.",
        r.identifiability.len() - bad,
        r.identifiability.len()
    ));
    let flagged: Vec<String> = r
        .identifiability
        .iter()
        .filter(|i| !i.unidentifiable.is_empty())
        .map(|i| {
            format!(
                "`{}`: not identifiable: {}{}",
                i.candidate,
                i.unidentifiable.join(", "),
                i.suggestion
                    .as_ref()
                    .map(|s| format!(". {s}"))
                    .unwrap_or_default()
            )
        })
        .collect();
    p.raw("<div id=\"identifiability\" class=\"flag\">");
    p.list(&flagged);
    p.raw("</div>");
    let rows: Vec<Vec<String>> = r
        .identifiability
        .iter()
        .map(|i| {
            vec![
                i.candidate.clone(),
                i.condition.map_or("—".to_string(), |c| format!("{c:.2e}")),
                format!("{:.1e}", i.min_relative_eigenvalue),
                if i.unidentifiable.is_empty() {
                    "identifiable".to_string()
                } else {
                    format!("not identifiable: {}", i.unidentifiable.join(", "))
                },
            ]
        })
        .collect();
    let header = ["candidate", "condition κ", "λ_min/λ_ref", "status"].map(String::from);
    p.raw("<details><summary>Every candidate's condition number</summary>");
    p.raw(&table("identifiability-all", &header, &rows));
    p.raw("</details>");
}

/// The residual generalized force regression's named terms per joint.
fn regression(p: &mut Page, r: &CalibrationResult) {
    let Some(reg) = &r.residual_regression else {
        return;
    };
    p.h2("Residual force regression");
    p.p(&format!(
        "The scene's residual generalized force regressed on candidate terms per joint (sparse; 95 % intervals). Strongest structure: {}.",
        reg.strongest.as_deref().unwrap_or("none (no term kept)")
    ));
    for j in &reg.joints {
        p.h3(&format!(
            "{}: residual force RMS {}, {:.1} % of the held-out residual explained ({} rows)",
            j.joint,
            g(j.rms_force),
            100.0 * j.explained_holdout,
            j.rows
        ));
        if j.terms.is_empty() {
            p.p("No term kept.");
            continue;
        }
        let rows: Vec<Vec<String>> = j
            .terms
            .iter()
            .map(|t| {
                vec![
                    t.term.clone(),
                    t.meaning.clone(),
                    g(t.coefficient),
                    format!("[{}, {}]", g(t.low), g(t.high)),
                    t.unit.clone(),
                ]
            })
            .collect();
        let header = ["term", "meaning", "coefficient", "95 % interval", "unit"].map(String::from);
        p.raw(&table(&format!("regression-{}", j.joint), &header, &rows));
    }
}

/// Each recording's gaps (several recordings only).
fn recordings(p: &mut Page, r: &CalibrationResult) {
    if r.recordings.len() < 2 {
        return;
    }
    p.h2("Recordings");
    let rows: Vec<Vec<String>> = r
        .recordings
        .iter()
        .map(|x| {
            vec![
                x.path.clone(),
                x.initial.clone(),
                x.samples.to_string(),
                g(x.train_before),
                g(x.train_after),
                g(x.holdout_before),
                g(x.holdout_after),
            ]
        })
        .collect();
    let header = [
        "recording",
        "initial state",
        "samples",
        "train before",
        "train after",
        "held-out before",
        "held-out after",
    ]
    .map(String::from);
    p.raw(&table("recordings", &header, &rows));
}
