//! Nodal failure factor and crack direction (paper eqs. 2.22–2.23).

use fdem_mesh::Csr;
use rayon::prelude::*;

/// Nodal failure factor `F̄_p = Σ A_e F_e / Σ A_e` over the active elements
/// around each node (eq. 2.22), and crack-normal direction `θ̄_p` (rad, the
/// direction of σ1): the doubled-angle average `½ atan2(Σ w sin 2θ, Σ w cos
/// 2θ)` with `w = A_e F_e`, so that 179° and 1° average to 0°, not 90°, and
/// elements that have not begun to crack do not vote. Written into
/// `factor` and `direction` (one per node); isolated nodes get 0.
pub fn nodal_failure(
    node_elems: &Csr,
    areas: &[f64],
    active: &[bool],
    element_factor: &[f64],
    element_direction: &[f64],
    factor: &mut [f64],
    direction: &mut [f64],
) {
    factor.par_iter_mut().zip(direction.par_iter_mut()).enumerate().with_min_len(1024).for_each(|(p, (f, d))| {
        let (mut wa, mut wf, mut c, mut s) = (0.0, 0.0, 0.0, 0.0);
        for &item in node_elems.row(p) {
            let e = (item / 3) as usize;
            if !active[e] {
                continue;
            }
            let a = areas[e];
            wa += a;
            wf += a * element_factor[e];
            let w = a * element_factor[e];
            let th = 2.0 * element_direction[e];
            c += w * th.cos();
            s += w * th.sin();
        }
        *f = if wa > 0.0 { wf / wa } else { 0.0 };
        *d = 0.5 * s.atan2(c);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubled_angle_average() {
        // one node shared by two equal elements cracked at 1° and 179°
        let csr = Csr::from_pairs(1, vec![(0, 0), (0, 3)]);
        let (mut f, mut d) = ([0.0], [0.0]);
        let deg = std::f64::consts::PI / 180.0;
        nodal_failure(&csr, &[1.0, 1.0], &[true, true], &[1.0, 1.0], &[1.0 * deg, 179.0 * deg], &mut f, &mut d);
        assert!((f[0] - 1.0).abs() < 1e-15);
        assert!(d[0].abs() < 1e-12, "{}", d[0] / deg);
        // area weights for the factor; an uncracked element does not vote on the direction
        nodal_failure(&csr, &[3.0, 1.0], &[true, true], &[1.2, 0.0], &[0.3, 1.4], &mut f, &mut d);
        assert!((f[0] - 0.9).abs() < 1e-15 && (d[0] - 0.3).abs() < 1e-12);
    }
}
