//! Material and cross-section: E, nu -> G = E / (2 (1 + nu)) and the rod
//! stiffnesses EA, EI = (pi/4) E h^4, GJ of a circular section (paper Sec. 2, eq. 11).
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Isotropic elastic material. Defaults are the paper's: E = 1.8 MPa, nu = 0.5,
/// and the density of the paper's code, rho = 1000 kg/m^3.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio nu.
    pub poisson_ratio: f64,
    /// Mass density rho (kg/m^3).
    pub density: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            youngs_modulus: 1.8e6,
            poisson_ratio: 0.5,
            density: 1000.0,
        }
    }
}

impl Material {
    /// Shear modulus G = E / (2 (1 + nu)).
    pub fn shear_modulus(&self) -> f64 {
        self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))
    }
}

/// Stiffnesses and inertias of a rod with a circular cross-section of radius h.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Section {
    /// Cross-section radius h (m).
    pub radius: f64,
    /// Stretching stiffness EA (N).
    pub ea: f64,
    /// Bending stiffness EI = (pi/4) E h^4 (N m^2), eq. (11).
    pub ei: f64,
    /// Twisting stiffness GJ with J = (pi/2) h^4 (N m^2).
    pub gj: f64,
    /// Mass per unit length rho A (kg/m).
    pub linear_density: f64,
    /// Rotational inertia about the axis per unit length, rho A h^2 / 2 (kg m).
    pub polar_inertia: f64,
}

impl Section {
    /// Section of a circular rod of radius `radius` made of `material`.
    pub fn circular(material: &Material, radius: f64) -> Self {
        let area = PI * radius * radius;
        let second_moment = PI * radius.powi(4) / 4.0;
        Self {
            radius,
            ea: material.youngs_modulus * area,
            ei: material.youngs_modulus * second_moment,
            gj: material.shear_modulus() * 2.0 * second_moment,
            linear_density: material.density * area,
            polar_inertia: material.density * area * radius * radius / 2.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_values() {
        let m = Material::default();
        assert!((m.shear_modulus() - 0.6e6).abs() < 1e-6);
        let s = Section::circular(&m, 1.6e-3);
        let ei = PI / 4.0 * 1.8e6 * 1.6e-3f64.powi(4);
        assert!((s.ei - ei).abs() < 1e-15 * ei.max(1.0));
        assert!((s.gj / s.ei - 2.0 / 3.0).abs() < 1e-12);
    }
}
