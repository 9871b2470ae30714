//! docs/API.md's section on the case parameters: the table
//! `solver::case::PARAMETERS` as markdown.
use crate::markdown::{left, table};
use solver::case::PARAMETERS;

/// The heading that opens the section in docs/API.md.
pub const HEADING: &str = "## Case parameters (`CaseParams`)";

/// The section, from its heading to the blank line after the table.
pub fn parameters_section() -> String {
    let intro = format!(
        "{HEADING}\n\n\
         Generated from `solver::case::PARAMETERS`, the table the CLI's flags, the OpenAPI schema and the web form \
         are made from and `CaseParams::validate` checks (`UPDATE_DOCS=1 cargo test -p knotsweep-report --test \
         api_doc` rewrites this section). Every field is optional; SI units. A value out of its range is a 422 naming \
         the field and the reason.\n\n"
    );
    let rows = PARAMETERS.iter().map(|p| {
        let meaning = match p.null {
            Some(null) => format!("{} null: {null}.", p.doc),
            None => p.doc.to_string(),
        };
        [
            format!("`{}`", p.name),
            p.unit.to_string(),
            format!("`{}`", p.default),
            p.range_text(),
            p.paper.to_string(),
            meaning,
        ]
    });
    intro
        + &table(
            &left(&["field", "unit", "default", "range", "paper", "meaning"]),
            rows,
        )
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
