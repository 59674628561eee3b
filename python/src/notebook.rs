//! What a notebook shows for each result (`_repr_html_`): a fragment, never a page, its style
//! scoped to its own `div` so that nothing around it is restyled; the numbers with their units.

use physid::api::document::{escape_html, Table};

/// Style of every result but the diagnosis (which carries its report's own): scoped to
/// `div.physid-result`.
const CSS: &str = ".physid-result { font-family: sans-serif; font-size: 13px; }
.physid-result table { border-collapse: collapse; margin: 0.4em 0; }
.physid-result th, .physid-result td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
.physid-result th { background: #f2f2f2; }
.physid-result td:first-child, .physid-result th:first-child { text-align: left; }
.physid-result .facts { color: #333; margin: 0.2em 0 0.4em; }
";

/// A number as a table shows it: four significant figures, NaN and infinities as words.
pub(crate) fn number(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "–".into()
        } else {
            format!("{x}")
        };
    }
    if x == 0.0 || (1e-3..1e5).contains(&x.abs()) {
        let digits = (3 - x.abs().log10().floor() as i32).clamp(0, 6) as usize;
        format!("{x:.digits$}")
    } else {
        format!("{x:.3e}")
    }
}

/// An HTML table of `header` and `rows` (cells escaped).
pub(crate) fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut t = Table::new(header.iter().copied());
    rows.iter().for_each(|r| t.row(r.iter().cloned()));
    t.to_html()
}

/// A result's card: its `title` (the class and what it is about), a line of `facts`
/// (`name: value`), then `tables` (each with a caption).
pub(crate) fn card(title: &str, facts: &[(&str, String)], tables: &[(&str, String)]) -> String {
    let facts: Vec<String> = facts
        .iter()
        .map(|(k, v)| format!("{}: <b>{}</b>", escape_html(k), escape_html(v)))
        .collect();
    let tables: String = tables
        .iter()
        .map(|(caption, t)| format!("<div>{}</div>\n{t}", escape_html(caption)))
        .collect();
    format!(
        "<div class=\"physid-result\">\n<style>\n{CSS}</style>\n<b>{}</b>\n<div class=\"facts\">{}</div>\n{tables}</div>\n",
        escape_html(title),
        facts.join(" · ")
    )
}

/// The rows of a CSV text (as the library writes its tables: no quoted commas) as a table.
pub(crate) fn csv_table(csv: &str) -> String {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let rows: Vec<Vec<String>> = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().map_or(c.to_string(), number))
                .collect()
        })
        .collect();
    table(&header, &rows)
}
