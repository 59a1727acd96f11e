//! The shape of the tensile softening curve (DESIGN §4.3; docs/fracture.md,
//! "Softening laws").
//!
//! A crack's traction falls from `f_t` at zero opening to zero at the
//! critical opening `w_c` along `σ = f_t s(F)`, `F = w / w_c` (the failure
//! factor, eq. 2.21). The area under the curve is the fracture energy,
//! `G_f = f_t w_c ∫₀¹ s dF`, which fixes `w_c` from `f_t` and `G_f`:
//!
//! * linear (the paper's B.1–B.4): `s = 1 − F`, area ½, `w_c = 2 G_f / f_t`;
//! * bilinear: straight from `(0, 1)` to a kink `(F_k, s_k)` and on to
//!   `(1, 0)`, area `(F_k + s_k)/2`. Petersson's fit for concrete (Crack
//!   growth and development of fracture zones in plain concrete and
//!   similar materials, Lund, 1981) has the kink at `f_t/3` and
//!   `0.8 G_f / f_t`, zero at `w_c = 3.6 G_f / f_t`: `s_k = 1/3`,
//!   `F_k = 2/9`. With the same `G_f` its first branch falls 1.67 times
//!   faster than the linear curve, which is what a notched beam's peak
//!   load feels.
//!
//! The crack band (`MohrCoulombRankine`) and the cohesive bonds that take
//! over from it (`fdem-contact`, `cohesive.rs`) follow the same curve: a
//! bond made at `F` gets the part of the curve from `F` on.

use crate::{check, ParameterError};

/// The shape of the softening curve, in units of `f_t` and `w_c`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Softening {
    /// `s = 1 − F`: the paper's law; the default.
    #[default]
    Linear,
    /// Two straight branches meeting at `(kink_opening, kink_stress)`:
    /// `F_k` (fraction of `w_c`) and `s_k` (fraction of `f_t`), both in
    /// `(0, 1)`.
    Bilinear {
        /// Traction at the kink, `s_k` (fraction of `f_t`).
        kink_stress: f64,
        /// Opening at the kink, `F_k` (fraction of `w_c`).
        kink_opening: f64,
    },
}

impl Softening {
    /// Petersson's (1981) bilinear curve for concrete: `f_t/3` at
    /// `0.8 G_f/f_t`, zero at `3.6 G_f/f_t`.
    pub const PETERSSON: Self = Self::Bilinear { kink_stress: 1.0 / 3.0, kink_opening: 2.0 / 9.0 };

    /// The curve, checked: the kink strictly inside the unit square.
    /// Errors name the parameter as the Python API spells it.
    pub fn checked(self) -> Result<Self, ParameterError> {
        if let Self::Bilinear { kink_stress, kink_opening } = self {
            let inside = |v: f64| v > 0.0 && v < 1.0;
            check("softening", kink_stress, inside(kink_stress), "the kink's traction must lie in (0, 1) of ft")?;
            check("softening", kink_opening, inside(kink_opening), "the kink's opening must lie in (0, 1) of w_c")?;
        }
        Ok(self)
    }

    /// `∫₀¹ s dF` (−): `G_f / (f_t w_c)`.
    pub fn area(&self) -> f64 {
        match *self {
            Self::Linear => 0.5,
            Self::Bilinear { kink_stress, kink_opening } => 0.5 * (kink_opening + kink_stress),
        }
    }

    /// `s(F)` (fraction of `f_t`) at failure factor `f`; 1 below 0, 0 from 1 on.
    pub fn stress(&self, f: f64) -> f64 {
        let f = f.clamp(0.0, 1.0);
        match *self {
            Self::Linear => 1.0 - f,
            Self::Bilinear { kink_stress: s, kink_opening: k } => {
                if f < k {
                    1.0 - (1.0 - s) * f / k
                } else {
                    s * (1.0 - f) / (1.0 - k)
                }
            }
        }
    }

    /// The fraction of `G_f` still to be dissipated at failure factor `f`:
    /// `∫_F¹ s dF / ∫₀¹ s dF` (`(1 − F)²` for the linear curve).
    pub fn remaining(&self, f: f64) -> f64 {
        let f = f.clamp(0.0, 1.0);
        let tail = match *self {
            Self::Linear => 0.5 * (1.0 - f) * (1.0 - f),
            Self::Bilinear { kink_stress: s, kink_opening: k } => {
                if f < k {
                    0.5 * (self.stress(f) + s) * (k - f) + 0.5 * s * (1.0 - k)
                } else {
                    0.5 * self.stress(f) * (1.0 - f)
                }
            }
        };
        tail / self.area()
    }

    /// The steepest slope `max |ds/dF|` (−): 1 for the linear curve.
    pub fn steepest(&self) -> f64 {
        match *self {
            Self::Linear => 1.0,
            Self::Bilinear { kink_stress: s, kink_opening: k } => ((1.0 - s) / k).max(s / (1.0 - k)),
        }
    }

    /// The rest of the curve from failure factor `f`, for a cohesive bond
    /// that takes over there: `Some((at, traction))`, the kink as fractions
    /// of the softening span still to go and of the traction `s(F)`, while
    /// `f` is before the kink; `None` when what is left is straight.
    pub fn kink_after(&self, f: f64) -> Option<(f64, f64)> {
        match *self {
            Self::Linear => None,
            Self::Bilinear { kink_stress: s, kink_opening: k } => {
                // a kink within 10⁻⁶ of the start is no kink
                if f < k * (1.0 - 1e-6) {
                    let f = f.max(0.0);
                    Some(((k - f) / (1.0 - f), s / self.stress(f)))
                } else {
                    None
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Petersson's curve: `w_c = 3.6 G_f / f_t` (area 5/18), the kink at
    /// `f_t/3` and `0.8 G_f / f_t`; the remaining energy falls from 1 to 0
    /// and matches a numerical integral of `s`.
    #[test]
    fn petersson_curve() {
        let p = Softening::PETERSSON;
        assert!((1.0 / p.area() - 3.6).abs() < 1e-12);
        let k = 0.8 * p.area(); // 0.8 G_f / f_t in units of w_c
        assert!((p.stress(k) - 1.0 / 3.0).abs() < 1e-12);
        assert_eq!(p.stress(1.0), 0.0);
        assert!((p.remaining(0.0) - 1.0).abs() < 1e-12);
        assert_eq!(p.remaining(1.0), 0.0);
        for f in [0.05, 0.2, 0.5, 0.9] {
            let n = 200_000;
            let h = (1.0 - f) / n as f64;
            let integral: f64 = (0..n).map(|i| p.stress(f + (i as f64 + 0.5) * h) * h).sum();
            assert!((p.remaining(f) - integral / p.area()).abs() < 1e-6, "F = {f}");
        }
        for f in [0.0, 0.1, 0.5] {
            let l = Softening::Linear;
            assert!((l.remaining(f) - (1.0 - f) * (1.0 - f)).abs() < 1e-15);
        }
        assert!((p.steepest() - 3.0).abs() < 1e-12);
    }

    /// The rest of the curve after `F` keeps its kink at the same point.
    #[test]
    fn the_kink_after_a_point_is_the_curves() {
        let p = Softening::PETERSSON;
        let f = 0.1;
        let (at, q) = p.kink_after(f).expect("before the kink");
        assert!((f + at * (1.0 - f) - 2.0 / 9.0).abs() < 1e-12);
        assert!((q * p.stress(f) - 1.0 / 3.0).abs() < 1e-12);
        assert!(p.kink_after(0.3).is_none());
        assert!(Softening::Linear.kink_after(0.0).is_none());
        assert!(Softening::Bilinear { kink_stress: 1.0, kink_opening: 0.5 }.checked().is_err());
        assert!(Softening::Bilinear { kink_stress: 0.3, kink_opening: 0.0 }.checked().is_err());
    }
}
