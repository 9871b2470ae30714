//! docs/API.md's section on the case parameters: the table
//! `solver::case::PARAMETERS` as markdown.
use solver::case::PARAMETERS;

/// The heading that opens the section in docs/API.md.
pub const HEADING: &str = "## Case parameters (`CaseParams`)";

/// The section, from its heading to the blank line after the table.
pub fn parameters_section() -> String {
    let mut text = format!(
        "{HEADING}\n\n\
         Generated from `solver::case::PARAMETERS`, the table the CLI's flags, the OpenAPI schema and the web form \
         are made from and `CaseParams::validate` checks (`UPDATE_DOCS=1 cargo test -p knotsweep-report --test \
         api_doc` rewrites this section). Every field is optional; SI units. A value out of its range is a 422 naming \
         the field and the reason.\n\n\
         | field | unit | default | range | paper | meaning |\n\
         | --- | --- | --- | --- | --- | --- |\n"
    );
    for p in PARAMETERS {
        let meaning = match p.null {
            Some(null) => format!("{} null: {null}.", p.doc),
            None => p.doc.to_string(),
        };
        let cells = [
            format!("`{}`", p.name),
            p.unit.to_string(),
            format!("`{}`", p.default),
            p.range_text(),
            p.paper.to_string(),
            meaning,
        ];
        let cells: Vec<String> = cells.iter().map(|c| cell(c)).collect();
        text.push_str(&format!("| {} |\n", cells.join(" | ")));
    }
    text.push('\n');
    text
}

/// A table cell: pipes escaped, empty cells as a dash.
fn cell(text: &str) -> String {
    if text.is_empty() {
        "-".to_string()
    } else {
        text.replace('|', "\\|")
    }
}

/// `document` with its parameter section (from [`HEADING`] to the next
/// `## ` heading) replaced by `section`; `None` without the heading.
pub fn with_section(document: &str, section: &str) -> Option<String> {
    let start = document.find(HEADING)?;
    let end = document[start + HEADING.len()..]
        .find("\n## ")
        .map_or(document.len(), |i| start + HEADING.len() + i + 1);
    Some(format!("{}{section}{}", &document[..start], &document[end..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_section_is_replaced_up_to_the_next_heading() {
        let doc = format!("# API\n\n{HEADING}\n\nold\n\n## Limits\n\nx\n");
        assert_eq!(
            with_section(&doc, &format!("{HEADING}\n\nnew\n\n")).unwrap(),
            format!("# API\n\n{HEADING}\n\nnew\n\n## Limits\n\nx\n")
        );
        assert!(with_section("# API\n", "").is_none());
    }

    #[test]
    fn every_parameter_has_a_row() {
        let section = parameters_section();
        for p in PARAMETERS {
            assert!(section.contains(&format!("| `{}` |", p.name)), "{}", p.name);
        }
    }
}
