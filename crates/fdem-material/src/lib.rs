//! Constitutive models of fdem, as pure functions on one material point.
//!
//! The material crate knows no mesh: the solver hands it a co-rotational
//! stress `σ̂ = [xx, yy, zz, xy]` (Pa, tension positive), a co-rotational rate
//! of deformation `D̂ = [xx, yy, xy]` (1/s, tensor shear) and a step `Δt` (s),
//! and gets back the updated stress and state.
//!
//! * [`elastic`]: isotropic linear elasticity in plane strain (`ε_zz = 0`,
//!   `σ_zz` tracked).
//! * [`mohr_coulomb_rankine`]: the paper's combined Mohr–Coulomb and Rankine
//!   multi-surface plasticity with fracture-energy softening (appendices A–C).
//! * [`principal`]: principal values with `σ_zz` as one of the three.
//! * [`softening`]: the shape of the tensile softening curve (linear, or
//!   bilinear as Petersson's for concrete).

pub mod crack_band;
mod dense;
pub mod elastic;
pub mod mohr_coulomb_rankine;
pub mod principal;
pub mod softening;

pub use elastic::Elastic;
pub use mohr_coulomb_rankine::{CrackBand, Geometry, MohrCoulombRankine, PlasticState, Update};
pub use softening::Softening;

/// Errors in material parameters, naming the offending parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterError {
    /// The parameter's name as the Python API spells it (`E`, `nu`, `rho`…).
    pub parameter: &'static str,
    /// The rejected value.
    pub value: f64,
    /// What the value must satisfy.
    pub requirement: String,
}

impl std::fmt::Display for ParameterError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "material parameter {} = {} is invalid: {}", self.parameter, self.value, self.requirement)
    }
}

impl std::error::Error for ParameterError {}

pub(crate) fn check(parameter: &'static str, value: f64, ok: bool, requirement: &str) -> Result<(), ParameterError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(ParameterError { parameter, value, requirement: requirement.to_string() })
    }
}
