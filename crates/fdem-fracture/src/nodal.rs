//! Nodal failure factor and crack direction (paper eqs. 2.22–2.23).

use fdem_core::CHUNK;
use fdem_mesh::Csr;
use rayon::prelude::*;

/// A doubled-angle unit vector `v = (cos 2θ, sin 2θ)` turned by the
/// rotation whose cosine and sine are `(c, s)`: the direction at `θ + φ`,
/// without a trigonometric call (`cos 2φ = c² − s²`, `sin 2φ = 2cs`).
#[inline]
pub fn doubled_direction(v: [f64; 2], (c, s): (f64, f64)) -> [f64; 2] {
    let (cr, sr) = (c * c - s * s, 2.0 * c * s);
    [v[0] * cr - v[1] * sr, v[1] * cr + v[0] * sr]
}

/// Nodal failure factor `F̄_p = Σ A_e F_e / Σ A_e` over the active elements
/// around each node (eq. 2.22), and the crack-normal direction `θ̄_p` (the
/// direction of σ1) as a doubled-angle vector: `Σ w (cos 2θ_e, sin 2θ_e)`
/// with `w = A_e F_e`, from the elements' unit vectors `element_direction`
/// ([`doubled_direction`]). Its angle `θ̄_p = ½ atan2(Σ w sin 2θ, Σ w cos
/// 2θ)` ([`direction_angle`]) averages 179° and 1° to 0°, not 90°, and
/// elements that have not begun to crack do not vote. The vector is summed
/// here and turned into an angle only where a crack is planned: a sine and
/// cosine per element around every node, and an arctangent per node, were
/// most of a fracture check (measured on the block-caving case). Written
/// into `factor` and `direction` (one per node); isolated nodes get 0.
pub fn nodal_failure(
    node_elems: &Csr,
    areas: &[f64],
    active: &[bool],
    element_factor: &[f64],
    element_direction: &[[f64; 2]],
    factor: &mut [f64],
    direction: &mut [[f64; 2]],
) {
    factor.par_iter_mut().zip(direction.par_iter_mut()).enumerate().with_min_len(CHUNK).for_each(|(p, (f, d))| {
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
            if w != 0.0 {
                let [ce, se] = element_direction[e];
                c += w * ce;
                s += w * se;
            }
        }
        *f = if wa > 0.0 { wf / wa } else { 0.0 };
        *d = [c, s];
    });
}

/// The angle `θ̄` (rad, in `[−π/2, π/2]`) of a doubled-angle vector from
/// [`nodal_failure`]: `½ atan2(y, x)`; 0 for the zero vector.
#[inline]
pub fn direction_angle(d: [f64; 2]) -> f64 {
    0.5 * d[1].atan2(d[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angles(element_direction: &[f64]) -> Vec<[f64; 2]> {
        element_direction.iter().map(|&th| [(2.0 * th).cos(), (2.0 * th).sin()]).collect()
    }

    #[test]
    fn doubled_angle_average() {
        // one node shared by two equal elements cracked at 1° and 179°
        let csr = Csr::from_pairs(1, vec![(0, 0), (0, 3)]);
        let (mut f, mut d) = ([0.0], [[0.0; 2]]);
        let deg = std::f64::consts::PI / 180.0;
        nodal_failure(
            &csr,
            &[1.0, 1.0],
            &[true, true],
            &[1.0, 1.0],
            &angles(&[1.0 * deg, 179.0 * deg]),
            &mut f,
            &mut d,
        );
        assert!((f[0] - 1.0).abs() < 1e-15);
        assert!(direction_angle(d[0]).abs() < 1e-12, "{}", direction_angle(d[0]) / deg);
        // area weights for the factor; an uncracked element does not vote on the direction
        nodal_failure(&csr, &[3.0, 1.0], &[true, true], &[1.2, 0.0], &angles(&[0.3, 1.4]), &mut f, &mut d);
        assert!((f[0] - 0.9).abs() < 1e-15 && (direction_angle(d[0]) - 0.3).abs() < 1e-12);
        // no cracked element: direction 0
        nodal_failure(&csr, &[3.0, 1.0], &[true, true], &[0.0, 0.0], &angles(&[0.3, 1.4]), &mut f, &mut d);
        assert_eq!((f[0], direction_angle(d[0])), (0.0, 0.0));
    }

    #[test]
    fn turned_direction_is_the_sum_of_the_angles() {
        // against the trigonometric form, over a sweep of angles and turns
        // (the turn given by its cosine and sine, as the polar rotation is)
        for i in 0..200 {
            let th = -1.6 + 0.0161 * i as f64;
            let phi = 3.1 - 0.031 * i as f64;
            let v = [(2.0 * th).cos(), (2.0 * th).sin()];
            let got = doubled_direction(v, (phi.cos(), phi.sin()));
            let (s, c) = (2.0 * (th + phi)).sin_cos();
            assert!((got[0] - c).abs() < 1e-14 && (got[1] - s).abs() < 1e-14, "{th} {phi}: {got:?}");
            // an orientation: half a turn more is the same direction
            let back = doubled_direction(v, (-phi.cos(), -phi.sin()));
            assert!((back[0] - c).abs() < 1e-14 && (back[1] - s).abs() < 1e-14);
        }
    }

    #[test]
    fn mean_direction_matches_the_trigonometric_average() {
        // weights and angles around one node, against ½ atan2(Σ w sin 2θ, Σ w cos 2θ)
        let csr = Csr::from_pairs(1, (0..5u32).map(|k| (0, 3 * k)).collect::<Vec<_>>());
        let th = [0.2, -1.1, 1.5, 0.7, -0.4];
        let (areas, factors) = ([1.0, 2.0, 0.5, 1.5, 0.8], [0.3, 0.9, 1.0, 0.0, 0.6]);
        let (mut f, mut d) = ([0.0], [[0.0; 2]]);
        nodal_failure(&csr, &areas, &[true; 5], &factors, &angles(&th), &mut f, &mut d);
        let (mut c, mut s) = (0.0, 0.0);
        for k in 0..5 {
            let w = areas[k] * factors[k];
            c += w * (2.0 * th[k]).cos();
            s += w * (2.0 * th[k]).sin();
        }
        assert!((direction_angle(d[0]) - 0.5 * s.atan2(c)).abs() < 1e-14);
    }
}
