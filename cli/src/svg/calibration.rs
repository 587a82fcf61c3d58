//! SVG plots of a calibration: per channel, measured samples vs the
//! simulation as given vs the calibrated simulation (the held-out window
//! shaded); and the residuals over time before and after.

use plotters::prelude::*;
use sdrs::calibrate::PlotWriter;
use sdrs::calibrate::data::Measured;
use sdrs::calibrate::problem::Simulated;

/// The plots `sdrs calibrate` (and the Python `calibrate`) write.
pub struct CalibrationPlots;

impl PlotWriter for CalibrationPlots {
    fn channel_svg(
        &self,
        m: &Measured,
        c: usize,
        before: &Simulated,
        after: &Simulated,
        split_t: f64,
    ) -> Result<String, String> {
        channel_svg(m, c, before, after, split_t)
    }

    fn residuals_svg(
        &self,
        m: &Measured,
        before: &Simulated,
        after: &Simulated,
    ) -> Result<String, String> {
        residuals_svg(m, before, after)
    }
}

type PlotResult = Result<String, String>;

fn err<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(1e-9);
    (lo - pad, hi + pad)
}

/// Measured vs simulated vs calibrated for channel `c` of `m`.
pub fn channel_svg(
    m: &Measured,
    c: usize,
    before: &Simulated,
    after: &Simulated,
    split_t: f64,
) -> PlotResult {
    let ch = &m.channels[c];
    let t_end = m.duration();
    let grid: Vec<f64> = (0..=400).map(|k| t_end * k as f64 / 400.0).collect();
    let meas: Vec<(f64, f64)> = m
        .times
        .iter()
        .zip(&ch.values)
        .filter_map(|(t, v)| v.map(|v| (*t, v)))
        .collect();
    let sb: Vec<(f64, f64)> = grid.iter().map(|&t| (t, before.at(ch.dof, t))).collect();
    let sa: Vec<(f64, f64)> = grid.iter().map(|&t| (t, after.at(ch.dof, t))).collect();
    let (lo, hi) = range(meas.iter().chain(&sb).chain(&sa).map(|p| p.1));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{}: measured vs simulated", ch.name),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(0f64..t_end.max(1e-9), lo..hi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc(ch.name.as_str())
            .draw()
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(split_t, lo), (t_end, hi)],
                RGBColor(235, 235, 235).filled(),
            )))
            .map_err(err)?
            .label("held-out window")
            .legend(|(x, y)| {
                Rectangle::new(
                    [(x, y - 5), (x + 18, y + 5)],
                    RGBColor(220, 220, 220).filled(),
                )
            });
        chart
            .draw_series(meas.iter().map(|p| Circle::new(*p, 2, BLACK.filled())))
            .map_err(err)?
            .label("measured")
            .legend(|(x, y)| Circle::new((x + 9, y), 3, BLACK.filled()));
        for (pts, color, label) in [
            (&sb, RED, "simulated (as given)"),
            (&sa, BLUE, "calibrated"),
        ] {
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// Residuals (simulated − measured) of every channel before and after.
pub fn residuals_svg(m: &Measured, before: &Simulated, after: &Simulated) -> PlotResult {
    let series = |s: &Simulated, c: usize| -> Vec<(f64, f64)> {
        let ch = &m.channels[c];
        m.times
            .iter()
            .zip(&ch.values)
            .filter_map(|(t, v)| v.map(|v| (*t, s.at(ch.dof, *t) - v)))
            .collect()
    };
    let all: Vec<Vec<(f64, f64)>> = (0..m.channels.len())
        .flat_map(|c| [series(before, c), series(after, c)])
        .collect();
    let (lo, hi) = range(all.iter().flatten().map(|p| p.1));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("residuals (simulated − measured)", ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(72)
            .build_cartesian_2d(0f64..m.duration().max(1e-9), lo..hi)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc("residual (SI)")
            .draw()
            .map_err(err)?;
        let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK];
        for (k, pts) in all.iter().enumerate() {
            let c = k / 2;
            let color = palette[c % palette.len()];
            let style = if k % 2 == 0 {
                color.mix(0.35).stroke_width(1)
            } else {
                color.stroke_width(2)
            };
            let label = format!(
                "{} ({})",
                m.channels[c].name,
                if k % 2 == 0 { "as given" } else { "calibrated" }
            );
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), style))
                .map_err(err)?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
        }
        chart
            .configure_series_labels()
            .border_style(BLACK)
            .background_style(WHITE)
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(svg)
}
