//! The co-rotational (Green–Naghdi) frame of one step (paper eqs. 2.17–2.20,
//! DESIGN §4.1).
//!
//! With `x^{n+1}` and `v^{n+½}` known, the midpoint configuration is
//! `x^{n+½} = x^{n+1} − Δt/2 · v^{n+½}`. The rate of deformation
//! `D = sym(∂v/∂x)` is evaluated there and rotated into the co-rotational
//! frame, `D̂ = R_{n+½}ᵀ D R_{n+½}`. The material law then integrates
//! `σ̂^{n+1} = σ̂ⁿ + C : D̂ Δt` (with its return mapping), and the Cauchy stress
//! is `σ^{n+1} = R_{n+1} σ̂^{n+1} R_{n+1}ᵀ`. `R` is the rotation of the polar
//! decomposition of `F`, so a rigid rotation leaves `σ̂` untouched and turns
//! `σ` with the body exactly.

use crate::kinematics::{deformation_gradient, edge_matrix, inverse_2x2, mul_2x2, polar_rotation, ReferenceShape};
use crate::{Tri, Vec2};

/// A rate of deformation in Voigt order `[xx, yy, xy]` (1/s), with the
/// tensor (not engineering) shear component.
pub type StrainRate = [f64; 3];

/// Everything the stress update of one element needs from its kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CorotationalFrame {
    /// Co-rotational rate of deformation `D̂ = R_{n+½}ᵀ D R_{n+½}` (1/s).
    pub d_hat: StrainRate,
    /// Spatial rate of deformation `D` at `x^{n+½}` (1/s), for viscous damping.
    pub d: StrainRate,
    /// Cosine of the rotation `R_{n+1}`.
    pub cos_new: f64,
    /// Sine of the rotation `R_{n+1}`.
    pub sin_new: f64,
    /// Twice the signed area at `x^{n+1}` (m²); not positive means inverted.
    pub twice_area_new: f64,
    /// Twice the signed area at `x^{n+½}` (m²).
    pub twice_area_mid: f64,
}

impl CorotationalFrame {
    /// `true` when the element is inverted or degenerate at the midpoint or
    /// at the end of the step, or its kinematics are not finite.
    #[inline(always)]
    pub fn is_inverted(&self) -> bool {
        // written so that NaN areas count as inverted
        !(self.twice_area_new > 0.0 && self.twice_area_mid > 0.0)
    }
}

/// Computes the co-rotational frame of one step for an element with
/// reference shape `reference`, end-of-step positions `x_new` (m) and
/// half-step velocities `v_half` (m/s), over a step `dt` (s).
#[inline(always)]
pub fn corotational_frame(
    reference: &ReferenceShape,
    x_new: &Tri<Vec2>,
    v_half: &Tri<Vec2>,
    dt: f64,
) -> CorotationalFrame {
    let h = 0.5 * dt;
    let x_mid = [
        [x_new[0][0] - h * v_half[0][0], x_new[0][1] - h * v_half[0][1]],
        [x_new[1][0] - h * v_half[1][0], x_new[1][1] - h * v_half[1][1]],
        [x_new[2][0] - h * v_half[2][0], x_new[2][1] - h * v_half[2][1]],
    ];
    let ds_mid = edge_matrix(&x_mid);
    let det_mid = ds_mid[0] * ds_mid[3] - ds_mid[1] * ds_mid[2];
    let (c_mid, s_mid) = polar_rotation(mul_2x2(ds_mid, reference.dm_inv));
    let l = mul_2x2(edge_matrix(v_half), inverse_2x2(ds_mid, det_mid));
    let d = [l[0], l[3], 0.5 * (l[1] + l[2])];
    // D̂ = Rᵀ D R
    let (cc, ss, cs) = (c_mid * c_mid, s_mid * s_mid, c_mid * s_mid);
    let d_hat = [
        cc * d[0] + ss * d[1] + 2.0 * cs * d[2],
        ss * d[0] + cc * d[1] - 2.0 * cs * d[2],
        -cs * (d[0] - d[1]) + (cc - ss) * d[2],
    ];
    let ds_new = edge_matrix(x_new);
    let (cos_new, sin_new) = polar_rotation(deformation_gradient(reference, x_new));
    CorotationalFrame {
        d_hat,
        d,
        cos_new,
        sin_new,
        twice_area_new: ds_new[0] * ds_new[3] - ds_new[1] * ds_new[2],
        twice_area_mid: det_mid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::reference_inverse;
    use crate::tensor::{rotate, rotate_back};

    const X: Tri<Vec2> = [[0.0, 0.0], [1.0, 0.2], [0.3, 0.9]];

    fn rot(th: f64, p: Vec2) -> Vec2 {
        [th.cos() * p[0] - th.sin() * p[1], th.sin() * p[0] + th.cos() * p[1]]
    }

    #[test]
    fn rigid_rotation_step_has_no_deformation() {
        // Exact rigid rotation from θ0 to θ1 reached with v = (x1 − x0)/Δt:
        // the midpoint velocity gradient is skew, so D = D̂ = 0.
        let reference = reference_inverse(&X).unwrap();
        let (t0, t1, dt) = (0.4, 0.45, 1e-3);
        let x_old = X.map(|p| rot(t0, p));
        let x_new = X.map(|p| rot(t1, p));
        let v = [0, 1, 2].map(|a| [(x_new[a][0] - x_old[a][0]) / dt, (x_new[a][1] - x_old[a][1]) / dt]);
        let f = corotational_frame(&reference, &x_new, &v, dt);
        for k in 0..3 {
            assert!(f.d_hat[k].abs() < 1e-9, "{:?}", f.d_hat);
        }
        assert!((f.cos_new - t1.cos()).abs() < 1e-14 && (f.sin_new - t1.sin()).abs() < 1e-14);
        assert!(!f.is_inverted());
    }

    #[test]
    fn stretch_in_rotated_frame_is_seen_unrotated() {
        // A body already rotated by 90° and stretched along its (current) x
        // axis sees the stretch along its reference y axis: D̂_yy = rate.
        let reference = reference_inverse(&X).unwrap();
        let th = std::f64::consts::FRAC_PI_2;
        let rate = 0.01;
        let x_mid = X.map(|p| rot(th, p));
        let v = x_mid.map(|p| [rate * p[0], 0.0]);
        let dt = 1e-6;
        let x_new = [0, 1, 2].map(|a| [x_mid[a][0] + 0.5 * dt * v[a][0], x_mid[a][1]]);
        let f = corotational_frame(&reference, &x_new, &v, dt);
        assert!((f.d[0] - rate).abs() < 1e-12);
        assert!((f.d_hat[1] - rate).abs() < 1e-8 && f.d_hat[0].abs() < 1e-8, "{:?}", f.d_hat);
        // and a co-rotational stress along ŷ maps to the current x axis
        let sigma = rotate([0.0, 1.0, 0.0, 0.0], f.cos_new, f.sin_new);
        assert!((sigma[0] - 1.0).abs() < 1e-6);
        let back = rotate_back(sigma, f.cos_new, f.sin_new);
        assert!((back[1] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn inverted_end_configuration_is_flagged() {
        let reference = reference_inverse(&X).unwrap();
        let x_new = [X[0], X[2], X[1]];
        let f = corotational_frame(&reference, &x_new, &[[0.0; 2]; 3], 1e-3);
        assert!(f.is_inverted());
        let nan = [[f64::NAN, 0.0], X[1], X[2]];
        assert!(corotational_frame(&reference, &nan, &[[0.0; 2]; 3], 1e-3).is_inverted());
    }
}
