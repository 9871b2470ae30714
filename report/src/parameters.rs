//! docs/API.md's section on the case parameters: the table
//! `solver::case::PARAMETERS` as markdown, and the named materials
//! (`solver::case::MATERIALS`).
use crate::markdown::{left, table};
use solver::case::{MATERIALS, PARAMETERS};

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
    let materials = MATERIALS.iter().map(|m| {
        [
            format!("`{}`", m.name),
            format!("{:e}", m.youngs_modulus),
            m.density.to_string(),
            m.poisson_ratio.to_string(),
            format!("{:.3}", 1.0 / (1.0 + m.poisson_ratio)),
            m.source.to_string(),
        ]
    });
    intro
        + &table(
            &left(&["field", "unit", "default", "range", "paper", "meaning"]),
            rows,
        )
        + "\n### Materials\n\n\
           The named materials of the web form's picker, the `material` grid axis and the `materials` preset \
           (`GET /api/materials`). Inversion does not depend on E or rho (docs/FIDELITY.md, \"Any rod\"); nu does \
           change it: it sets the twisting stiffness GJ/EI = 1/(1 + nu).\n\n"
        + &table(
            &left(&["name", "E (Pa)", "rho (kg/m^3)", "nu", "GJ/EI", "source"]),
            materials,
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
