//! `report.html` of `sdrs optimize`: one self-contained page (inline SVG,
//! no script, no network) with the convergence plot next to rendered
//! stills of the robot — initial vs optimized, whole robot at `t = 0` and
//! at the horizon (`robot.svg`), and the designed links in their own frames
//! (`shapes.svg`) — and the headline numbers. Works without a browser
//! engine's WebGL; `sdrs view DIR --out view.html` gives the animated view.

/// The HTML page. `svgs` are `(caption, svg document)` pairs shown after
/// the convergence plot, in order.
pub fn report_html(
    title: &str,
    initial_loss: f64,
    final_loss: f64,
    iterations: usize,
    convergence_svg: &str,
    svgs: &[(&str, &str)],
) -> String {
    let esc = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut figs = format!(
        "<figure>{}<figcaption>convergence (best loss per iteration)</figcaption></figure>\n",
        strip_prolog(convergence_svg)
    );
    for (cap, svg) in svgs {
        figs.push_str(&format!(
            "<figure>{}<figcaption>{}</figcaption></figure>\n",
            strip_prolog(svg),
            esc(cap)
        ));
    }
    format!(
        r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>{t}</title>
<style>
body {{ font: 14px sans-serif; margin: 16px; color: #222; }}
.figs {{ display: flex; flex-wrap: wrap; gap: 16px; align-items: flex-start; }}
figure {{ margin: 0; border: 1px solid #ddd; padding: 6px; }}
figcaption {{ text-align: center; color: #555; }}
figure svg {{ max-width: min(640px, 46vw); height: auto; }}
</style></head><body>
<h1>{t}</h1>
<p>loss {initial_loss:.4e} → {final_loss:.4e} ({red:.1}% lower) in {iterations} iterations.
Animated view: <code>sdrs view THIS_DIRECTORY --out view.html</code>.</p>
<div class="figs">
{figs}</div>
</body></html>
"#,
        t = esc(title),
        red = 100.0 * (1.0 - final_loss / initial_loss),
    )
}

/// An SVG document without an XML declaration or doctype (for inlining).
fn strip_prolog(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_inlines_every_figure_beside_the_plot() {
        let plot = "<?xml version=\"1.0\"?>\n<svg id=\"plot\"></svg>";
        let html = report_html(
            "a <b>",
            2.0,
            0.5,
            3,
            plot,
            &[("robot", "<svg id=\"robot\"></svg>")],
        );
        assert!(!html.contains("<?xml"));
        let (p, r) = (
            html.find("id=\"plot\"").unwrap(),
            html.find("id=\"robot\"").unwrap(),
        );
        assert!(p < r);
        assert!(html.contains("75.0% lower"));
        assert!(html.contains("a &lt;b&gt;"));
    }
}
