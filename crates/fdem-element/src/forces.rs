//! Internal nodal forces and lumped mass of a CST.

use crate::{Tri, Vec2};

/// Internal nodal forces `f_a = A σ ∇N_a` (N per unit thickness) of a
/// triangle at `x` (m, counter-clockwise) carrying the Cauchy stress `σ`
/// (Pa, `[xx, yy, zz, xy]`; `zz` does no work in plane strain).
///
/// With `∇N_a = (y_b − y_c, x_c − x_b) / 2A` the area cancels:
/// `f_a = ½ [σxx (y_b − y_c) + σxy (x_c − x_b), σxy (y_b − y_c) + σyy (x_c − x_b)]`.
/// The equation of motion is `M a = f_ext − f_int`.
#[inline(always)]
pub fn internal_forces(x: &Tri<Vec2>, sigma: &[f64; 4]) -> Tri<Vec2> {
    let mut f = [[0.0; 2]; 3];
    for a in 0..3 {
        let b = (a + 1) % 3;
        let c = (a + 2) % 3;
        let ny = 0.5 * (x[b][1] - x[c][1]);
        let nx = 0.5 * (x[c][0] - x[b][0]);
        f[a] = [sigma[0] * ny + sigma[3] * nx, sigma[3] * ny + sigma[1] * nx];
    }
    f
}

/// Lumped (row-sum) mass per node of a CST (kg per unit thickness):
/// `ρ A / 3` for each of its three nodes.
#[inline(always)]
pub fn lumped_mass(density: f64, area: f64) -> f64 {
    density * area / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::{shape_gradients, signed_area};

    #[test]
    fn forces_equal_b_transpose_sigma_and_balance() {
        let x = [[0.1, 0.0], [1.3, 0.4], [0.2, 1.1]];
        let s = [2.0e6, -1.0e6, 0.3e6, 0.7e6];
        let f = internal_forces(&x, &s);
        let g = shape_gradients(&x);
        let a = signed_area(&x);
        for n in 0..3 {
            let fx = a * (s[0] * g[n][0] + s[3] * g[n][1]);
            let fy = a * (s[3] * g[n][0] + s[1] * g[n][1]);
            assert!((f[n][0] - fx).abs() < 1e-8 && (f[n][1] - fy).abs() < 1e-8);
        }
        // no net force and no net moment from a self-equilibrated stress
        let sx: f64 = f.iter().map(|v| v[0]).sum();
        let sy: f64 = f.iter().map(|v| v[1]).sum();
        let m: f64 = (0..3).map(|n| x[n][0] * f[n][1] - x[n][1] * f[n][0]).sum();
        assert!(sx.abs() < 1e-8 && sy.abs() < 1e-8 && m.abs() < 1e-8);
    }

    #[test]
    fn uniform_pressure_pushes_nodes_outward_per_edge() {
        // Hydrostatic tension p in a right triangle: the force on the corner at
        // the origin equals −p times half of each adjacent edge's outward normal.
        let x = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        let p = 5.0;
        let f = internal_forces(&x, &[p, p, 0.0, 0.0]);
        assert!((f[0][0] + p).abs() < 1e-14 && (f[0][1] + p).abs() < 1e-14);
    }
}
