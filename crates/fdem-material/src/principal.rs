//! Principal values of a plane-strain stress `[xx, yy, zz, xy]`, with `σ_zz`
//! as one of the three, sorted `σ1 ≥ σ2 ≥ σ3`, and the way back.

/// The spectral form of `[xx, yy, zz, xy]`: in-plane principal values
/// `a ≥ b` with the direction of `a` given by `(cos 2θ, sin 2θ)`, plus `zz`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectral {
    /// Larger in-plane principal value.
    pub a: f64,
    /// Smaller in-plane principal value.
    pub b: f64,
    /// `cos 2θ` of the direction of `a` (1 when `a = b`).
    pub cos2: f64,
    /// `sin 2θ` of the direction of `a`.
    pub sin2: f64,
}

impl Spectral {
    /// Decomposes the in-plane part of `t`.
    #[inline]
    pub fn of(t: [f64; 4]) -> Self {
        let mean = 0.5 * (t[0] + t[1]);
        let half = 0.5 * (t[0] - t[1]);
        let r = (half * half + t[3] * t[3]).sqrt();
        let (cos2, sin2) = if r > 0.0 { (half / r, t[3] / r) } else { (1.0, 0.0) };
        Self { a: mean + r, b: mean - r, cos2, sin2 }
    }

    /// The in-plane tensor with principal values `a`, `b` on these
    /// directions, and `zz`, as `[xx, yy, zz, xy]`.
    #[inline]
    pub fn compose(&self, a: f64, b: f64, zz: f64) -> [f64; 4] {
        let (m, h) = (0.5 * (a + b), 0.5 * (a - b));
        [m + h * self.cos2, m - h * self.cos2, zz, h * self.sin2]
    }

    /// Normal components of another tensor `t` on these principal axes:
    /// `[n_a·t·n_a, n_b·t·n_b, t_zz]`.
    #[inline]
    pub fn normal_components(&self, t: [f64; 4]) -> [f64; 3] {
        let (m, h) = (0.5 * (t[0] + t[1]), 0.5 * (t[0] - t[1]));
        let r = h * self.cos2 + t[3] * self.sin2;
        [m + r, m - r, t[2]]
    }

    /// Angle θ (rad, in `(−π/2, π/2]`) of the direction of `a` from x.
    #[inline]
    pub fn angle(&self) -> f64 {
        0.5 * self.sin2.atan2(self.cos2)
    }

    /// The direction of `a` as a [`DirectionCode`].
    #[inline]
    pub fn direction_code(&self) -> f64 {
        DirectionCode::of(self.cos2, self.sin2)
    }
}

/// A direction (an orientation: `θ` and `θ + π` are the same) kept in one
/// number without a trigonometric call, for a material point that records
/// the direction of σ1 at every tensile plastic step (the rotating crack's
/// normal) but whose angle is read only now and then: an arctangent per
/// update was about 4% of a late step of the block-caving case.
///
/// With `(c, s) = (cos 2θ, sin 2θ)` and `θ ∈ [−π/2, π/2]` the code is
/// `tan θ = s / (1 + c)` in `[−1, 1]` for `|θ| ≤ π/4` (`c ≥ 0`), and
/// `±2 − cot θ`, `cot θ = s / (1 − c)`, in `(1, 2]` or `[−2, −1)` beyond
/// (each formula where it is well conditioned): a monotone function of `θ`,
/// 0 for `θ = 0` (the default state), `±2` for `θ = ±π/2` (the same
/// direction). Converting costs a division; reading back the doubled-angle
/// vector costs two, the angle one arctangent.
pub struct DirectionCode;

impl DirectionCode {
    /// The code of the direction whose doubled angle has cosine `c` and
    /// sine `s` (a unit vector).
    #[inline]
    pub fn of(c: f64, s: f64) -> f64 {
        if c >= 0.0 {
            s / (1.0 + c)
        } else {
            let u = s / (1.0 - c);
            2.0f64.copysign(u) - u
        }
    }

    /// The code of the direction at angle `theta` (rad).
    pub fn of_angle(theta: f64) -> f64 {
        let (s, c) = (2.0 * theta).sin_cos();
        Self::of(c, s)
    }

    /// `tan θ` (`|code| ≤ 1`) or `cot θ` (beyond), and which of the two.
    #[inline]
    fn split(code: f64) -> (f64, bool) {
        if code.abs() <= 1.0 {
            (code, false)
        } else {
            (2.0f64.copysign(code) - code, true)
        }
    }

    /// The doubled-angle unit vector `(cos 2θ, sin 2θ)` of a code.
    #[inline]
    pub fn doubled(code: f64) -> [f64; 2] {
        let (t, cot) = Self::split(code);
        let (t2, r) = (t * t, 1.0 / (1.0 + t * t));
        let c = (1.0 - t2) * r;
        [if cot { -c } else { c }, 2.0 * t * r]
    }

    /// The angle `θ` (rad, in `[−π/2, π/2]`) of a code.
    #[inline]
    pub fn angle(code: f64) -> f64 {
        let (t, cot) = Self::split(code);
        if cot {
            std::f64::consts::FRAC_PI_2.copysign(code) - t.atan()
        } else {
            t.atan()
        }
    }
}

/// Where each sorted principal value comes from: `slot[k]` is 0 for the
/// in-plane `a`, 1 for the in-plane `b`, 2 for `zz`, for `σ_{k+1}`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Order {
    /// Source of `σ1, σ2, σ3`.
    pub slot: [u8; 3],
}

impl Order {
    /// Sorts `[a, b, zz]` (with `a ≥ b`) descending.
    #[inline]
    pub fn sort(a: f64, b: f64, zz: f64) -> ([f64; 3], Self) {
        if zz >= a {
            ([zz, a, b], Order { slot: [2, 0, 1] })
        } else if zz >= b {
            ([a, zz, b], Order { slot: [0, 2, 1] })
        } else {
            ([a, b, zz], Order { slot: [0, 1, 2] })
        }
    }

    /// Orders `[a, b, zz]`-slotted values the way the sort did.
    #[inline]
    pub fn sort_like(&self, v: [f64; 3]) -> [f64; 3] {
        [v[self.slot[0] as usize], v[self.slot[1] as usize], v[self.slot[2] as usize]]
    }

    /// Puts sorted values back as `[a, b, zz]`.
    #[inline]
    pub fn unsort(&self, s: [f64; 3]) -> [f64; 3] {
        let mut out = [0.0; 3];
        for k in 0..3 {
            out[self.slot[k] as usize] = s[k];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Difference of two orientations (rad), modulo π.
    fn off(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(std::f64::consts::PI);
        d.min(std::f64::consts::PI - d)
    }

    #[test]
    fn direction_code_round_trips_and_is_monotone() {
        let half = std::f64::consts::FRAC_PI_2;
        let mut last = f64::NEG_INFINITY;
        for i in 0..=4000 {
            // a sweep of (−π/2, π/2], and the quarter turns exactly
            let th = -half + half * i as f64 / 2000.0;
            let sp = Spectral::of([(2.0 * th).cos(), -(2.0 * th).cos(), 0.0, (2.0 * th).sin()]);
            let code = sp.direction_code();
            assert!(code > last || i == 0, "not monotone at {th}: {code} after {last}");
            last = code;
            assert!(off(DirectionCode::angle(code), sp.angle()) < 4e-16, "{th}");
            let [c, s] = DirectionCode::doubled(code);
            assert!((c - sp.cos2).abs() < 4e-16 && (s - sp.sin2).abs() < 4e-16, "{th}: {c} {s}");
            assert!(code.abs() <= 2.0);
        }
        // the default state's code is the x direction; ±π/2 are one direction
        assert_eq!(DirectionCode::angle(0.0), 0.0);
        assert_eq!(DirectionCode::doubled(0.0), [1.0, 0.0]);
        for code in [2.0, -2.0] {
            assert!(off(DirectionCode::angle(code), half) < 1e-16);
            assert_eq!(DirectionCode::doubled(code), [-1.0, 0.0]);
        }
        assert!(off(DirectionCode::angle(DirectionCode::of_angle(1.3)), 1.3) < 4e-16);
    }

    #[test]
    fn round_trip() {
        let t = [3.0, -2.0, 0.5, 1.5];
        let s = Spectral::of(t);
        let back = s.compose(s.a, s.b, t[2]);
        for k in 0..4 {
            assert!((back[k] - t[k]).abs() < 1e-14);
        }
        let (sorted, order) = Order::sort(s.a, s.b, t[2]);
        assert!(sorted[0] >= sorted[1] && sorted[1] >= sorted[2]);
        assert_eq!(order.unsort(sorted), [s.a, s.b, t[2]]);
        assert_eq!(order.sort_like([s.a, s.b, t[2]]), sorted);
        // a tensor's normal components on its own axes are its principal values
        let n = s.normal_components(t);
        assert!((n[0] - s.a).abs() < 1e-14 && (n[1] - s.b).abs() < 1e-14);
    }

    #[test]
    fn angle_of_major_direction() {
        let th: f64 = 0.4;
        let (c, s) = (th.cos(), th.sin());
        // uniaxial 1 along θ
        let t = [c * c, s * s, 0.0, c * s];
        assert!((Spectral::of(t).angle() - th).abs() < 1e-14);
    }
}
