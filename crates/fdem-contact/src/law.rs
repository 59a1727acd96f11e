//! Interface laws: normal and tangential penalties, Coulomb friction with
//! cohesion, contact damping (paper appendix D, DESIGN §4.5).

/// The constitutive law of one kind of interface (joint, crack, free
/// boundary), per unit thickness.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InterfaceLaw {
    /// Normal stiffness `k_n` (Pa/m): contact pressure per unit penetration.
    /// A node's penalty spring is `α_n = k_n ℓ` with `ℓ` its tributary length
    /// on the contact, so a uniform penetration gives consistent nodal loads.
    pub normal_stiffness: f64,
    /// Shear stiffness `k_s` (Pa/m) of the elastic tangential gap `g_tᵉ`
    /// (`α_t = k_s ℓ`).
    pub shear_stiffness: f64,
    /// Friction coefficient `μ = tan φ_j` (−).
    pub friction: f64,
    /// Cohesion `c_j` (Pa). The interface resists slip with `c_j` per unit
    /// length on top of friction: a node carries `c_j` × its tributary
    /// length where only its side presses on the other, half of that where
    /// the other side's nodes press on its facets too (two-pass contact;
    /// `narrow::cohesive_length`).
    pub cohesion: f64,
    /// Damping ratio `ξ` of the normal dashpot `ξ · 2√(α_n m)` (−).
    pub damping_ratio: f64,
}

/// An invalid interface-law parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct LawError {
    /// The parameter's name as the Python API spells it.
    pub parameter: &'static str,
    /// The rejected value.
    pub value: f64,
}

impl std::fmt::Display for LawError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interface parameter {} = {} must be finite and non-negative", self.parameter, self.value)
    }
}

impl std::error::Error for LawError {}

impl InterfaceLaw {
    /// A checked law: every parameter finite and ≥ 0, stiffnesses > 0.
    pub fn new(
        normal_stiffness: f64,
        shear_stiffness: f64,
        friction: f64,
        cohesion: f64,
        damping_ratio: f64,
    ) -> Result<Self, LawError> {
        let check = |parameter: &'static str, value: f64, strict: bool| {
            let ok = value.is_finite() && if strict { value > 0.0 } else { value >= 0.0 };
            if ok {
                Ok(())
            } else {
                Err(LawError { parameter, value })
            }
        };
        check("normal_stiffness", normal_stiffness, true)?;
        check("shear_stiffness", shear_stiffness, true)?;
        check("friction", friction, false)?;
        check("cohesion", cohesion, false)?;
        check("damping", damping_ratio, false)?;
        Ok(Self { normal_stiffness, shear_stiffness, friction, cohesion, damping_ratio })
    }
}

/// The tangential (friction) update of appendix D (D.1–D.4) for one contact.
///
/// `stiffness` is the contact's tangential spring `α_t` (N/m per m), `elastic_gap`
/// `g_tᵉ` carried from the last step, `slip_increment` the relative
/// tangential displacement of the step, `normal_force` `f_n ≥ 0` and
/// `cohesion_force` `C_0` (N/m). Returns `(f_t, g_tᵉ new, slip work)`: the
/// tangential force (positive along the gap), the new elastic gap, and the
/// work dissipated by slip in the step (J/m).
#[inline]
pub fn friction_update(
    law: &InterfaceLaw,
    stiffness: f64,
    elastic_gap: f64,
    slip_increment: f64,
    normal_force: f64,
    cohesion_force: f64,
) -> (f64, f64, f64) {
    let trial_gap = elastic_gap + slip_increment;
    let trial = stiffness * trial_gap;
    let limit = law.friction * normal_force + cohesion_force;
    if trial.abs() <= limit {
        (trial, trial_gap, 0.0)
    } else {
        let f = limit.copysign(trial);
        let gap = f / stiffness;
        (f, gap, limit * (trial_gap - gap).abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stick_then_slip() {
        let law = InterfaceLaw::new(1e9, 1e8, 0.5, 0.0, 0.0).unwrap();
        // below the limit: elastic
        let (f, g, w) = friction_update(&law, 1e8, 0.0, 1e-9, 10.0, 0.0);
        assert!((f - 0.1).abs() < 1e-12 && (g - 1e-9).abs() < 1e-20 && w == 0.0);
        // beyond: capped at μ f_n, slip dissipates limit × slip
        let (f, g, w) = friction_update(&law, 1e8, 0.0, 1e-6, 10.0, 0.0);
        assert_eq!(f, 5.0);
        assert!((g - 5e-8).abs() < 1e-20);
        assert!((w - 5.0 * (1e-6 - 5e-8)).abs() < 1e-18);
        // negative direction, with cohesion
        let (f, _, _) = friction_update(&law, 1e8, 0.0, -1e-6, 10.0, 2.0);
        assert_eq!(f, -7.0);
    }

    #[test]
    fn parameters_are_checked() {
        assert_eq!(InterfaceLaw::new(1.0, 1.0, -0.1, 0.0, 0.0).unwrap_err().parameter, "friction");
        assert_eq!(InterfaceLaw::new(1.0, 1.0, 0.1, -1.0, 0.0).unwrap_err().parameter, "cohesion");
        assert_eq!(InterfaceLaw::new(0.0, 1.0, 0.1, 0.0, 0.0).unwrap_err().parameter, "normal_stiffness");
        assert_eq!(InterfaceLaw::new(1.0, 1.0, 0.1, 0.0, -0.5).unwrap_err().parameter, "damping");
    }
}
