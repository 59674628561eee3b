//! A report as one section model — a title, a summary, a preface and sections of headings,
//! paragraphs and tables — rendered three ways: plain text for a terminal, Markdown
//! (CommonMark with tables) and HTML. Each block says whom it reaches ([`Reach`]): the detail a
//! file carries (every candidate's score) stays out of the terminal, and a terminal's
//! condensed view (the worst regimes per joint) out of the files.

use std::fmt::Write as _;

/// A run of inline text.
#[derive(Clone, Debug, PartialEq)]
pub enum Span {
    /// Text as it is.
    Plain(String),
    /// A name or a value set in code type (a kind, a body, a file).
    Code(String),
    /// Text in italics (a reference to another section).
    Emphasis(String),
    /// Strongly emphasised text.
    Strong(String),
}

/// Inline text: spans in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Text(pub Vec<Span>);

impl Text {
    /// Plain text.
    pub fn plain(s: impl Into<String>) -> Self {
        Text(vec![Span::Plain(s.into())])
    }

    /// This text, then `span`.
    fn then(mut self, span: Span) -> Self {
        self.0.push(span);
        self
    }

    /// This text, then `s` as it is.
    pub fn and(self, s: impl Into<String>) -> Self {
        self.then(Span::Plain(s.into()))
    }

    /// This text, then `s` in code type.
    pub fn code(self, s: impl Into<String>) -> Self {
        self.then(Span::Code(s.into()))
    }

    /// This text, then `s` in italics.
    pub fn emphasis(self, s: impl Into<String>) -> Self {
        self.then(Span::Emphasis(s.into()))
    }

    /// This text, then `s` strongly emphasised.
    pub fn strong(self, s: impl Into<String>) -> Self {
        self.then(Span::Strong(s.into()))
    }

    /// The text without marks.
    pub fn to_plain(&self) -> String {
        self.0
            .iter()
            .map(|s| match s {
                Span::Plain(t) | Span::Code(t) | Span::Emphasis(t) | Span::Strong(t) => t.as_str(),
            })
            .collect()
    }

    /// The text as Markdown (a code span fenced with more backticks than it holds).
    pub fn to_markdown(&self) -> String {
        let mut out = String::new();
        for span in &self.0 {
            match span {
                Span::Plain(t) => out += t,
                Span::Code(t) => {
                    let fence = "`".repeat(longest_run(t, '`') + 1);
                    let pad = if t.starts_with('`') || t.ends_with('`') {
                        " "
                    } else {
                        ""
                    };
                    let _ = write!(out, "{fence}{pad}{t}{pad}{fence}");
                }
                Span::Emphasis(t) => {
                    let _ = write!(out, "*{t}*");
                }
                Span::Strong(t) => {
                    let _ = write!(out, "**{t}**");
                }
            }
        }
        out
    }

    /// The text as HTML, escaped.
    pub fn to_html(&self) -> String {
        self.0
            .iter()
            .map(|s| match s {
                Span::Plain(t) => escape_html(t),
                Span::Code(t) => format!("<code>{}</code>", escape_html(t)),
                Span::Emphasis(t) => format!("<em>{}</em>", escape_html(t)),
                Span::Strong(t) => format!("<strong>{}</strong>", escape_html(t)),
            })
            .collect()
    }
}

impl From<String> for Text {
    fn from(s: String) -> Self {
        Text::plain(s)
    }
}

impl From<&str> for Text {
    fn from(s: &str) -> Self {
        Text::plain(s)
    }
}

/// The longest run of `c` in `s`.
fn longest_run(s: &str, c: char) -> usize {
    let (mut longest, mut run) = (0, 0);
    for x in s.chars() {
        run = if x == c { run + 1 } else { 0 };
        longest = longest.max(run);
    }
    longest
}

/// A table: a header and rows of cells, every row as wide as the header.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Table {
    /// Column titles.
    pub header: Vec<String>,
    /// Rows of cells.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table with these column titles.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            rows: vec![],
        }
    }

    /// The table as HTML, every cell escaped.
    pub fn to_html(&self) -> String {
        let cells = |row: &[String], tag: &str| -> String {
            row.iter()
                .map(|c| format!("<{tag}>{}</{tag}>", escape_html(c)))
                .collect()
        };
        let mut out = format!(
            "<table>\n<thead>\n<tr>{}</tr>\n</thead>\n<tbody>\n",
            cells(&self.header, "th")
        );
        for row in &self.rows {
            let _ = writeln!(out, "<tr>{}</tr>", cells(row, "td"));
        }
        out + "</tbody>\n</table>\n"
    }

    /// Appends a row (as wide as the header).
    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        let row: Vec<String> = cells.into_iter().map(Into::into).collect();
        debug_assert_eq!(row.len(), self.header.len(), "a row as wide as its header");
        self.rows.push(row);
    }
}

/// A block of a section.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// A sub-heading.
    Heading(Text),
    /// A paragraph.
    Paragraph(Text),
    /// A table.
    Table(Table),
}

/// Whom a block reaches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reach {
    /// The terminal and the files.
    Everywhere,
    /// The terminal only (a condensed view of what the files tabulate in full).
    Terminal,
    /// The files only (Markdown, HTML): detail a terminal reader does not scroll through.
    Files,
}

/// A titled section of blocks.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// The section's title.
    pub title: String,
    /// Its blocks in order, each with whom it reaches.
    pub blocks: Vec<(Reach, Block)>,
}

impl Section {
    /// An empty section.
    pub fn new(title: impl Into<String>) -> Self {
        Section {
            title: title.into(),
            blocks: vec![],
        }
    }

    /// Appends a block for every reader.
    pub fn push(&mut self, block: Block) {
        self.blocks.push((Reach::Everywhere, block));
    }

    /// Appends a block for the files only.
    pub fn detail(&mut self, block: Block) {
        self.blocks.push((Reach::Files, block));
    }

    /// Appends a block for the terminal only.
    pub fn terminal(&mut self, block: Block) {
        self.blocks.push((Reach::Terminal, block));
    }

    /// The blocks that reach the files (or, with `terminal`, the terminal).
    fn reaching(&self, terminal: bool) -> impl Iterator<Item = &Block> {
        self.blocks
            .iter()
            .filter(move |(r, _)| match r {
                Reach::Everywhere => true,
                Reach::Terminal => terminal,
                Reach::Files => !terminal,
            })
            .map(|(_, b)| b)
    }
}

/// A report: a title, the one-sentence summary, a preface and the sections.
#[derive(Clone, Debug, PartialEq)]
pub struct Document {
    /// The title.
    pub title: String,
    /// The summary: first in the files, last on a terminal (where it stays in view).
    pub summary: String,
    /// What precedes the sections (the data and the model the report is about).
    pub preface: Text,
    /// The sections.
    pub sections: Vec<Section>,
}

impl Document {
    /// The report as Markdown: the title, the summary in bold, the preface, then each section
    /// under a `##` title; blocks apart by a blank line.
    pub fn markdown(&self) -> String {
        let mut blocks = vec![
            format!("# {}", self.title),
            format!("**{}**", self.summary),
            self.preface.to_markdown(),
        ];
        for section in &self.sections {
            blocks.push(format!("## {}", section.title));
            blocks.extend(section.reaching(false).map(markdown_block));
        }
        blocks.join("\n\n") + "\n"
    }

    /// The report as plain text for a terminal: the title and preface, each section under its title in
    /// capitals (paragraphs indented by two, tables by four, columns aligned), the summary
    /// last.
    pub fn text(&self) -> String {
        let mut out = format!("{}\n{}\n", self.title, self.preface.to_plain());
        for section in &self.sections {
            let _ = write!(out, "\n{}\n", section.title.to_uppercase());
            for block in section.reaching(true) {
                out += &text_block(block);
            }
        }
        let _ = writeln!(out, "\n{}", self.summary);
        out
    }

    /// The sections as HTML, each folded (`<details>`) under its title; the title, summary and
    /// preface are the page's to place.
    pub fn html_sections(&self) -> String {
        let mut out = String::new();
        for section in &self.sections {
            let _ = writeln!(
                out,
                "<details>\n<summary>{}</summary>",
                escape_html(&section.title)
            );
            for block in section.reaching(false) {
                out += &html_block(block);
            }
            out += "</details>\n";
        }
        out
    }
}

/// A block as Markdown, without a trailing line break.
fn markdown_block(block: &Block) -> String {
    match block {
        Block::Heading(t) => format!("### {}", t.to_markdown()),
        Block::Paragraph(t) => t.to_markdown(),
        Block::Table(t) => {
            let line = |cells: &[String]| {
                let cells: Vec<String> = cells.iter().map(|c| super::md_cell(c)).collect();
                format!("| {} |", cells.join(" | "))
            };
            let mut lines = vec![line(&t.header)];
            lines.push(format!("|{}", "---|".repeat(t.header.len())));
            lines.extend(t.rows.iter().map(|r| line(r)));
            lines.join("\n")
        }
    }
}

/// A block as indented plain text, ending in a line break.
fn text_block(block: &Block) -> String {
    match block {
        Block::Heading(t) | Block::Paragraph(t) => format!("  {}\n", t.to_plain()),
        Block::Table(t) => aligned(t, "    "),
    }
}

/// A table as plain text: each column as wide as its widest cell, a column of numbers (and its
/// title) to the right.
fn aligned(t: &Table, indent: &str) -> String {
    let width = |c: &String| c.chars().count();
    let columns: Vec<(usize, bool)> = (0..t.header.len())
        .map(|k| {
            let cells = || t.rows.iter().filter_map(|r| r.get(k));
            let widest = cells().chain([&t.header[k]]).map(width).max().unwrap_or(0);
            let numeric = !t.rows.is_empty() && cells().all(|c| c.is_empty() || is_number(c));
            (widest, numeric)
        })
        .collect();
    let line = |cells: &[String]| {
        let cells: Vec<String> = cells
            .iter()
            .zip(&columns)
            .map(|(c, &(w, right))| {
                if right {
                    format!("{c:>w$}")
                } else {
                    format!("{c:<w$}")
                }
            })
            .collect();
        format!("{indent}{}", cells.join("  ").trim_end())
    };
    let mut out = String::new();
    for row in std::iter::once(&t.header).chain(&t.rows) {
        out += &line(row);
        out += "\n";
    }
    out
}

/// Whether a cell reads as a number (with an optional unit of percent).
fn is_number(cell: &str) -> bool {
    cell.trim_end_matches('%')
        .trim()
        .parse::<f64>()
        .is_ok_and(f64::is_finite)
}

/// A block as HTML.
fn html_block(block: &Block) -> String {
    match block {
        Block::Heading(t) => format!("<h3>{}</h3>\n", t.to_html()),
        Block::Paragraph(t) => format!("<p>{}</p>\n", t.to_html()),
        Block::Table(t) => t.to_html(),
    }
}

/// Text escaped for HTML.
pub fn escape_html(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Document {
        let mut s = Section::new("Where");
        s.push(Block::Paragraph(
            Text::plain("The residual of ")
                .code("a|b")
                .and(" is ")
                .strong("large"),
        ));
        let mut t = Table::new(["joint", "RMS"]);
        t.row(["j|1", "0.125"]);
        t.row(["j2", "12.5"]);
        s.detail(Block::Table(t));
        s.terminal(Block::Heading("worst <joint>".into()));
        Document {
            title: "Diagnosis of r".into(),
            summary: "Explained.".into(),
            preface: "2 joints.".into(),
            sections: vec![s],
        }
    }

    #[test]
    fn markdown_carries_the_files_blocks_with_cells_escaped() {
        let md = sample().markdown();
        assert_eq!(
            md,
            "# Diagnosis of r\n\n**Explained.**\n\n2 joints.\n\n## Where\n\nThe residual of `a|b` is **large**\n\n| joint | RMS |\n|---|---|\n| j\\|1 | 0.125 |\n| j2 | 12.5 |\n"
        );
    }

    #[test]
    fn text_carries_the_terminal_blocks_aligned_and_the_summary_last() {
        let text = sample().text();
        assert_eq!(
            text,
            "Diagnosis of r\n2 joints.\n\nWHERE\n  The residual of a|b is large\n  worst <joint>\n\nExplained.\n"
        );
        let mut t = Table::new(["joint", "RMS"]);
        t.row(["j1", "0.125"]);
        t.row(["shoulder", "12.5"]);
        assert_eq!(
            aligned(&t, ""),
            "joint       RMS\nj1        0.125\nshoulder   12.5\n"
        );
    }

    #[test]
    fn html_escapes_and_folds_each_section() {
        let html = sample().html_sections();
        assert!(html.starts_with("<details>\n<summary>Where</summary>\n"));
        assert!(html.contains("<code>a|b</code> is <strong>large</strong>"));
        assert!(html.contains("<td>j|1</td><td>0.125</td>"));
        assert!(!html.contains("worst"), "a terminal block in the files");
        assert!(html.ends_with("</details>\n"));
    }

    #[test]
    fn a_code_span_holding_backticks_is_fenced_with_more() {
        let t = Text::plain("x ").code("a`b").and(" ").code("`c");
        assert_eq!(t.to_markdown(), "x ``a`b`` `` `c ``");
    }
}
