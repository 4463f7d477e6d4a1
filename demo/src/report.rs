//! A small HTML page builder for the report.
//!
//! A [`Report`] is a title, intro paragraphs, a list of [`Section`]s and a footer. A section is a
//! heading followed by [`Block`]s: paragraphs, display formulas, figures with captions and small
//! tables. [`Report::write`] renders one self-contained `index.html` (inline CSS, no scripts);
//! figures are referenced by file names relative to it.
//!
//! Text passed to the builder is plain text: it is HTML-escaped, and `` `backticks` `` become
//! `<code>` spans, which is handy for formulas and identifiers.
//!
//! ```
//! use mcg_demo::report::{Report, Section, Table};
//!
//! let mut section = Section::new("example", "An example");
//! section
//!     .paragraph("The density is `p(x) = e^(−x)`.")
//!     .figure("example.png", "A chart drawn by the plot module.")
//!     .table(Table::new("Numbers", ["x", "p(x)"]).row(["1", "0.37"]));
//! let mut page = Report::new("Demo");
//! page.push_section(section);
//! let html = page.to_html();
//! assert!(html.contains("<code>p(x) = e^(−x)</code>"));
//! assert_eq!(page.figure_files().collect::<Vec<_>>(), ["example.png"]);
//! ```

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// File name of the page inside the output folder.
pub const INDEX_FILE: &str = "index.html";

/// The whole page.
#[derive(Clone, Debug, Default)]
pub struct Report {
    title: String,
    intro: Vec<Block>,
    sections: Vec<Section>,
    footer: Vec<String>,
}

/// One section: an anchor id, a heading and its content in order.
#[derive(Clone, Debug)]
pub struct Section {
    id: String,
    title: String,
    blocks: Vec<Block>,
}

/// A piece of content inside a section (or the intro).
#[derive(Clone, Debug)]
pub enum Block {
    /// A paragraph of plain text (escaped; `` `code` `` spans allowed).
    Paragraph(String),
    /// A display formula, shown centred in a monospace font.
    Formula(String),
    /// A sub-heading inside a section.
    Heading(String),
    /// An image file (relative to `index.html`) with a caption.
    Figure {
        /// File name relative to the output folder, e.g. `vmf-histograms.png`.
        file: String,
        /// Caption under the image (plain text like a paragraph).
        caption: String,
    },
    /// A small table.
    Table(Table),
}

/// A small table with a caption, a header row and body rows of text cells.
#[derive(Clone, Debug)]
pub struct Table {
    caption: String,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with a caption and column headers, no rows yet.
    pub fn new<S: Into<String>>(caption: &str, header: impl IntoIterator<Item = S>) -> Self {
        Self {
            caption: caption.to_owned(),
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row (builder style). Cells are plain text like paragraphs.
    #[must_use]
    pub fn row<S: Into<String>>(mut self, cells: impl IntoIterator<Item = S>) -> Self {
        self.push_row(cells);
        self
    }

    /// Appends a row in place.
    pub fn push_row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.rows.push(cells.into_iter().map(Into::into).collect());
    }

    fn render(&self, html: &mut String) {
        html.push_str("<table>\n");
        if !self.caption.is_empty() {
            let _ = writeln!(html, "<caption>{}</caption>", inline(&self.caption));
        }
        html.push_str("<thead><tr>");
        for cell in &self.header {
            let _ = write!(html, "<th>{}</th>", inline(cell));
        }
        html.push_str("</tr></thead>\n<tbody>\n");
        for row in &self.rows {
            html.push_str("<tr>");
            for cell in row {
                let _ = write!(html, "<td>{}</td>", inline(cell));
            }
            html.push_str("</tr>\n");
        }
        html.push_str("</tbody>\n</table>\n");
    }
}

impl Section {
    /// An empty section. `id` is the HTML anchor (letters, digits and `-`), `title` its heading.
    pub fn new(id: &str, title: &str) -> Self {
        Self {
            id: id.to_owned(),
            title: title.to_owned(),
            blocks: Vec::new(),
        }
    }

    /// The anchor id given to [`Section::new`].
    pub fn id(&self) -> &str {
        &self.id
    }

    /// Appends a paragraph of plain text.
    pub fn paragraph(&mut self, text: &str) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.to_owned()));
        self
    }

    /// Appends a display formula.
    pub fn formula(&mut self, text: &str) -> &mut Self {
        self.blocks.push(Block::Formula(text.to_owned()));
        self
    }

    /// Appends a sub-heading.
    pub fn heading(&mut self, text: &str) -> &mut Self {
        self.blocks.push(Block::Heading(text.to_owned()));
        self
    }

    /// Appends a figure: `file` relative to the output folder, and its caption.
    pub fn figure(&mut self, file: &str, caption: &str) -> &mut Self {
        self.blocks.push(Block::Figure {
            file: file.to_owned(),
            caption: caption.to_owned(),
        });
        self
    }

    /// Appends a table.
    pub fn table(&mut self, table: Table) -> &mut Self {
        self.blocks.push(Block::Table(table));
        self
    }

    /// The blocks in order.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }
}

impl Report {
    /// An empty page with a title.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.to_owned(),
            ..Self::default()
        }
    }

    /// Appends an intro paragraph (shown above the table of contents).
    pub fn paragraph(&mut self, text: &str) -> &mut Self {
        self.intro.push(Block::Paragraph(text.to_owned()));
        self
    }

    /// Appends a section.
    pub fn push_section(&mut self, section: Section) -> &mut Self {
        self.sections.push(section);
        self
    }

    /// Appends a line to the footer.
    pub fn footer(&mut self, text: &str) -> &mut Self {
        self.footer.push(text.to_owned());
        self
    }

    /// File names of all figures, in page order.
    pub fn figure_files(&self) -> impl Iterator<Item = &str> {
        self.intro
            .iter()
            .chain(self.sections.iter().flat_map(|s| &s.blocks))
            .filter_map(|block| match block {
                Block::Figure { file, .. } => Some(file.as_str()),
                _ => None,
            })
    }

    /// Renders the page as a complete HTML document.
    pub fn to_html(&self) -> String {
        let mut html = String::with_capacity(16 * 1024);
        let _ = write!(
            html,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>\n<h1>{}</h1>\n",
            escape(&self.title),
            escape(&self.title)
        );
        let mut figure_number = 0;
        for block in &self.intro {
            render_block(block, &mut html, &mut figure_number);
        }
        if !self.sections.is_empty() {
            html.push_str("<nav><h2>Contents</h2>\n<ol>\n");
            for section in &self.sections {
                let _ = writeln!(
                    html,
                    "<li><a href=\"#{}\">{}</a></li>",
                    escape(&section.id),
                    escape(&section.title)
                );
            }
            html.push_str("</ol>\n</nav>\n");
        }
        for section in &self.sections {
            let _ = writeln!(
                html,
                "<section id=\"{}\">\n<h2>{}</h2>",
                escape(&section.id),
                escape(&section.title)
            );
            for block in &section.blocks {
                render_block(block, &mut html, &mut figure_number);
            }
            html.push_str("</section>\n");
        }
        html.push_str("</main>\n");
        if !self.footer.is_empty() {
            html.push_str("<footer>\n");
            for line in &self.footer {
                let _ = writeln!(html, "<p>{}</p>", inline(line));
            }
            html.push_str("</footer>\n");
        }
        html.push_str("</body>\n</html>\n");
        html
    }

    /// Writes [`INDEX_FILE`] into `dir` and returns its path.
    pub fn write(&self, dir: &Path) -> std::io::Result<PathBuf> {
        let path = dir.join(INDEX_FILE);
        std::fs::write(&path, self.to_html())?;
        Ok(path)
    }
}

fn render_block(block: &Block, html: &mut String, figure_number: &mut usize) {
    match block {
        Block::Paragraph(text) => {
            let _ = writeln!(html, "<p>{}</p>", inline(text));
        }
        Block::Formula(text) => {
            let _ = writeln!(html, "<p class=\"formula\">{}</p>", escape(text));
        }
        Block::Heading(text) => {
            let _ = writeln!(html, "<h3>{}</h3>", inline(text));
        }
        Block::Figure { file, caption } => {
            *figure_number += 1;
            let _ = writeln!(
                html,
                "<figure>\n<a href=\"{file}\"><img src=\"{file}\" alt=\"Figure {n}\"></a>\n\
                 <figcaption><b>Figure {n}.</b> {caption}</figcaption>\n</figure>",
                file = escape(file),
                n = figure_number,
                caption = inline(caption)
            );
        }
        Block::Table(table) => table.render(html),
    }
}

/// Escapes `&`, `<`, `>` and `"` for use in HTML text and attribute values.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

/// Escapes `text` and turns `` `spans` `` into `<code>spans</code>`.
fn inline(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    for (i, part) in text.split('`').enumerate() {
        if i % 2 == 1 {
            let _ = write!(out, "<code>{}</code>", escape(part));
        } else {
            out.push_str(&escape(part));
        }
    }
    out
}

const STYLE: &str = "\
body{margin:0;background:#f6f7f9;color:#1d232b;font:16px/1.55 system-ui,-apple-system,'Segoe UI',Roboto,sans-serif}\
main{max-width:1100px;margin:0 auto;padding:24px 28px 8px;background:#fff;box-shadow:0 0 12px rgba(0,0,0,.06)}\
h1{margin-top:8px;font-size:1.9em}h2{margin-top:2em;border-bottom:1px solid #dde1e6;padding-bottom:4px}\
h3{margin-top:1.6em}nav ol{padding-left:1.4em}nav h2{margin-top:1em;border:none;font-size:1.1em}\
code,.formula{font-family:'DejaVu Sans Mono',Menlo,Consolas,monospace;font-size:.92em}\
code{background:#f0f2f5;padding:1px 4px;border-radius:3px}\
.formula{text-align:center;background:#f7f8fa;padding:10px;border-radius:4px;overflow-x:auto}\
figure{margin:1.2em 0;text-align:center}figure img{max-width:100%;height:auto;border:1px solid #e3e6ea}\
figcaption{text-align:left;font-size:.93em;color:#39424e;margin-top:6px}\
table{border-collapse:collapse;margin:1em auto;font-size:.93em}caption{caption-side:top;padding:4px;color:#39424e}\
th,td{border:1px solid #d5d9de;padding:4px 10px;text-align:right}th{background:#f0f2f5}\
td:first-child,th:first-child{text-align:left}\
footer{max-width:1100px;margin:0 auto;padding:8px 28px 24px;color:#5b6572;font-size:.9em}";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_code_spans_work() {
        assert_eq!(escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
        assert_eq!(inline("x `a<b` y"), "x <code>a&lt;b</code> y");
    }

    #[test]
    fn page_has_sections_figures_and_tables() {
        let mut section = Section::new("s1", "First");
        section
            .paragraph("hello")
            .figure("a.png", "cap")
            .table(Table::new("t", ["a", "b"]).row(["1", "2"]));
        let mut page = Report::new("T");
        page.paragraph("intro").push_section(section).footer("end");
        let html = page.to_html();
        for needle in [
            "<h1>T</h1>",
            "href=\"#s1\"",
            "<img src=\"a.png\"",
            "<td>1</td>",
            "Figure 1.",
            "<p>end</p>",
        ] {
            assert!(html.contains(needle), "{needle} missing from\n{html}");
        }
    }
}
