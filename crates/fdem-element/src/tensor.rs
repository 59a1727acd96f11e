//! Small helpers on symmetric 2D tensors stored as `[xx, yy, zz, xy]`.

/// Rotates a symmetric in-plane tensor by the rotation with cosine `c` and
/// sine `s`: returns `R σ Rᵀ` with `R = [[c, −s], [s, c]]`. The out-of-plane
/// component `zz` is unchanged.
#[inline(always)]
pub fn rotate(t: [f64; 4], c: f64, s: f64) -> [f64; 4] {
    let (cc, ss, cs) = (c * c, s * s, c * s);
    [
        cc * t[0] + ss * t[1] - 2.0 * cs * t[3],
        ss * t[0] + cc * t[1] + 2.0 * cs * t[3],
        t[2],
        cs * (t[0] - t[1]) + (cc - ss) * t[3],
    ]
}

/// Rotates back: returns `Rᵀ σ R` (the inverse of [`rotate`]).
#[inline(always)]
pub fn rotate_back(t: [f64; 4], c: f64, s: f64) -> [f64; 4] {
    rotate(t, c, -s)
}

/// In-plane principal values `(σ_max, σ_min)` and the angle (rad, in
/// `(−π/2, π/2]`) of the direction of `σ_max` measured from the x axis.
#[inline]
pub fn principal_2d(t: [f64; 4]) -> (f64, f64, f64) {
    let mean = 0.5 * (t[0] + t[1]);
    let half = 0.5 * (t[0] - t[1]);
    let r = half.hypot(t[3]);
    (mean + r, mean - r, 0.5 * t[3].atan2(half))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_round_trip_and_invariants() {
        let t = [3.0, -1.0, 0.5, 2.0];
        let (c, s) = (0.3_f64.cos(), 0.3_f64.sin());
        let r = rotate(t, c, s);
        let b = rotate_back(r, c, s);
        for k in 0..4 {
            assert!((b[k] - t[k]).abs() < 1e-14);
        }
        // trace and determinant of the in-plane part are invariant
        assert!((r[0] + r[1] - (t[0] + t[1])).abs() < 1e-14);
        let det = |a: [f64; 4]| a[0] * a[1] - a[3] * a[3];
        assert!((det(r) - det(t)).abs() < 1e-13);
    }

    #[test]
    fn quarter_turn_swaps_normal_components() {
        let t = [5.0, 1.0, 0.0, 0.0];
        let r = rotate(t, 0.0, 1.0);
        assert!((r[0] - 1.0).abs() < 1e-15 && (r[1] - 5.0).abs() < 1e-15 && r[3].abs() < 1e-15);
    }

    #[test]
    fn principal_values_and_direction() {
        // uniaxial tension 2 along the direction at 30°
        let th: f64 = 30f64.to_radians();
        let t = rotate([2.0, 0.0, 0.0, 0.0], th.cos(), th.sin());
        let (s1, s2, a) = principal_2d(t);
        assert!((s1 - 2.0).abs() < 1e-14 && s2.abs() < 1e-14);
        assert!((a - th).abs() < 1e-14);
    }
}
