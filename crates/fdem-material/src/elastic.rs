//! Isotropic linear elasticity in plane strain.

use crate::{check, ParameterError};

/// Isotropic linear-elastic constants (plane strain, `ε_zz = 0`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Elastic {
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Poisson's ratio `ν` (−).
    pub poisson: f64,
    /// First Lamé constant `λ = E ν / ((1 + ν)(1 − 2ν))` (Pa).
    pub lambda: f64,
    /// Shear modulus `G = μ = E / (2(1 + ν))` (Pa).
    pub mu: f64,
}

impl Elastic {
    /// Elastic constants from `E` (Pa) and `ν`, checked: `E > 0`,
    /// `−1 < ν < 0.5`.
    pub fn new(young: f64, poisson: f64) -> Result<Self, ParameterError> {
        check("E", young, young > 0.0, "Young's modulus must be positive")?;
        check("nu", poisson, poisson > -1.0 && poisson < 0.5, "Poisson's ratio must lie in (-1, 0.5)")?;
        Ok(Self {
            young,
            poisson,
            lambda: young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)),
            mu: young / (2.0 * (1.0 + poisson)),
        })
    }

    /// P-wave modulus `λ + 2G` (Pa); the plane-strain P-wave speed is
    /// `√((λ + 2G)/ρ)`.
    pub fn p_wave_modulus(&self) -> f64 {
        self.lambda + 2.0 * self.mu
    }

    /// Plane-strain modulus `E' = E / (1 − ν²)` (Pa).
    pub fn plane_strain_modulus(&self) -> f64 {
        self.young / (1.0 - self.poisson * self.poisson)
    }

    /// Elastic trial stress `σ̂ + C : D̂ Δt` with `ε̂_zz = 0`:
    /// `Δσ_ii = λ tr(D̂) Δt + 2G D̂_ii Δt`, `Δσ_zz = λ tr(D̂) Δt`,
    /// `Δσ_xy = 2G D̂_xy Δt` (paper eq. 2.18, bracket).
    #[inline(always)]
    pub fn trial(&self, sigma: [f64; 4], d_hat: [f64; 3], dt: f64) -> [f64; 4] {
        let l = self.lambda * (d_hat[0] + d_hat[1]) * dt;
        let g = 2.0 * self.mu * dt;
        [sigma[0] + l + g * d_hat[0], sigma[1] + l + g * d_hat[1], sigma[2] + l, sigma[3] + g * d_hat[2]]
    }

    /// Viscous stress `β C : D` (Pa) of stiffness-proportional damping with
    /// coefficient `beta` (s), in-plane components `[xx, yy, zz, xy]`.
    #[inline(always)]
    pub fn viscous(&self, d: [f64; 3], beta: f64) -> [f64; 4] {
        self.trial([0.0; 4], d, beta)
    }

    /// Elastic strain `C⁻¹ : σ` (3D isotropic compliance, engineering shear
    /// returned as the tensor component), `[xx, yy, zz, xy]`.
    pub fn strain(&self, s: [f64; 4]) -> [f64; 4] {
        let (e, nu) = (self.young, self.poisson);
        [
            (s[0] - nu * (s[1] + s[2])) / e,
            (s[1] - nu * (s[0] + s[2])) / e,
            (s[2] - nu * (s[0] + s[1])) / e,
            s[3] / (2.0 * self.mu),
        ]
    }

    /// Elastic strain-energy density `½ σ : C⁻¹ : σ` (J/m³) of a stress
    /// `[xx, yy, zz, xy]`, using the 3D compliance so that `σ_zz` counts
    /// where plastic flow has made `ε^e_zz ≠ 0`.
    #[inline]
    pub fn energy_density(&self, s: [f64; 4]) -> f64 {
        let (e, nu) = (self.young, self.poisson);
        let normal = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] - 2.0 * nu * (s[0] * s[1] + s[1] * s[2] + s[2] * s[0]);
        0.5 * normal / e + s[3] * s[3] / (2.0 * self.mu)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lame_constants_from_e_and_nu() {
        let m = Elastic::new(60e9, 0.25).unwrap();
        assert!((m.lambda - 24e9).abs() < 1e-3);
        assert!((m.mu - 24e9).abs() < 1e-3);
    }

    #[test]
    fn uniaxial_strain_gives_plane_strain_stresses() {
        // ε_xx = 1e-4, others zero: σxx = (λ+2G) ε, σyy = σzz = λ ε
        let m = Elastic::new(10e9, 0.2).unwrap();
        let s = m.trial([0.0; 4], [1e-4, 0.0, 0.0], 1.0);
        assert!((s[0] - (m.lambda + 2.0 * m.mu) * 1e-4).abs() < 1e-6);
        assert!((s[1] - m.lambda * 1e-4).abs() < 1e-6 && (s[2] - s[1]).abs() < 1e-9);
        // the compliance recovers the strain, with ε_zz = 0
        let eps = m.strain(s);
        assert!((eps[0] - 1e-4).abs() < 1e-16 && eps[1].abs() < 1e-16 && eps[2].abs() < 1e-16);
        // energy ½ σ:ε
        assert!((m.energy_density(s) - 0.5 * s[0] * 1e-4).abs() < 1e-9);
    }

    #[test]
    fn parameters_are_checked() {
        assert_eq!(Elastic::new(-1.0, 0.2).unwrap_err().parameter, "E");
        assert_eq!(Elastic::new(1.0, 0.5).unwrap_err().parameter, "nu");
        assert_eq!(Elastic::new(1.0, -1.0).unwrap_err().parameter, "nu");
        assert_eq!(Elastic::new(f64::NAN, 0.2).unwrap_err().parameter, "E");
    }
}
