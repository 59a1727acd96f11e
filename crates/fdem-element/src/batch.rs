//! The co-rotational frame of [`LANES`] elements at once.
//!
//! The per-element frame ([`corotational_frame`](crate::corotational::corotational_frame))
//! is a chain of dependent square roots and divisions; one element at a time
//! it is latency-bound. Here every quantity is an array over lanes, and every
//! operation a loop over the lanes, so the compiler emits packed SIMD and
//! independent elements fill each other's latency. Same equations, same
//! results bit for bit (each lane does exactly the scalar operations).

use crate::corotational::StrainRate;

/// Elements per batch.
pub const LANES: usize = 4;

/// A value per lane.
pub type Lanes = [f64; LANES];

#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> Lanes {
    std::array::from_fn(f)
}

/// Node data of a batch in lane layout: `x[k][l]` is coordinate `k`
/// (`x0, y0, x1, y1, x2, y2`) of the element in lane `l`.
pub type TriLanes = [Lanes; 6];

/// The co-rotational frames of a batch; see
/// [`CorotationalFrame`](crate::corotational::CorotationalFrame).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameLanes {
    /// Co-rotational rate of deformation `D̂` per lane (1/s).
    pub d_hat: [Lanes; 3],
    /// Spatial rate of deformation `D` per lane (1/s).
    pub d: [Lanes; 3],
    /// cos of `R_{n+1}`.
    pub cos_new: Lanes,
    /// sin of `R_{n+1}`.
    pub sin_new: Lanes,
    /// Twice the area at `x^{n+1}` (m²).
    pub twice_area_new: Lanes,
    /// Twice the area at `x^{n+½}` (m²).
    pub twice_area_mid: Lanes,
}

impl FrameLanes {
    /// `D̂` of lane `l`.
    #[inline(always)]
    pub fn d_hat(&self, l: usize) -> StrainRate {
        [self.d_hat[0][l], self.d_hat[1][l], self.d_hat[2][l]]
    }

    /// `D` of lane `l`.
    #[inline(always)]
    pub fn d(&self, l: usize) -> StrainRate {
        [self.d[0][l], self.d[1][l], self.d[2][l]]
    }

    /// Lane `l` inverted or degenerate (NaN counts as inverted).
    #[inline(always)]
    pub fn is_inverted(&self, l: usize) -> bool {
        !(self.twice_area_new[l] > 0.0 && self.twice_area_mid[l] > 0.0)
    }
}

/// Frames of a batch: `dm_inv[k][l]` is entry `k` of lane `l`'s `Dm⁻¹`,
/// `x` end-of-step positions, `v` half-step velocities, `dt` the step.
#[inline(always)]
pub fn corotational_frames(dm_inv: &[Lanes; 4], x: &TriLanes, v: &TriLanes, dt: f64) -> FrameLanes {
    let h = 0.5 * dt;
    let xm: TriLanes = std::array::from_fn(|k| lanes(|l| x[k][l] - h * v[k][l]));
    // edge matrices [a b; c d] = [x1 − x0, x2 − x0; y1 − y0, y2 − y0]
    let edge = |p: &TriLanes| -> [Lanes; 4] {
        [
            lanes(|l| p[2][l] - p[0][l]),
            lanes(|l| p[4][l] - p[0][l]),
            lanes(|l| p[3][l] - p[1][l]),
            lanes(|l| p[5][l] - p[1][l]),
        ]
    };
    let mul = |a: &[Lanes; 4], b: &[Lanes; 4]| -> [Lanes; 4] {
        [
            lanes(|l| a[0][l] * b[0][l] + a[1][l] * b[2][l]),
            lanes(|l| a[0][l] * b[1][l] + a[1][l] * b[3][l]),
            lanes(|l| a[2][l] * b[0][l] + a[3][l] * b[2][l]),
            lanes(|l| a[2][l] * b[1][l] + a[3][l] * b[3][l]),
        ]
    };
    let ds_mid = edge(&xm);
    let det_mid = lanes(|l| ds_mid[0][l] * ds_mid[3][l] - ds_mid[1][l] * ds_mid[2][l]);
    let f_mid = mul(&ds_mid, dm_inv);
    let a_mid = lanes(|l| f_mid[0][l] + f_mid[3][l]);
    let b_mid = lanes(|l| f_mid[2][l] - f_mid[1][l]);
    let r_mid = lanes(|l| 1.0 / (a_mid[l] * a_mid[l] + b_mid[l] * b_mid[l]).sqrt());
    let c_mid = lanes(|l| a_mid[l] * r_mid[l]);
    let s_mid = lanes(|l| b_mid[l] * r_mid[l]);
    let inv_det = lanes(|l| 1.0 / det_mid[l]);
    let dsi = [
        lanes(|l| ds_mid[3][l] * inv_det[l]),
        lanes(|l| -ds_mid[1][l] * inv_det[l]),
        lanes(|l| -ds_mid[2][l] * inv_det[l]),
        lanes(|l| ds_mid[0][l] * inv_det[l]),
    ];
    let lg = mul(&edge(v), &dsi);
    let d = [lanes(|l| lg[0][l]), lanes(|l| lg[3][l]), lanes(|l| 0.5 * (lg[1][l] + lg[2][l]))];
    let cc = lanes(|l| c_mid[l] * c_mid[l]);
    let ss = lanes(|l| s_mid[l] * s_mid[l]);
    let cs = lanes(|l| c_mid[l] * s_mid[l]);
    let d_hat = [
        lanes(|l| cc[l] * d[0][l] + ss[l] * d[1][l] + 2.0 * cs[l] * d[2][l]),
        lanes(|l| ss[l] * d[0][l] + cc[l] * d[1][l] - 2.0 * cs[l] * d[2][l]),
        lanes(|l| -cs[l] * (d[0][l] - d[1][l]) + (cc[l] - ss[l]) * d[2][l]),
    ];
    let ds_new = edge(x);
    let f_new = mul(&ds_new, dm_inv);
    let a_new = lanes(|l| f_new[0][l] + f_new[3][l]);
    let b_new = lanes(|l| f_new[2][l] - f_new[1][l]);
    let r_new = lanes(|l| 1.0 / (a_new[l] * a_new[l] + b_new[l] * b_new[l]).sqrt());
    FrameLanes {
        d_hat,
        d,
        cos_new: lanes(|l| a_new[l] * r_new[l]),
        sin_new: lanes(|l| b_new[l] * r_new[l]),
        twice_area_new: lanes(|l| ds_new[0][l] * ds_new[3][l] - ds_new[1][l] * ds_new[2][l]),
        twice_area_mid: det_mid,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corotational::corotational_frame;
    use crate::kinematics::reference_inverse;

    #[test]
    fn batch_equals_scalar_bit_for_bit() {
        let refs = [
            [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            [[0.0, 0.0], [2.0, 0.3], [0.4, 1.5]],
            [[1.0, 1.0], [1.5, 1.1], [1.2, 2.0]],
            [[0.0, 0.0], [1.0, 0.0], [0.5, 0.8]],
        ];
        let xs = [
            [[0.01, 0.0], [1.02, 0.03], [-0.01, 0.99]],
            [[0.0, 0.1], [1.9, 0.5], [0.1, 1.6]],
            [[1.0, 1.0], [1.45, 1.2], [1.1, 2.1]],
            [[0.2, 0.1], [1.1, 0.2], [0.6, 0.9]],
        ];
        let vs = [
            [[1.0, 0.0], [0.5, -0.2], [0.0, 0.3]],
            [[0.0, 0.0], [2.0, 1.0], [-1.0, 0.5]],
            [[0.3, 0.3], [0.1, -0.4], [0.2, 0.0]],
            [[-1.0, 2.0], [0.0, 0.0], [3.0, -1.0]],
        ];
        let r: Vec<_> = refs.iter().map(|x| reference_inverse(x).unwrap()).collect();
        let dm_inv = std::array::from_fn(|k| std::array::from_fn(|l| r[l].dm_inv[k]));
        let pack = |a: &[[[f64; 2]; 3]; 4]| -> TriLanes {
            std::array::from_fn(|k| std::array::from_fn(|l| a[l][k / 2][k % 2]))
        };
        let batch = corotational_frames(&dm_inv, &pack(&xs), &pack(&vs), 1e-3);
        for l in 0..LANES {
            let s = corotational_frame(&r[l], &xs[l], &vs[l], 1e-3);
            assert_eq!(batch.d_hat(l), s.d_hat);
            assert_eq!(batch.d(l), s.d);
            assert_eq!((batch.cos_new[l], batch.sin_new[l]), (s.cos_new, s.sin_new));
            assert_eq!((batch.twice_area_new[l], batch.twice_area_mid[l]), (s.twice_area_new, s.twice_area_mid));
        }
    }
}
