//! The paper's symbols for the case parameters and the measured quantities,
//! the words every table, legend and axis of this crate uses.
use solver::case::PARAMETERS;

/// l bar k, the knot's dimensionless tightness (L - l_c) / h (paper eq. 11).
pub const L_K_BAR: &str = "l̄_k";
/// F bar = F h² / EI, the dimensionless pulling force.
pub const F_BAR: &str = "F̄";
/// H bar = H / W, the loop's height over its width.
pub const H_BAR: &str = "H̄";

/// The paper's symbol of a case parameter (its name for those without one).
pub fn symbol(name: &str) -> &str {
    match name {
        "mu" => "μ",
        "length" => "L",
        "youngs_modulus" => "E",
        "density" => "ρ",
        "poisson_ratio" => "ν",
        "nodes" => "K",
        "gravity" => "g",
        "dt" => "Δt",
        "pull_speed" => "v",
        other => other,
    }
}

/// A parameter's SI unit from the parameter table (empty for pure numbers).
pub fn unit(name: &str) -> &'static str {
    PARAMETERS.iter().find(|p| p.name == name).map_or("", |p| p.unit)
}

/// A parameter as a column or axis names it: symbol and SI unit, `h (m)`, `μ`.
pub fn column(name: &str) -> String {
    match unit(name) {
        "" => symbol(name).to_string(),
        u => format!("{} ({u})", symbol(name)),
    }
}

/// A parameter's value as legends and captions show it, with its unit in the
/// unit a figure uses (h in mm, as the paper's figures): `h = 1.6 mm`, `μ = 0.1`.
pub fn value(name: &str, v: &serde_json::Value) -> String {
    let Some(x) = v.as_f64() else {
        return format!(
            "{} = {}",
            symbol(name),
            v.as_str().map_or(v.to_string(), str::to_string)
        );
    };
    match (name, unit(name)) {
        ("h", _) => format!("h = {} mm", crate::charts::compact(x * 1e3)),
        (_, "") => format!("{} = {}", symbol(name), crate::charts::compact(x)),
        (_, u) => format!("{} = {} {u}", symbol(name), crate::charts::compact(x)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_carry_the_table_units() {
        assert_eq!(column("h"), "h (m)");
        assert_eq!(column("mu"), "μ");
        assert_eq!(column("youngs_modulus"), "E (Pa)");
        assert_eq!(value("h", &serde_json::json!(0.0016)), "h = 1.6 mm");
        assert_eq!(value("mu", &serde_json::json!(0.1)), "μ = 0.1");
        assert_eq!(value("material", &serde_json::json!("steel")), "material = steel");
    }
}
