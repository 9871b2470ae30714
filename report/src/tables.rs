//! Phase diagrams as tables: the CSV beside the phase diagram's JSON
//! (`GET /api/sweeps/{id}/phase-diagram.csv`, `knotsweep sweep --csv`), one
//! row per point, columns named by the paper's symbols with their units.
use crate::symbols::{self, F_BAR, H_BAR, L_K_BAR};
use serde_json::Value;
use std::fmt::Write;

/// The columns after the varied parameters: the header's words and where each
/// value sits in a point of the phase diagram's JSON.
const COLUMNS: [(&str, &[&str]); 11] = [
    (L_K_BAR, &["inversion", "l_k_bar"]),
    ("δl̄_k", &["uncertainty", "absolute"]),
    ("converged", &["uncertainty", "converged"]),
    ("l_c/L", &["inversion", "l_c_over_L"]),
    ("F̄ before", &["inversion", "F_bar_before"]),
    ("F̄ after", &["inversion", "F_bar_after"]),
    ("H̄ before", &["inversion", "H_bar_before"]),
    ("H̄ after", &["inversion", "H_bar_after"]),
    ("kinetic energy ratio", &["inversion", "kinetic_energy_ratio"]),
    ("simplified l̄_k", &["simplified_l_k_bar"]),
    ("flip back l̄_k", &["hysteresis", "flip_back_l_k_bar"]),
];

/// The phase diagram (the JSON of `GET /api/sweeps/{id}/phase-diagram`) as
/// CSV: `case`, the varied parameters (symbol and SI unit: `h (m)`, `μ`),
/// `status`, the inversion (l̄_k, its certified uncertainty δl̄_k, l_c/L, F̄
/// and H̄ around it), the simplified model's l̄_k, the flip back, every event
/// and the reason a point has no inversion. Numbers are written as the JSON
/// holds them (shortest round trip), empty where the JSON has null.
pub fn phase_diagram_csv(pd: &Value) -> String {
    let varied: Vec<&str> = pd["varied"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(Value::as_str)
        .collect();
    let mut header: Vec<String> = vec!["case".to_string()];
    header.extend(varied.iter().map(|v| symbols::column(v)));
    header.push("status".to_string());
    header.extend(COLUMNS.iter().map(|(name, _)| name.to_string()));
    header.extend(["events".to_string(), "reason".to_string()]);
    let mut out = String::new();
    row(&mut out, header);
    for point in pd["points"].as_array().into_iter().flatten() {
        let mut cells = vec![cell(&point["case_id"])];
        cells.extend(varied.iter().map(|v| cell(&point["params"][*v])));
        cells.push(cell(&point["status"]));
        cells.extend(
            COLUMNS
                .iter()
                .map(|(_, path)| cell(path.iter().fold(point, |v, key| &v[*key]))),
        );
        cells.push(events(&point["events"]));
        cells.push(cell(&point["reason"]));
        row(&mut out, cells);
    }
    out
}

/// A JSON value as a cell: numbers and words as they are, empty for null.
fn cell(v: &Value) -> String {
    match v {
        Value::Null => String::new(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// A point's events in one cell: `inversion (tighten, stage 1) at l̄_k 129.3,
/// F̄ 0.8 → 0.2, H̄ 0.9 → 0.3, clean; ...`.
fn events(events: &Value) -> String {
    let mut text = String::new();
    for (k, e) in events.as_array().into_iter().flatten().enumerate() {
        if k > 0 {
            text.push_str("; ");
        }
        let number = |key: &str| e[key].as_f64().map_or(String::new(), crate::charts::compact);
        let _ = write!(
            text,
            "{} ({}, stage {}) at {L_K_BAR} {}, {F_BAR} {} → {}, {H_BAR} {} → {}, {}",
            cell(&e["kind"]),
            cell(&e["direction"]),
            e["stage"].as_u64().map_or(String::new(), |s| (s + 1).to_string()),
            number("l_k_bar"),
            number("F_bar_before"),
            number("F_bar_after"),
            number("H_bar_before"),
            number("H_bar_after"),
            if e["clean"] == Value::Bool(true) {
                "clean"
            } else {
                "not clean"
            },
        );
    }
    text
}

/// One CSV row (RFC 4180: a cell with a comma, quote or line break is quoted).
fn row(out: &mut String, cells: Vec<String>) {
    let quoted: Vec<String> = cells
        .into_iter()
        .map(|c| {
            if c.contains([',', '"', '\n', '\r']) {
                format!("\"{}\"", c.replace('"', "\"\""))
            } else {
                c
            }
        })
        .collect();
    out.push_str(&quoted.join(","));
    out.push_str("\r\n");
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A minimal RFC 4180 reader, independent of the writer's quoting.
    fn parse(text: &str) -> Vec<Vec<String>> {
        let (mut rows, mut row, mut cell, mut quoted) = (Vec::new(), Vec::new(), String::new(), false);
        let mut chars = text.chars().peekable();
        while let Some(c) = chars.next() {
            match (quoted, c) {
                (true, '"') if chars.peek() == Some(&'"') => {
                    chars.next();
                    cell.push('"');
                }
                (true, '"') => quoted = false,
                (true, c) => cell.push(c),
                (false, '"') => quoted = true,
                (false, ',') => row.push(std::mem::take(&mut cell)),
                (false, '\r') => {}
                (false, '\n') => {
                    row.push(std::mem::take(&mut cell));
                    rows.push(std::mem::take(&mut row));
                }
                (false, c) => cell.push(c),
            }
        }
        rows
    }

    #[test]
    fn one_row_per_point_and_the_json_numbers_back() {
        let pd = json!({
            "varied": ["h", "mu"],
            "points": [
                {"case_id": 4, "params": {"h": 0.0016, "mu": 0.1}, "status": "completed",
                 "inversion": {"l_k_bar": 120.93409012345678, "l_c_over_L": 0.61, "F_bar_before": 0.8,
                               "F_bar_after": 0.2, "H_bar_before": 0.9, "H_bar_after": 0.3,
                               "kinetic_energy_ratio": 40.5},
                 "reason": null, "simplified_l_k_bar": 110.5,
                 "uncertainty": {"absolute": 0.25, "converged": true},
                 "events": [{"stage": 0, "direction": "tighten", "kind": "inversion", "l_k_bar": 120.9,
                             "F_bar_before": 0.8, "F_bar_after": 0.2, "H_bar_before": 0.9,
                             "H_bar_after": 0.3, "clean": true}]},
                {"case_id": 5, "params": {"h": 0.0024, "mu": 0.1}, "status": "completed",
                 "inversion": null, "reason": "no inversion detected, \"at\" l_k bar 60",
                 "simplified_l_k_bar": null, "uncertainty": null, "events": []}
            ]
        });
        let rows = parse(&phase_diagram_csv(&pd));
        assert_eq!(rows.len(), 3, "header and one row per point");
        assert_eq!(rows[0][..4], ["case", "h (m)", "μ", "status"]);
        let at = |name: &str| rows[0].iter().position(|c| c == name).unwrap();
        for (row, point) in rows[1..].iter().zip(pd["points"].as_array().unwrap()) {
            assert_eq!(row.len(), rows[0].len());
            assert_eq!(
                row[at("h (m)")].parse::<f64>().unwrap(),
                point["params"]["h"].as_f64().unwrap()
            );
            let l_k: Option<f64> = row[at("l̄_k")].parse().ok();
            assert_eq!(l_k, point["inversion"]["l_k_bar"].as_f64());
            assert_eq!(row[at("reason")], cell(&point["reason"]));
        }
        assert_eq!(rows[1][at("δl̄_k")], "0.25");
        assert!(rows[1][at("events")].starts_with("inversion (tighten, stage 1) at l̄_k 120.9"));
    }
}
