//! The application's SVG plots (plotters' SVG backend): line plots
//! (`optimize`'s convergence, `sdrs plot`, the `compare` report) with
//! titled, labelled axes with units, a legend, log axes padded to at least
//! one decade so that they carry several ticks; and calibration's plots
//! ([`calibration`]).

pub mod calibration;

use anyhow::Result;
use plotters::prelude::*;

/// One labelled series of `(x, y)` points.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Dashed line (paper or reference data).
    pub dashed: bool,
}

/// Axes of a plot.
pub struct Axes<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
    pub log_x: bool,
    pub log_y: bool,
}

fn range(v: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && (!log || *x > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        // At least one decade, centred on the data (geometrically).
        let (mut l, mut h) = (lo / 1.3, hi * 1.3);
        if h / l < 10.0 {
            let c = (l * h).sqrt();
            l = c / 10f64.sqrt();
            h = c * 10f64.sqrt();
        }
        (l, h)
    } else {
        let pad = 0.05 * (hi - lo).abs().max(1e-12 * hi.abs().max(1.0));
        (lo - pad, hi + pad)
    }
}

const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];

fn fmt_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if (1e-2..1e4).contains(&a) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// The plot as an SVG document.
pub fn line_plot(axes: &Axes<'_>, series: &[Series]) -> Result<String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (640, 400)).into_drawing_area();
        root.fill(&WHITE)?;
        let (x0, x1) = range(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
            axes.log_x,
        );
        let (y0, y1) = range(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
            axes.log_y,
        );
        let mut b = ChartBuilder::on(&root);
        b.caption(axes.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(axes.x)
                    .y_desc(axes.y)
                    .x_label_formatter(&|x| fmt_tick(*x))
                    .y_label_formatter(&|y| fmt_tick(*y))
                    .draw()?;
                for (k, s) in series.iter().enumerate() {
                    let color = COLORS[k % COLORS.len()];
                    let pts: Vec<(f64, f64)> = s
                        .points
                        .iter()
                        .copied()
                        .filter(|(x, y)| {
                            x.is_finite()
                                && y.is_finite()
                                && (!axes.log_x || *x > 0.0)
                                && (!axes.log_y || *y > 0.0)
                        })
                        .collect();
                    let style = color.stroke_width(2);
                    if s.dashed {
                        chart
                            .draw_series(DashedLineSeries::new(pts.clone(), 6, 4, style))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 18, y)], style)
                            });
                    } else {
                        chart
                            .draw_series(LineSeries::new(pts.clone(), style))?
                            .label(s.label.as_str())
                            .legend(move |(x, y)| {
                                PathElement::new(vec![(x, y), (x + 18, y)], style)
                            });
                    }
                    chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
                }
                chart
                    .configure_series_labels()
                    .border_style(BLACK)
                    .background_style(WHITE.mix(0.9))
                    .position(SeriesLabelPosition::UpperLeft)
                    .draw()?;
            }};
        }
        match (axes.log_x, axes.log_y) {
            (true, true) => {
                draw!(b.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?)
            }
            (false, true) => draw!(b.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?),
            (true, false) => draw!(b.build_cartesian_2d((x0..x1).log_scale(), y0..y1)?),
            (false, false) => draw!(b.build_cartesian_2d(x0..x1, y0..y1)?),
        }
        root.present()?;
    }
    Ok(svg)
}

/// Convergence plot (best loss per iteration) as SVG, titled `title`;
/// several labelled histories may share it (e.g. co-design vs controller
/// only). The loss axis is logarithmic (padded to at least a decade, so it
/// carries several labelled ticks) when every loss is positive, else linear.
pub fn convergence_svg(
    title: &str,
    series: &[(&str, &[sdrs::optimize::IterRecord])],
) -> Result<String> {
    let positive = series
        .iter()
        .all(|(_, h)| h.iter().all(|r| r.best_loss > 0.0));
    let s: Vec<Series> = series
        .iter()
        .map(|(label, h)| Series {
            label: label.to_string(),
            points: h.iter().map(|r| (r.iter as f64, r.best_loss)).collect(),
            dashed: false,
        })
        .collect();
    line_plot(
        &Axes {
            title,
            x: "iteration",
            y: "best task loss",
            log_x: false,
            log_y: positive,
        },
        &s,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_carry_title_labels_legend_and_several_ticks() {
        let svg = line_plot(
            &Axes {
                title: "cost vs vertices",
                x: "vertices per hull",
                y: "µs per evaluation",
                log_x: true,
                log_y: true,
            },
            &[Series {
                label: "SDRS".into(),
                points: vec![(8.0, 3.0), (16.0, 4.0)],
                dashed: false,
            }],
        )
        .unwrap();
        for s in [
            "cost vs vertices",
            "vertices per hull",
            "µs per evaluation",
            "SDRS",
        ] {
            assert!(svg.contains(s), "missing {s}");
        }
        // A range of less than a decade is padded: several y tick labels.
        let ticks = svg.matches("<text").count();
        assert!(ticks >= 8, "only {ticks} text elements");
    }
}
