//! A single material point driven along a strain or deformation path: the
//! calibration tool engineers use before meshing (issue 3, item 4).

use fdem_element::kinematics::{inverse_2x2, mul_2x2, polar_rotation};
use fdem_element::tensor::{rotate, rotate_back};
use fdem_material::{Elastic, Geometry, PlasticState};

use crate::error::SetupError;
use crate::model::MaterialSpec;

/// The path a material point is driven along.
#[derive(Clone, Debug, PartialEq)]
pub enum Path {
    /// Strain increments `[Δε_xx, Δε_yy, Δε_xy]` (tensor shear; `ε_zz = 0`),
    /// applied without rotation.
    StrainIncrements(Vec<[f64; 3]>),
    /// Deformation gradients `F = [F11, F12, F21, F22]` at successive
    /// instants, starting from the identity; rotations are handled by the
    /// same co-rotational update as the elements (eqs. 2.17–2.20).
    DeformationGradients(Vec<[f64; 4]>),
}

/// What happened at each point of the path (`n + 1` entries, the first the
/// initial state; per-step quantities have `n`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct History {
    /// Cauchy stress `[xx, yy, zz, xy]` (Pa).
    pub stress: Vec<[f64; 4]>,
    /// Plastic state in the co-rotational frame.
    pub state: Vec<PlasticState>,
    /// Failure factor `κ H / f_t`.
    pub failure_factor: Vec<f64>,
    /// Active set of each step (bits of `fdem_material::mohr_coulomb_rankine::surface`).
    pub active: Vec<u8>,
    /// Mohr–Coulomb dissipation of each step (J/m³).
    pub plastic_dissipation: Vec<f64>,
    /// Fracture dissipation of each step (J/m³).
    pub fracture_dissipation: Vec<f64>,
}

/// Drives one material point of `material` from the Cauchy stress
/// `initial` along `path`. `crack_band` (m) is the band width the point
/// softens over (the element size it stands for).
pub fn material_point(
    material: &MaterialSpec,
    initial: [f64; 4],
    path: &Path,
    crack_band: f64,
) -> Result<History, SetupError> {
    let bad = |index, error| SetupError::Material { index, error };
    let elastic = Elastic::new(material.young, material.poisson).map_err(|e| bad(0, e))?;
    let law = material.law.plastic(elastic).map_err(|e| bad(0, e))?;
    if !(crack_band > 0.0 && crack_band.is_finite()) {
        return Err(SetupError::Invalid(format!("element_size = {crack_band} must be positive")));
    }
    if let Some(l) = &law {
        if crack_band > l.snap_back_size() {
            return Err(SetupError::Invalid(format!(
                "element_size = {crack_band} m exceeds the snap-back limit E' w_c / (ft max|s'|) = {:.4} m (2 E' Gf / ft^2 for linear softening)",
                l.snap_back_size()
            )));
        }
    }
    if !initial.iter().all(|v| v.is_finite()) {
        return Err(SetupError::Invalid("initial stress must be finite".into()));
    }
    // A band preset on the state fixes h_c whatever the crack direction.
    let mut state = PlasticState { crack_band, ..Default::default() };
    let geometry = Geometry { e1: [crack_band, 0.0], e2: [0.0, crack_band] };
    let failure = |s: &PlasticState| law.as_ref().map_or(0.0, |l| l.failure_factor(s));
    let mut h = History {
        stress: vec![initial],
        state: vec![state],
        failure_factor: vec![failure(&state)],
        ..Default::default()
    };
    let step = |sigma_hat: [f64; 4], d_hat: [f64; 3], h: &mut History, state: &mut PlasticState| {
        let trial = elastic.trial(sigma_hat, d_hat, 1.0);
        let (new, active, dp, df) = match &law {
            Some(l) => {
                let u = l.update(sigma_hat, trial, state, || geometry);
                (u.stress, u.active, u.plastic_dissipation, u.fracture_dissipation)
            }
            None => (trial, 0, 0.0, 0.0),
        };
        h.active.push(active);
        h.plastic_dissipation.push(dp);
        h.fracture_dissipation.push(df);
        h.state.push(*state);
        h.failure_factor.push(failure(state));
        new
    };
    match path {
        Path::StrainIncrements(incs) => {
            let mut s = initial;
            for (i, d) in incs.iter().enumerate() {
                if !d.iter().all(|v| v.is_finite()) {
                    return Err(SetupError::Invalid(format!("strain increment {i} is not finite")));
                }
                s = step(s, *d, &mut h, &mut state);
                h.stress.push(s);
            }
        }
        Path::DeformationGradients(fs) => {
            let mut f_old = [1.0, 0.0, 0.0, 1.0];
            let mut s_hat = initial;
            for (i, f) in fs.iter().enumerate() {
                let det = f[0] * f[3] - f[1] * f[2];
                if !(det > 0.0 && f.iter().all(|v| v.is_finite())) {
                    return Err(SetupError::Invalid(format!(
                        "deformation gradient {i} must be finite with a positive determinant (got {det})"
                    )));
                }
                let mid = [
                    0.5 * (f[0] + f_old[0]),
                    0.5 * (f[1] + f_old[1]),
                    0.5 * (f[2] + f_old[2]),
                    0.5 * (f[3] + f_old[3]),
                ];
                let det_mid = mid[0] * mid[3] - mid[1] * mid[2];
                if det_mid <= 0.0 {
                    return Err(SetupError::Invalid(format!(
                        "deformation gradients {i} and the one before are too far apart"
                    )));
                }
                let df = [f[0] - f_old[0], f[1] - f_old[1], f[2] - f_old[2], f[3] - f_old[3]];
                let l = mul_2x2(df, inverse_2x2(mid, det_mid));
                let (c, s) = polar_rotation(mid);
                let d_spatial = [l[0], l[3], 0.0, 0.5 * (l[1] + l[2])];
                let dh = rotate_back(d_spatial, c, s);
                s_hat = step(s_hat, [dh[0], dh[1], dh[3]], &mut h, &mut state);
                let (cn, sn) = polar_rotation(*f);
                h.stress.push(rotate(s_hat, cn, sn));
                f_old = *f;
            }
        }
    }
    Ok(h)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::LawSpec;
    use fdem_material::CrackBand;

    fn rock() -> MaterialSpec {
        MaterialSpec {
            density: 2700.0,
            young: 30e9,
            poisson: 0.25,
            law: LawSpec::MohrCoulombRankine {
                cohesion: 5e6,
                friction: 35f64.to_radians(),
                dilation: 5f64.to_radians(),
                tensile_strength: 2e6,
                fracture_energy: 50.0,
                shear_fracture_energy: 50.0,
                crack_band: CrackBand::Oliver,
                softening: fdem_material::Softening::Linear,
            },
        }
    }

    #[test]
    fn rigid_rotation_path_rotates_the_stress() {
        let s0 = [-3e6, -5e6, -2e6, 1e6]; // inside both surfaces
        let th = std::f64::consts::FRAC_PI_2;
        let fs: Vec<[f64; 4]> =
            (1..=200).map(|k| th * k as f64 / 200.0).map(|a| [a.cos(), -a.sin(), a.sin(), a.cos()]).collect();
        let h = material_point(&rock(), s0, &Path::DeformationGradients(fs), 0.1).unwrap();
        let last = h.stress.last().unwrap();
        let expected = [s0[1], s0[0], s0[2], -s0[3]];
        for k in 0..4 {
            assert!((last[k] - expected[k]).abs() < 1e-6 * 3e6, "{last:?}");
        }
    }

    #[test]
    fn bad_paths_are_named() {
        let e = material_point(&rock(), [0.0; 4], &Path::DeformationGradients(vec![[1.0, 0.0, 0.0, -1.0]]), 0.1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("deformation gradient 0"), "{e}");
        let e =
            material_point(&rock(), [0.0; 4], &Path::StrainIncrements(vec![[0.0; 3]]), 100.0).unwrap_err().to_string();
        assert!(e.contains("snap-back"), "{e}");
    }
}
