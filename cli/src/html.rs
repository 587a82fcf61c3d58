//! The application's one HTML writer: self-contained report pages (inline
//! CSS and SVG, no network) for `sdrs compare` (`report.html`) and `sdrs
//! calibrate` (`report.html`). A [`Page`] is a title, then headings,
//! paragraphs, tables and inline SVG figures in order; [`Page::finish`]
//! appends a self-check the browser tests read back (`#render-check`:
//! "plots rendered: k of n", counting the figures with drawn content).
//! (The interactive viewers of `sdrs view` are another kind of page:
//! `view/page.rs`.)

/// Escapes text for HTML element content.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// Escapes text for element content, rendering `` `…` `` spans (as the
/// Markdown reports write names) as `<code>` (unbalanced backticks are
/// left as they are).
pub fn text(s: &str) -> String {
    let e = escape(s);
    if !e.matches('`').count().is_multiple_of(2) {
        return e;
    }
    let mut out = String::new();
    for (k, part) in e.split('`').enumerate() {
        if k % 2 == 1 {
            out.push_str(&format!("<code>{part}</code>"));
        } else {
            out.push_str(part);
        }
    }
    out
}

/// Escapes text for a double-quoted attribute value.
pub fn attr(s: &str) -> String {
    escape(s).replace('"', "&quot;")
}

/// The style every report page shares.
const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em}table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:3px 8px;text-align:right}th{background:#eee}td:first-child{text-align:left}figure{margin:1em 0}.regressed{color:#b00;font-weight:bold}";

/// A table as HTML: header cells and rows of cells, all escaped text.
pub fn table(id: &str, header: &[String], rows: &[Vec<String>]) -> String {
    table_with(id, header, rows, |_| "")
}

/// [`table`] with a class per row (`""`: none); cells are escaped text.
pub fn table_with<'a>(
    id: &str,
    header: &[String],
    rows: &[Vec<String>],
    class: impl Fn(usize) -> &'a str,
) -> String {
    let cells: Vec<Vec<Cell>> = rows
        .iter()
        .map(|r| r.iter().map(|c| Cell::Text(c.clone())).collect())
        .collect();
    table_cells(id, header, &cells, class)
}

/// A table cell: escaped text, or markup the caller built (from escaped
/// parts).
pub enum Cell {
    Text(String),
    Html(String),
}

/// A table of [`Cell`]s with a class per row (`""`: none).
pub fn table_cells<'a>(
    id: &str,
    header: &[String],
    rows: &[Vec<Cell>],
    class: impl Fn(usize) -> &'a str,
) -> String {
    let mut s = format!("<table id=\"{}\"><thead><tr>", attr(id));
    for h in header {
        s.push_str(&format!("<th>{}</th>", escape(h)));
    }
    s.push_str("</tr></thead><tbody>");
    for (k, r) in rows.iter().enumerate() {
        match class(k) {
            "" => s.push_str("<tr>"),
            c => s.push_str(&format!("<tr class=\"{}\">", attr(c))),
        }
        for c in r {
            match c {
                Cell::Text(t) => s.push_str(&format!("<td>{}</td>", escape(t))),
                Cell::Html(h) => s.push_str(&format!("<td>{h}</td>")),
            }
        }
        s.push_str("</tr>");
    }
    s + "</tbody></table>"
}

/// An SVG document (as plotters writes it) ready to inline: the XML
/// prolog dropped, the root tagged `class="plot"` for the render check.
pub fn inline_svg(svg: &str) -> String {
    let body = svg.find("<svg").map_or(svg, |i| &svg[i..]);
    body.replacen("<svg", "<svg class=\"plot\"", 1)
}

/// A report page being written.
pub struct Page {
    html: String,
}

impl Page {
    /// A page titled `title` (also its `<h1>`), with `css` added to the
    /// shared style.
    pub fn new(title: &str, css: &str) -> Page {
        Page {
            html: format!(
                "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{STYLE}{css}</style></head><body><h1>{}</h1>",
                escape(title),
                escape(title)
            ),
        }
    }

    /// Markup built by the caller (from escaped parts).
    pub fn raw(&mut self, html: &str) {
        self.html.push_str(html);
    }

    pub fn h2(&mut self, text: &str) {
        self.html.push_str(&format!("<h2>{}</h2>", escape(text)));
    }

    pub fn h3(&mut self, text: &str) {
        self.html.push_str(&format!("<h3>{}</h3>", escape(text)));
    }

    /// A paragraph of text (`` `…` `` spans as code, [`text`]).
    pub fn p(&mut self, t: &str) {
        self.html.push_str(&format!("<p>{}</p>", text(t)));
    }

    /// A bulleted list of text items (`` `…` `` spans as code).
    pub fn list(&mut self, items: &[String]) {
        self.html.push_str("<ul>");
        for i in items {
            self.html.push_str(&format!("<li>{}</li>", text(i)));
        }
        self.html.push_str("</ul>");
    }

    /// An inline SVG figure with a caption.
    pub fn figure(&mut self, svg: &str, caption: &str) {
        self.html.push_str(&format!(
            "<figure>{}<figcaption>{}</figcaption></figure>",
            inline_svg(svg),
            escape(caption)
        ));
    }

    /// The page, closed, with the render self-check.
    pub fn finish(mut self) -> String {
        self.html.push_str("<p id=\"render-check\">plots not checked</p><script>(function(){var s=document.querySelectorAll('svg.plot');var ok=0;s.forEach(function(e){var b=e.getBBox();if(e.querySelectorAll('polyline,polygon,path,line,circle').length>0&&b.width>0&&b.height>0)ok++;});document.getElementById('render-check').textContent='plots rendered: '+ok+' of '+s.length;})();</script></body></html>\n");
        self.html
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_svg_inlined_for_the_check() {
        let mut p = Page::new("a < b", "");
        p.p("x & `y`");
        p.figure(
            "<?xml version=\"1.0\"?>\n<svg width=\"2\"><line/></svg>",
            "c",
        );
        let t = table("t", &["h".into()], &[vec!["<i>".into()]]);
        p.raw(&t);
        let h = p.finish();
        assert!(
            h.contains("<title>a &lt; b</title>") && h.contains("<p>x &amp; <code>y</code></p>")
        );
        assert!(h.contains("<figure><svg class=\"plot\" width=\"2\">") && !h.contains("<?xml"));
        assert!(h.contains("<td>&lt;i&gt;</td>") && h.contains("id=\"render-check\""));
    }
}
