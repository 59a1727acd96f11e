//! Cohesive bonds across freshly inserted cracks (DESIGN §4.4, as amended
//! in `docs/fracture.md`).
//!
//! A crack inserted before the material around it has fully softened
//! (nodal failure factor `F̄ < 1`) still owes the fracture energy
//! `(1 − F̄)² G_f` per unit length: the part of the linear softening curve
//! the band has not yet travelled. A bond ties the two copies of the split
//! node with a penalty spring and gives it back: traction `t = k (1 − D) d`
//! for the opening vector `d = x_b − x_a`, with the damage `D` driven by the
//! largest opening `δ_max = max |d|` so that the traction follows the
//! linear envelope
//!
//! ```text
//! t_env(δ) = t₀ (δ_c − δ) / (δ_c − δ₀),   δ₀ = t₀ / k ≤ δ ≤ δ_c,
//! ```
//!
//! from the strength left, `t₀ = f_t (1 − F̄)`, to zero at
//! `δ_c = 2 G_f (1 − F̄) / f_t`. The area under the envelope is
//! `½ t₀ δ_c = (1 − F̄)² G_f`: band and bond together dissipate `G_f`.
//!
//! The law is isotropic in `d` (mode II costs what mode I does); a broken
//! bond is dropped and the faces interact by contact alone.

use crate::Vec2;

/// A cohesive bond between node `a` and its copy `b` (per unit thickness).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bond {
    /// The two nodes tied together.
    pub nodes: [u32; 2],
    /// Tributary crack length `ℓ` (m): half of each crack face at the node.
    pub length: f64,
    /// Penalty stiffness `k` (Pa/m).
    pub stiffness: f64,
    /// Strength `t₀` (Pa) left when the crack was inserted.
    pub strength: f64,
    /// Opening `δ_c` (m) at which the traction reaches zero.
    pub final_opening: f64,
    /// Largest opening `δ_max` (m) so far.
    pub max_opening: f64,
    /// Opening (m) the bond counts on top of `d`: the bond acts on
    /// `d + offset`. Set when the crack is inserted so that the bond then
    /// carries the force the elements carried through the split node
    /// (traction continuity; within the elastic range, `|offset| ≤ δ₀`);
    /// zero for a bond that starts slack. Fixed in the global frame: a
    /// bond lives until its crack has opened by `δ_c` (tens of µm), over
    /// which its pieces turn little. Checkpoints keep it beside the
    /// bonds (format 8), so it is not part of this type's serial form.
    #[serde(skip)]
    pub offset: Vec2,
}

/// What one evaluation of a bond gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BondResponse {
    /// Force on node `b` (N per unit thickness); `a` gets its negative.
    pub force: Vec2,
    /// Energy dissipated by this step's damage growth (J per unit thickness).
    pub dissipated: f64,
    /// Elastic energy in the bond after the step (J per unit thickness).
    pub elastic: f64,
    /// The bond has reached `δ_c`: it carries nothing any more.
    pub broken: bool,
}

impl Bond {
    /// Opening at which softening begins, `δ₀ = t₀ / k` (m).
    #[inline]
    pub fn elastic_limit(&self) -> f64 {
        self.strength / self.stiffness
    }

    /// Traction (Pa) on the envelope at opening `delta` (m).
    #[inline]
    fn envelope(&self, delta: f64) -> f64 {
        let d0 = self.elastic_limit();
        if delta <= d0 {
            self.stiffness * delta
        } else if delta >= self.final_opening {
            0.0
        } else {
            self.strength * (self.final_opening - delta) / (self.final_opening - d0)
        }
    }

    /// Secant stiffness `k (1 − D)` (Pa/m) after a largest opening `δ_max`.
    #[inline]
    pub fn secant(&self, max_opening: f64) -> f64 {
        if max_opening <= self.elastic_limit() {
            self.stiffness
        } else {
            self.envelope(max_opening) / max_opening
        }
    }

    /// Energy (J/m² of crack) dissipated once the largest opening is
    /// `δ_max`: the area under the envelope up to `δ_max` less the elastic
    /// energy still held at `δ_max`. `½ t₀ δ_c` at `δ_c`.
    pub fn dissipation(&self, max_opening: f64) -> f64 {
        let d0 = self.elastic_limit();
        if max_opening <= d0 {
            return 0.0;
        }
        let dm = max_opening.min(self.final_opening);
        let span = self.final_opening - d0;
        let area =
            0.5 * self.strength * d0 + self.strength * (dm - d0) - 0.5 * self.strength * (dm - d0).powi(2) / span;
        area - 0.5 * self.envelope(dm) * dm
    }

    /// Fracture energy the bond can dissipate in all, `½ t₀ δ_c` (J/m²).
    pub fn fracture_energy(&self) -> f64 {
        0.5 * self.strength * self.final_opening
    }

    /// Updates the bond for positions `xa`, `xb` (m) and returns its force
    /// and energies.
    pub fn update(&mut self, xa: Vec2, xb: Vec2) -> BondResponse {
        let d = self.opening(xa, xb);
        let delta = (d[0] * d[0] + d[1] * d[1]).sqrt();
        let before = self.dissipation(self.max_opening);
        if delta > self.max_opening {
            self.max_opening = delta;
        }
        let dissipated = (self.dissipation(self.max_opening) - before) * self.length;
        let broken = self.max_opening >= self.final_opening;
        let k = self.current_secant();
        BondResponse {
            force: self.spring_force(k, d),
            dissipated,
            elastic: 0.5 * k * delta * delta * self.length,
            broken,
        }
    }

    /// The force on node `b` (N per unit thickness; `a` gets its negative)
    /// at positions `xa`, `xb` (m) with the damage the bond holds, without
    /// updating it: at the positions of its last [`update`](Self::update),
    /// the force that update returned, to the bit (the same expressions).
    pub fn force(&self, xa: Vec2, xb: Vec2) -> Vec2 {
        self.spring_force(self.current_secant(), self.opening(xa, xb))
    }

    /// The opening the law acts on, `x_b − x_a + offset` (m).
    #[inline]
    fn opening(&self, xa: Vec2, xb: Vec2) -> Vec2 {
        [xb[0] - xa[0] + self.offset[0], xb[1] - xa[1] + self.offset[1]]
    }

    /// Secant stiffness (Pa/m) for the largest opening so far; 0 once broken.
    #[inline]
    fn current_secant(&self) -> f64 {
        if self.max_opening >= self.final_opening {
            0.0
        } else {
            self.secant(self.max_opening)
        }
    }

    /// Force on node `b` of a spring of stiffness `k` (Pa/m) over the
    /// tributary length at the opening `d` (m).
    #[inline]
    fn spring_force(&self, k: f64, d: Vec2) -> Vec2 {
        let s = -k * self.length;
        [s * d[0], s * d[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bond() -> Bond {
        Bond {
            nodes: [0, 1],
            length: 0.5,
            stiffness: 1e12,
            strength: 2e6,
            final_opening: 1e-4,
            max_opening: 0.0,
            offset: [0.0; 2],
        }
    }

    /// Loading to `δ_c` dissipates `½ t₀ δ_c ℓ` whatever the path, and the
    /// traction follows the envelope.
    #[test]
    fn dissipates_the_area_under_the_envelope() {
        let mut b = bond();
        let mut total = 0.0;
        let mut last = BondResponse { force: [0.0; 2], dissipated: 0.0, elastic: 0.0, broken: false };
        // open to 40%, close to 10%, reopen in mixed mode to failure
        let path: Vec<f64> = (0..=400)
            .map(|i| 0.4e-4 * i as f64 / 400.0)
            .chain((0..=300).map(|i| 0.4e-4 - 0.3e-4 * i as f64 / 300.0))
            .chain((0..=1000).map(|i| 0.1e-4 + 0.95e-4 * i as f64 / 1000.0))
            .collect();
        for (i, &delta) in path.iter().enumerate() {
            let dir = if i > 700 { [0.6, 0.8] } else { [1.0, 0.0] };
            last = b.update([0.0, 0.0], [delta * dir[0], delta * dir[1]]);
            total += last.dissipated;
            let t = (last.force[0].powi(2) + last.force[1].powi(2)).sqrt() / b.length;
            assert!(t <= b.envelope(delta) * (1.0 + 1e-12) + 1e-9, "traction {t} above the envelope at {delta}");
        }
        assert!(last.broken);
        let expected = 0.5 * 2e6 * 1e-4 * 0.5;
        assert!((total - expected).abs() < 1e-12 * expected, "{total} vs {expected}");
    }

    /// A bond with an offset carries `k ℓ |offset|` at zero opening, along
    /// the offset, holds `½ k ℓ |offset|²`, and softens from where
    /// `d + offset` reaches `δ₀`: the law shifted by the offset, still
    /// dissipating `½ t₀ δ_c ℓ` in all.
    #[test]
    fn an_offset_bond_carries_its_preload_at_zero_opening() {
        let mut b = bond();
        b.offset = [0.6e-6, 0.8e-6]; // |o| = 1 µm, half of δ₀ = 2 µm
        let r = b.update([0.0, 0.0], [0.0, 0.0]);
        let (k, l) = (b.stiffness, b.length);
        assert_eq!(r.force, [-k * l * 0.6e-6, -k * l * 0.8e-6]);
        assert!((r.elastic - 0.5 * k * l * 1e-12).abs() < 1e-12 * r.elastic);
        assert_eq!(r.dissipated, 0.0);
        // opening along the offset by 1 µm reaches δ₀ exactly: no damage yet
        let r = b.update([0.0, 0.0], [0.6e-6, 0.8e-6]);
        assert_eq!(r.dissipated, 0.0);
        let mut total = 0.0;
        for i in 1..=2000 {
            let delta = 1e-6 + 1e-4 * i as f64 / 2000.0;
            total += b.update([0.0, 0.0], [0.6 * delta, 0.8 * delta]).dissipated;
        }
        let expected = 0.5 * 2e6 * 1e-4 * 0.5;
        assert!((total - expected).abs() < 1e-9 * expected, "{total} vs {expected}");
    }

    /// `force` without an update gives, at the positions of the last update,
    /// the force that update gave, bit for bit (what a restored run's
    /// contact forces are rebuilt with), and changes nothing.
    #[test]
    fn force_repeats_the_last_update() {
        let mut b = bond();
        let xa = [0.1, -0.2];
        for (i, &delta) in [0.3e-4, 0.6e-4, 0.2e-4, 0.99e-4].iter().enumerate() {
            let xb = [xa[0] + 0.6 * delta + 1e-7 * i as f64, xa[1] + 0.8 * delta];
            let r = b.update(xa, xb);
            let kept = b;
            assert_eq!(b.force(xa, xb), r.force);
            assert_eq!(b, kept);
        }
    }

    /// Unloading is elastic along the secant: energy held, none dissipated.
    #[test]
    fn unloading_follows_the_secant() {
        let mut b = bond();
        b.update([0.0; 2], [0.5e-4, 0.0]);
        let held = b.update([0.0; 2], [0.25e-4, 0.0]);
        assert_eq!(held.dissipated, 0.0);
        let k = b.secant(0.5e-4);
        assert!((held.force[0] + k * 0.25e-4 * b.length).abs() < 1e-9);
        assert!((held.elastic - 0.5 * k * (0.25e-4f64).powi(2) * b.length).abs() < 1e-15);
        // the secant at δ_max meets the envelope there
        assert!((k * 0.5e-4 - b.envelope(0.5e-4)).abs() < 1e-6);
    }
}
