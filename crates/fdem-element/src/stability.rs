//! The critical time step of the central-difference scheme from each
//! element's own eigenvalue problem (DESIGN §4.2).
//!
//! For the lumped CST, `M_e = ρA/3 · I` and `K_e = A Bᵀ C B`, so the highest
//! eigenfrequency is `ω_e² = (3/ρ) λ_max(Bᵀ C B)`. The non-zero eigenvalues
//! of `Bᵀ C B` (6×6) are those of the symmetric 3×3 `Lᵀ B Bᵀ L` with
//! `C = L Lᵀ`. By the element eigenvalue inequality (Irons & Treharne) the
//! assembled system's highest frequency never exceeds `max_e ω_e`, so
//! `Δt = 2 / max_e ω_e` is always stable; unlike `h/c_p` it never
//! over-estimates.

use crate::kinematics::{shape_gradients, signed_area, ReferenceShape};
use crate::{Tri, Vec2};

/// Largest eigenvalue of the symmetric 3×3 matrix
/// `[[m0, m3, m4], [m3, m1, m5], [m4, m5, m2]]`, by the closed-form
/// trigonometric solution of the characteristic cubic.
pub fn sym3_max_eigenvalue(m: [f64; 6]) -> f64 {
    let [a, b, c, d, e, f] = m;
    let p1 = d * d + e * e + f * f;
    let q = (a + b + c) / 3.0;
    let p2 = (a - q).powi(2) + (b - q).powi(2) + (c - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p <= f64::EPSILON * q.abs() {
        return q;
    }
    let (ba, bb, bc) = ((a - q) / p, (b - q) / p, (c - q) / p);
    let (bd, be, bf) = (d / p, e / p, f / p);
    let det = ba * (bb * bc - bf * bf) - bd * (bd * bc - bf * be) + be * (bd * bf - bb * be);
    let r = (0.5 * det).clamp(-1.0, 1.0);
    q + 2.0 * p * (r.acos() / 3.0).cos()
}

/// Highest angular eigenfrequency `ω_e` (rad/s) of a lumped plane-strain CST
/// at `x` (m) with Lamé constants `lambda`, `mu` (Pa) and density `rho`
/// (kg/m³).
pub fn max_frequency(x: &Tri<Vec2>, lambda: f64, mu: f64, rho: f64) -> f64 {
    let g = shape_gradients(x);
    let (mut p, mut q, mut r) = (0.0, 0.0, 0.0);
    for n in g {
        p += n[0] * n[0];
        q += n[1] * n[1];
        r += n[0] * n[1];
    }
    // B Bᵀ in Voigt order (xx, yy, γxy)
    let (g11, g22, g33, g13, g23) = (p, q, p + q, r, r);
    // C = L Lᵀ (Cholesky) for plane strain
    let a = lambda + 2.0 * mu;
    let l11 = a.sqrt();
    let l21 = lambda / l11;
    let l22 = (a - l21 * l21).sqrt();
    let l33 = mu.sqrt();
    // S = Lᵀ G L with L lower triangular [[l11,0,0],[l21,l22,0],[0,0,l33]]
    let s11 = l11 * l11 * g11 + l21 * l21 * g22;
    let s22 = l22 * l22 * g22;
    let s33 = l33 * l33 * g33;
    let s12 = l21 * l22 * g22;
    let s13 = l33 * (l11 * g13 + l21 * g23);
    let s23 = l33 * l22 * g23;
    let lam = sym3_max_eigenvalue([s11, s22, s33, s12, s13, s23]);
    (3.0 * lam.max(0.0) / rho).sqrt()
}

/// Highest angular eigenfrequency `ω_e` (rad/s) of a lumped plane-strain CST
/// deformed from its reference shape `reference` to `x` (m): the stiffness
/// is the current one, `K_e = A Bᵀ C B` (Cauchy stress on the current
/// shape, as the internal forces are computed), but the lumped mass stays
/// `ρ A₀ / 3` of the reference area `A₀`, so
/// `ω_e² = (3/ρ) (A/A₀) λ_max(Bᵀ C B)`: [`max_frequency`] times `√J`,
/// `J = A/A₀`. An element stretched to four times its area has twice the
/// frequency of its current shape at its own density; without the factor
/// the stable step of fully softened, hugely stretched rock (block
/// caving's debris) was over-estimated and stiffness damping went unstable
/// there (docs/meshing.md).
pub fn max_frequency_deformed(x: &Tri<Vec2>, reference: &ReferenceShape, lambda: f64, mu: f64, rho: f64) -> f64 {
    let d = reference.dm_inv;
    let j = 2.0 * signed_area(x) * (d[0] * d[3] - d[1] * d[2]);
    max_frequency(x, lambda, mu, rho) * j.max(0.0).sqrt()
}

/// Critical time step (s) of one element, `2/ω_e`, reduced for
/// stiffness-proportional damping `beta` (s) by `√(1 + ξ²) − ξ` with
/// `ξ = β ω_e / 2`.
pub fn critical_time_step(x: &Tri<Vec2>, lambda: f64, mu: f64, rho: f64, beta: f64) -> f64 {
    let w = max_frequency(x, lambda, mu, rho);
    let xi = 0.5 * beta * w;
    2.0 / w * ((1.0 + xi * xi).sqrt() - xi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{shape_gradients, signed_area};
    use nalgebra::{DMatrix, SymmetricEigen};

    /// Independent reference: assemble the 6×6 K_e and M_e and take the
    /// largest generalised eigenvalue with nalgebra.
    fn reference_omega(x: &Tri<Vec2>, e: f64, nu: f64, rho: f64) -> f64 {
        let g = shape_gradients(x);
        let a = signed_area(x);
        let mut b = DMatrix::<f64>::zeros(3, 6);
        for n in 0..3 {
            b[(0, 2 * n)] = g[n][0];
            b[(1, 2 * n + 1)] = g[n][1];
            b[(2, 2 * n)] = g[n][1];
            b[(2, 2 * n + 1)] = g[n][0];
        }
        let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let c = DMatrix::from_row_slice(
            3,
            3,
            &[f * (1.0 - nu), f * nu, 0.0, f * nu, f * (1.0 - nu), 0.0, 0.0, 0.0, f * (1.0 - 2.0 * nu) / 2.0],
        );
        let k = b.transpose() * c * b * a;
        let m = rho * a / 3.0;
        let eig = SymmetricEigen::new(k / m);
        eig.eigenvalues.max().sqrt()
    }

    #[test]
    fn closed_form_eigenvalue_matches_reference() {
        let (e, nu, rho) = (60e9, 0.25, 3100.0);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let shapes: [Tri<Vec2>; 4] = [
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            [[0.0, 0.0], [1.0, 0.0], [0.5, 0.866]],
            [[0.0, 0.0], [3.0, 0.1], [0.2, 0.4]],
            [[1.0, 2.0], [1.5, 2.1], [1.1, 4.0]],
        ];
        for x in shapes {
            let w = max_frequency(&x, lambda, mu, rho);
            let w_ref = reference_omega(&x, e, nu, rho);
            assert!((w - w_ref).abs() < 1e-9 * w_ref, "{w} vs {w_ref}");
        }
    }

    #[test]
    fn deformed_element_keeps_its_reference_mass() {
        // K at the current shape (A Bᵀ C B), M = ρ A₀/3 of the reference
        // area: the generalised eigenvalue, assembled with nalgebra
        let (e, nu, rho) = (60e9, 0.25, 3100.0);
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let x0: Tri<Vec2> = [[0.0, 0.0], [1.0, 0.0], [0.5, 0.866]];
        let reference = crate::kinematics::reference_inverse(&x0).unwrap();
        for (sx, sy, rot) in [(1.0, 1.0, 0.7), (1.0, 4.0, 0.0), (0.5, 8.0, 1.1), (1.0, 0.9, 0.3)] {
            let (c, s) = (f64::cos(rot), f64::sin(rot));
            let x = x0.map(|p| {
                let q = [sx * p[0], sy * p[1]];
                [c * q[0] - s * q[1], s * q[0] + c * q[1]]
            });
            let j = signed_area(&x) / signed_area(&x0);
            // reference_omega uses the current area for the mass: rescale
            let w_ref = reference_omega(&x, e, nu, rho) * j.sqrt();
            let w = max_frequency_deformed(&x, &reference, lambda, mu, rho);
            assert!((w - w_ref).abs() < 1e-9 * w_ref, "stretch ({sx}, {sy}): {w} vs {w_ref}");
        }
        // a rigid rotation changes nothing
        let x = x0.map(|p| [p[0] * 0.6 - p[1] * 0.8, p[0] * 0.8 + p[1] * 0.6]);
        let w0 = max_frequency(&x0, lambda, mu, rho);
        assert!((max_frequency_deformed(&x, &reference, lambda, mu, rho) - w0).abs() < 1e-9 * w0);
    }

    #[test]
    fn eigenvalue_of_diagonal_and_repeated() {
        assert!((sym3_max_eigenvalue([1.0, 5.0, 3.0, 0.0, 0.0, 0.0]) - 5.0).abs() < 1e-14);
        assert!((sym3_max_eigenvalue([2.0, 2.0, 2.0, 0.0, 0.0, 0.0]) - 2.0).abs() < 1e-14);
    }

    #[test]
    fn damping_shortens_the_step() {
        let x = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let undamped = critical_time_step(&x, 1e9, 1e9, 2000.0, 0.0);
        let damped = critical_time_step(&x, 1e9, 1e9, 2000.0, 1e-4);
        assert!(damped < undamped);
        let w = max_frequency(&x, 1e9, 1e9, 2000.0);
        assert!((undamped - 2.0 / w).abs() < 1e-18);
    }
}
