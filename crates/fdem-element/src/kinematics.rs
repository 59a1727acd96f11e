//! Geometry and kinematics of one linear triangle.
//!
//! A triangle with nodes `x0, x1, x2` (counter-clockwise) has the edge matrix
//! `Ds = [x1 − x0, x2 − x0]` (edges as columns). With `Dm` the same matrix in
//! the reference configuration, the deformation gradient is `F = Ds Dm⁻¹`
//! (constant over the element).

use crate::{Tri, Vec2};

/// Twice the signed area: positive for a counter-clockwise triangle (m²).
#[inline(always)]
pub fn twice_signed_area(x: &Tri<Vec2>) -> f64 {
    (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1])
}

/// Signed area (m²): positive for a counter-clockwise triangle.
#[inline(always)]
pub fn signed_area(x: &Tri<Vec2>) -> f64 {
    0.5 * twice_signed_area(x)
}

/// Edge matrix `Ds = [x1 − x0, x2 − x0]` stored row-major `[a, b, c, d]`
/// for `[[a, b], [c, d]]`.
#[inline(always)]
pub fn edge_matrix(x: &Tri<Vec2>) -> [f64; 4] {
    [x[1][0] - x[0][0], x[2][0] - x[0][0], x[1][1] - x[0][1], x[2][1] - x[0][1]]
}

/// Inverse of a 2×2 row-major matrix given its determinant.
#[inline(always)]
pub fn inverse_2x2(m: [f64; 4], det: f64) -> [f64; 4] {
    let r = 1.0 / det;
    [m[3] * r, -m[1] * r, -m[2] * r, m[0] * r]
}

/// Product of two 2×2 row-major matrices.
#[inline(always)]
pub fn mul_2x2(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [a[0] * b[0] + a[1] * b[2], a[0] * b[1] + a[1] * b[3], a[2] * b[0] + a[3] * b[2], a[2] * b[1] + a[3] * b[3]]
}

/// What an element keeps of its reference configuration: `Dm⁻¹`, the inverse
/// of the reference edge matrix (1/m), row-major.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ReferenceShape {
    /// `Dm⁻¹` row-major.
    pub dm_inv: [f64; 4],
}

/// `Dm⁻¹` of a reference triangle, or `None` when its area is not positive
/// (clockwise or degenerate) or not finite.
pub fn reference_inverse(x_ref: &Tri<Vec2>) -> Option<ReferenceShape> {
    let dm = edge_matrix(x_ref);
    let det = dm[0] * dm[3] - dm[1] * dm[2];
    (det > 0.0 && det.is_finite()).then(|| ReferenceShape { dm_inv: inverse_2x2(dm, det) })
}

/// Deformation gradient `F = Ds Dm⁻¹` (row-major).
#[inline(always)]
pub fn deformation_gradient(reference: &ReferenceShape, x: &Tri<Vec2>) -> [f64; 4] {
    mul_2x2(edge_matrix(x), reference.dm_inv)
}

/// Cosine and sine of the rotation `R` in the polar decomposition `F = R U`.
///
/// In 2D the angle is `atan2(F21 − F12, F11 + F22)` (DESIGN §4.1); we return
/// its cosine and sine directly, which needs one square root and no
/// trigonometric call. `F` must have a positive determinant.
#[inline(always)]
pub fn polar_rotation(f: [f64; 4]) -> (f64, f64) {
    let a = f[0] + f[3];
    let b = f[2] - f[1];
    let r = 1.0 / (a * a + b * b).sqrt();
    (a * r, b * r)
}

/// Shape-function gradients `∇N_a` (1/m) of the triangle at `x`, computed
/// as `(y_b − y_c, x_c − x_b) / 2A` for `(a, b, c)` cyclic.
#[inline(always)]
pub fn shape_gradients(x: &Tri<Vec2>) -> Tri<Vec2> {
    let r = 1.0 / twice_signed_area(x);
    let mut g = [[0.0; 2]; 3];
    for a in 0..3 {
        let b = (a + 1) % 3;
        let c = (a + 2) % 3;
        g[a] = [(x[b][1] - x[c][1]) * r, (x[c][0] - x[b][0]) * r];
    }
    g
}

/// Velocity gradient `L = ∂v/∂x` (1/s, row-major) on the configuration `x`,
/// as `Dv Ds⁻¹` with `Dv` the velocity edge matrix.
#[inline(always)]
pub fn velocity_gradient(x: &Tri<Vec2>, v: &Tri<Vec2>) -> [f64; 4] {
    let ds = edge_matrix(x);
    let det = ds[0] * ds[3] - ds[1] * ds[2];
    mul_2x2(edge_matrix(v), inverse_2x2(ds, det))
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: Tri<Vec2> = [[0.0, 0.0], [2.0, 0.0], [0.5, 1.5]];

    #[test]
    fn area_sign_follows_orientation() {
        assert!((signed_area(&T) - 1.5).abs() < 1e-15);
        let cw = [T[0], T[2], T[1]];
        assert!((signed_area(&cw) + 1.5).abs() < 1e-15);
        assert!(reference_inverse(&cw).is_none());
        assert!(reference_inverse(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_none());
    }

    #[test]
    fn gradients_sum_to_zero_and_reproduce_linear_fields() {
        let g = shape_gradients(&T);
        // ∑ ∇N_a = 0 (partition of unity) and ∑ x_a ⊗ ∇N_a = I (linear completeness)
        for d in 0..2 {
            assert!((g[0][d] + g[1][d] + g[2][d]).abs() < 1e-15);
            for e in 0..2 {
                let s: f64 = (0..3).map(|a| T[a][d] * g[a][e]).sum();
                assert!((s - if d == e { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn affine_map_gives_its_gradient() {
        // x = A X + b with A known: F must equal A exactly.
        let a = [1.1, 0.3, -0.2, 0.9];
        let map = |p: Vec2| [a[0] * p[0] + a[1] * p[1] + 3.0, a[2] * p[0] + a[3] * p[1] - 1.0];
        let x = [map(T[0]), map(T[1]), map(T[2])];
        let f = deformation_gradient(&reference_inverse(&T).unwrap(), &x);
        for k in 0..4 {
            assert!((f[k] - a[k]).abs() < 1e-14, "{f:?}");
        }
    }

    #[test]
    fn polar_rotation_of_rotated_stretch() {
        // F = R(θ) U with U symmetric positive definite: recover θ.
        let th = 2.5_f64;
        let u = [1.2, 0.1, 0.1, 0.8];
        let r = [th.cos(), -th.sin(), th.sin(), th.cos()];
        let (c, s) = polar_rotation(mul_2x2(r, u));
        assert!((c - th.cos()).abs() < 1e-14 && (s - th.sin()).abs() < 1e-14);
    }

    #[test]
    fn velocity_gradient_of_linear_field() {
        let l = [0.2, -0.7, 0.4, 0.1];
        let v = T.map(|p| [l[0] * p[0] + l[1] * p[1] + 5.0, l[2] * p[0] + l[3] * p[1]]);
        let got = velocity_gradient(&T, &v);
        for k in 0..4 {
            assert!((got[k] - l[k]).abs() < 1e-14);
        }
    }
}
