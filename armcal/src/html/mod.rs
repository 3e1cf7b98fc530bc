//! The HTML reports of `check`, `calibrate` and `diagnose` (`--report FILE.html`): one
//! self-contained page each (styles inline, plots as inline SVG, no script, no network), which
//! a browser shows and prints to PDF as the test report or calibration certificate a customer
//! or an auditor receives.
//!
//! - `Document`: the page (title, header, sections, tables, figures, preformatted text),
//!   every text escaped here, so that a file name or a serial cannot inject markup.
//! - [`header`]: the provenance every report opens with (serial, date, data and SHA-256,
//!   software version, temperatures, ball, MPE file, decision rule).
//! - [`svg`]: the plots; [`residuals`]: the residual plots two reports share.
//! - [`check`], [`calibration`], [`diagnosis`]: each command's page.

pub mod calibration;
pub mod check;
pub mod diagnosis;
pub mod header;
pub mod residuals;
pub mod svg;

use std::fmt::Write as _;

/// `s` with HTML's special characters escaped (text and attribute values alike).
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// How a verdict or a decision is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Tone {
    /// Proven within (green).
    Good,
    /// Proven beyond (red).
    Bad,
    /// Neither (amber).
    Unsure,
    /// Plain.
    Plain,
}

impl Tone {
    fn class(self) -> &'static str {
        match self {
            Tone::Good => "good",
            Tone::Bad => "bad",
            Tone::Unsure => "unsure",
            Tone::Plain => "plain",
        }
    }
}

/// A table cell: text and its tone.
pub(crate) struct Cell(pub String, pub Tone);

impl From<String> for Cell {
    fn from(s: String) -> Cell {
        Cell(s, Tone::Plain)
    }
}

impl From<&str> for Cell {
    fn from(s: &str) -> Cell {
        Cell(s.to_string(), Tone::Plain)
    }
}

/// An HTML page being written.
pub(crate) struct Document {
    title: String,
    body: String,
}

const STYLE: &str = "body{font-family:sans-serif;margin:2em auto;max-width:1180px;color:#222}\
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;border-bottom:1px solid #ccc;margin-top:1.6em}\
table{border-collapse:collapse;margin:.6em 0;font-size:.9em}td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}\
th{background:#f2f2f2}td.num{text-align:right;font-variant-numeric:tabular-nums}\
.good{background:#d9f2d9}.bad{background:#f7d4d4}.unsure{background:#fbecc2}\
.verdict{font-size:1.5em;font-weight:bold;padding:.6em 1em;border:2px solid #888;margin:1em 0}\
.detail{font-size:.6em;font-weight:normal;margin-top:.3em}\
.figures{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0;break-inside:avoid}\
figcaption{font-size:.85em;max-width:560px;color:#444}pre{font-size:.8em;background:#f8f8f8;padding:.6em;overflow-x:auto}\
@media print{body{margin:0;max-width:none}.figures{display:block}}";

impl Document {
    /// A page titled `title` (also its first heading).
    pub fn new(title: &str) -> Document {
        Document {
            title: title.to_string(),
            body: format!("<h1>{}</h1>\n", escape(title)),
        }
    }

    /// The opening every report shares, in one place so that the certificate, the diagnosis
    /// and the test report read alike: the title, the header of where it comes from
    /// ([`header::Provenance`]), the verdict box and the warnings under it.
    pub fn opening(
        title: &str,
        prov: &header::Provenance,
        verdict: (&str, &str, Tone),
        warnings: &[String],
    ) -> Document {
        let mut d = Document::new(title);
        d.facts(&prov.facts());
        d.verdict(verdict.0, verdict.1, verdict.2);
        for w in warnings {
            d.paragraph(&format!("Warning: {w}"));
        }
        d
    }

    /// The ending of the reports that carry a command's text report: it, whole, and the page.
    pub fn closing(mut self, text: &str) -> String {
        self.heading("The report, in full");
        self.preformatted(text);
        self.finish()
    }

    /// A section heading.
    pub(crate) fn heading(&mut self, text: &str) {
        let _ = writeln!(self.body, "<h2>{}</h2>", escape(text));
    }

    /// A paragraph of text.
    pub(crate) fn paragraph(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
    }

    /// The verdict, boxed in its tone: a headline, then the detail; `id` lets a test or a
    /// script find it.
    pub fn verdict(&mut self, headline: &str, detail: &str, tone: Tone) {
        let _ = writeln!(
            self.body,
            r#"<div id="verdict" class="verdict {}">{}<div class="detail">{}</div></div>"#,
            tone.class(),
            escape(headline),
            escape(detail)
        );
    }

    /// A table of `rows` under `head`; a cell that parses as a number is right-aligned.
    pub fn table(&mut self, head: &[&str], rows: Vec<Vec<Cell>>) {
        self.body.push_str("<table><tr>");
        for h in head {
            let _ = write!(self.body, "<th>{}</th>", escape(h));
        }
        self.body.push_str("</tr>\n");
        for r in rows {
            self.body.push_str("<tr>");
            for Cell(text, tone) in r {
                let num = text.trim().parse::<f64>().is_ok();
                let class = match (tone, num) {
                    (Tone::Plain, false) => String::new(),
                    (Tone::Plain, true) => r#" class="num""#.into(),
                    (t, false) => format!(r#" class="{}""#, t.class()),
                    (t, true) => format!(r#" class="num {}""#, t.class()),
                };
                let _ = write!(self.body, "<td{class}>{}</td>", escape(&text));
            }
            self.body.push_str("</tr>\n");
        }
        self.body.push_str("</table>\n");
    }

    /// Key–value rows (the header).
    pub fn facts(&mut self, facts: &[(String, String)]) {
        self.body.push_str("<table>");
        for (k, v) in facts {
            let _ = write!(
                self.body,
                "<tr><th>{}</th><td>{}</td></tr>",
                escape(k),
                escape(v)
            );
        }
        self.body.push_str("</table>\n");
    }

    /// Plots side by side, each with its caption.
    pub fn figures(&mut self, plots: &[(svg::Plot, String)]) {
        if plots.is_empty() {
            return;
        }
        self.body.push_str(r#"<div class="figures">"#);
        for (p, caption) in plots {
            let _ = write!(
                self.body,
                "<figure>{}<figcaption>{}</figcaption></figure>",
                p.svg(),
                escape(caption)
            );
        }
        self.body.push_str("</div>\n");
    }

    /// Preformatted text (a command's text report, whole).
    pub(crate) fn preformatted(&mut self, text: &str) {
        let _ = writeln!(self.body, "<pre>{}</pre>", escape(text));
    }

    /// The page.
    pub fn finish(self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\
             <style>{STYLE}</style></head><body>\n{}</body></html>\n",
            escape(&self.title),
            self.body
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_text_is_escaped() {
        let mut d = Document::new("<script>x</script>");
        d.paragraph("a & b");
        d.facts(&[("k\"".into(), "<v>".into())]);
        d.table(
            &["<h>"],
            vec![vec!["1.5".into(), Cell("<x>".into(), Tone::Bad)]],
        );
        d.verdict("<ok>", "d", Tone::Good);
        let page = d.finish();
        assert!(!page.contains("<script>") && !page.contains("<v>") && !page.contains("<x>"));
        assert!(page.contains("&lt;script&gt;") && page.contains("a &amp; b"));
        assert!(page.contains(r#"<td class="num">1.5</td>"#), "{page}");
        assert!(page.contains(r#"<div id="verdict" class="verdict good">&lt;ok&gt;<div"#));
        // Self-contained: nothing fetched.
        assert!(!page.contains("http://") && !page.contains("https://") && !page.contains("src="));
    }
}
