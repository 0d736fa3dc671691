//! The page's pieces: escaping, tables, sections and the stylesheet. The page is built as a
//! string; every text that comes from a file (names, devices, free-form settings) goes through
//! [`esc`].

use std::fmt::Write as _;

/// `s` safe as HTML text or an attribute value.
pub(crate) fn esc(s: &str) -> String {
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

/// A table: a header row, then rows; cells are HTML already (escape text with [`esc`]).
pub(crate) fn table(head: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::from("<table><thead><tr>");
    for h in head {
        let _ = write!(s, "<th>{h}</th>");
    }
    s.push_str("</tr></thead><tbody>");
    for r in rows {
        s.push_str("<tr>");
        for c in r {
            let _ = write!(s, "<td>{c}</td>");
        }
        s.push_str("</tr>");
    }
    s.push_str("</tbody></table>");
    s
}

/// A two-column table of names and values.
pub(crate) fn facts(rows: &[(&str, String)]) -> String {
    let mut s = String::from("<table class=\"facts\"><tbody>");
    for (k, v) in rows {
        let _ = write!(s, "<tr><th>{k}</th><td>{v}</td></tr>");
    }
    s.push_str("</tbody></table>");
    s
}

/// A section with its id, heading and body.
pub(crate) fn section(id: &str, title: &str, body: &str) -> String {
    format!("<section id=\"{id}\"><h2>{title}</h2>{body}</section>\n")
}

/// A note saying what was not measured and which flag would measure it.
pub(crate) fn not_measured(what: &str, how: &str) -> String {
    format!("<p class=\"missing\">Not measured: {what}. {how}</p>")
}

/// A figure: an inline SVG and its caption.
pub(crate) fn figure(svg: &str, caption: &str) -> String {
    format!("<figure>{svg}<figcaption>{caption}</figcaption></figure>")
}

/// The whole page.
pub(crate) fn page(title: &str, header: &str, toc: &[(&str, &str)], body: &str) -> String {
    let mut nav = String::from("<nav><ol>");
    for (id, t) in toc {
        let _ = write!(nav, "<li><a href=\"#{id}\">{t}</a></li>");
    }
    nav.push_str("</ol></nav>");
    format!(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
         <title>{title}</title><style>{STYLE}</style></head>\n<body>\n<header>{header}</header>\n{nav}\n<main>\n{body}</main>\n</body></html>\n",
        title = esc(title)
    )
}

/// Screen and print: A4 portrait, figures and tables kept whole on a page. Contact maps take a
/// row each: their text is sized for the SVG's own width (up to 960 units), so a half-page
/// column (90 mm) printed its 12-unit labels at 3.2 pt, the full 182 mm prints them at 6.5 pt.
const STYLE: &str = "\
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;color:#222;max-width:960px;margin:0 auto;padding:16px;line-height:1.4}\
header h1{margin:0 0 4px;font-size:1.6em}header p{margin:0;color:#555}\
nav ol{columns:2;font-size:.9em;margin:12px 0}\
h2{border-bottom:2px solid #1f77b4;padding-bottom:2px;margin-top:28px;font-size:1.25em}\
table{border-collapse:collapse;margin:8px 0;font-size:.92em}\
th,td{border:1px solid #ccc;padding:3px 8px;text-align:left;vertical-align:top}\
td.num,th.num{text-align:right;font-variant-numeric:tabular-nums}\
table.facts th{background:#f4f6f8;font-weight:600;width:34%}\
thead th{background:#f4f6f8}\
figure{margin:10px 0;break-inside:avoid}figure svg{max-width:100%;height:auto;border:1px solid #ddd}\
figcaption{font-size:.85em;color:#444}\
.plots{display:grid;grid-template-columns:1fr 1fr;gap:10px}.plots.maps{grid-template-columns:1fr}\
.fill{color:#666}\
.missing{color:#8a5a00;background:#fff7e6;border-left:4px solid #f0a500;padding:4px 8px}\
.warn{color:#8a1f11;background:#fdecea;border-left:4px solid #d62728;padding:4px 8px;margin:4px 0}\
.ok{color:#1b5e20;background:#e8f5e9;border-left:4px solid #2e7d32;padding:4px 8px}\
@media print{body{max-width:none;padding:0;font-size:10pt}nav{display:none}section{break-inside:auto}\
h2{break-after:avoid}table,figure{break-inside:avoid}.plots{grid-template-columns:1fr 1fr}}\
@page{size:A4;margin:14mm}";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_from_files_cannot_make_markup() {
        assert_eq!(esc(r#"<img src=x onerror="a">&'"#), "&lt;img src=x onerror=&quot;a&quot;&gt;&amp;&#39;");
    }

    #[test]
    fn a_table_has_its_head_and_rows() {
        let t = table(&["a", "b"], &[vec!["1".into(), "2".into()]]);
        assert_eq!(
            t,
            "<table><thead><tr><th>a</th><th>b</th></tr></thead><tbody><tr><td>1</td><td>2</td></tr></tbody></table>"
        );
    }
}
