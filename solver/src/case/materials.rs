//! Named materials: textbook Young's modulus, density and Poisson's ratio of
//! the rods knots are tied in, for the web form's picker and the `materials`
//! preset.
use serde::Serialize;

/// A material's elastic constants and where they come from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NamedMaterial {
    pub name: &'static str,
    /// Young's modulus E (Pa), density rho (kg/m^3), Poisson's ratio nu.
    pub youngs_modulus: f64,
    pub density: f64,
    pub poisson_ratio: f64,
    /// What the rod is and the source of its constants.
    pub source: &'static str,
}

/// Rubber (the paper's), silicone, nylon, nitinol and steel.
pub const MATERIALS: &[NamedMaterial] = &[
    NamedMaterial {
        name: "rubber",
        youngs_modulus: 1.8e6,
        density: 1000.0,
        poisson_ratio: 0.5,
        source: "The paper's rubber rod: E = 1.8 MPa, nu = 0.5 (incompressible) from its Sec. 4, rho = 1000 kg/m^3 \
                 from its code.",
    },
    NamedMaterial {
        name: "silicone",
        youngs_modulus: 1.25e6,
        density: 1160.0,
        poisson_ratio: 0.5,
        source: "Vinyl polysiloxane (VPS, e.g. Zhermack Elite Double 32), cast into the rods of knot and filament \
                 experiments: E about 1.25 MPa and rho about 1160 kg/m^3 as reported for that grade (measure your \
                 batch); nu = 0.5, incompressible.",
    },
    NamedMaterial {
        name: "nylon",
        youngs_modulus: 3.0e9,
        density: 1140.0,
        poisson_ratio: 0.4,
        source: "Nylon 6,6 monofilament (fishing line): E = 1.6-3.8 GPa, rho = 1140 kg/m^3, nu = 0.39 (Callister & \
                 Rethwisch, Materials Science and Engineering, Appendix B); 3 GPa for drawn line.",
    },
    NamedMaterial {
        name: "nitinol",
        youngs_modulus: 7.5e10,
        density: 6450.0,
        poisson_ratio: 0.33,
        source: "Superelastic NiTi wire, austenite: E = 70-83 GPa, rho = 6450 kg/m^3, nu = 0.33 (ASM Handbook \
                 vol. 2, Shape Memory Alloys; ASTM F2063).",
    },
    NamedMaterial {
        name: "steel",
        youngs_modulus: 2.0e11,
        density: 7850.0,
        poisson_ratio: 0.3,
        source: "Spring (music) steel wire: E = 200-207 GPa, rho = 7850 kg/m^3, nu = 0.30 (Callister & Rethwisch, \
                 Appendix B, plain carbon steel; ASTM A228).",
    },
];

/// The material called `name`.
pub fn material(name: &str) -> Option<&'static NamedMaterial> {
    MATERIALS.iter().find(|m| m.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::case::CaseParams;

    /// The first material is the paper's rod, the defaults' material; every
    /// material's constants lie in the parameter table's ranges.
    #[test]
    fn the_table_starts_with_the_papers_rod_and_fits_the_ranges() {
        let d = CaseParams::default();
        let rubber = MATERIALS[0];
        assert_eq!(
            (rubber.youngs_modulus, rubber.density, rubber.poisson_ratio),
            (d.youngs_modulus, d.density, d.poisson_ratio)
        );
        for m in MATERIALS {
            let p = CaseParams {
                youngs_modulus: m.youngs_modulus,
                density: m.density,
                poisson_ratio: m.poisson_ratio,
                ..CaseParams::default()
            };
            assert_eq!(p.range_errors(), vec![], "{}", m.name);
            assert_eq!(material(m.name), Some(m));
        }
    }
}
