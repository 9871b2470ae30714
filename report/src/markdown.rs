//! Markdown tables, the one form every generated document's tables take.

/// How a column's cells line up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Align {
    Left,
    Right,
}

/// A table of `columns` (heading and alignment) over `rows` (one cell per
/// column), followed by a blank line. Pipes in cells are escaped and an empty
/// cell shows a dash.
pub fn table<R>(columns: &[(&str, Align)], rows: impl IntoIterator<Item = R>) -> String
where
    R: IntoIterator,
    R::Item: AsRef<str>,
{
    let line = |cells: Vec<String>| format!("| {} |\n", cells.join(" | "));
    let mut out = line(columns.iter().map(|(heading, _)| heading.to_string()).collect());
    out.push_str(&line(
        (columns.iter())
            .map(|(_, align)| match align {
                Align::Left => "---".to_string(),
                Align::Right => "---:".to_string(),
            })
            .collect(),
    ));
    for row in rows {
        out.push_str(&line(row.into_iter().map(|c| cell(c.as_ref())).collect()));
    }
    out.push('\n');
    out
}

/// Left-aligned columns of these headings.
pub fn left<'a>(headings: &[&'a str]) -> Vec<(&'a str, Align)> {
    headings.iter().map(|h| (*h, Align::Left)).collect()
}

/// Right-aligned (numeric) columns of these headings.
pub fn right<'a>(headings: &[&'a str]) -> Vec<(&'a str, Align)> {
    headings.iter().map(|h| (*h, Align::Right)).collect()
}

/// A table cell: pipes escaped, an empty cell as a dash.
fn cell(text: &str) -> String {
    if text.is_empty() {
        "-".to_string()
    } else {
        text.replace('|', "\\|")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_has_its_header_alignment_rows_and_a_blank_line() {
        let t = table(
            &[("name", Align::Left), ("value", Align::Right)],
            [vec!["a|b", "1"], vec!["", "2"]],
        );
        assert_eq!(
            t,
            "| name | value |\n| --- | ---: |\n| a\\|b | 1 |\n| - | 2 |\n\n"
        );
    }
}
