//! Cohesive bonds across freshly inserted cracks (DESIGN §4.4, as amended
//! in `docs/fracture.md`).
//!
//! A crack inserted before the material around it has fully softened
//! (nodal failure factor `F̄ < 1`) still owes the fracture energy
//! `(1 − F̄)² G_f` per unit length: the part of the linear softening curve
//! the band has not yet travelled. A bond ties the two copies of the split
//! node with a penalty spring `k` and gives it back.
//!
//! **Mixed mode** (bonds made since checkpoint format 9; docs/fracture.md,
//! "Mixed-mode bonds"). The opening `d = x_b − x_a` splits along the
//! crack's normal `n` into an opening `δ_n = d·n` and a slip `δ_s = d·t`.
//! Tension and slip soften with one damage `D`; compression is never
//! damaged (a closed crack pushes back whatever its damage):
//!
//! ```text
//! t_n = (1 − D) k δ_n  (δ_n > 0),   t_n = k δ_n  (δ_n ≤ 0),   t_s = (1 − D) k δ_s.
//! ```
//!
//! Strengths: `T = f_t (1 − F̄)` in tension, `S = c (1 − F̄) + σ_c tan φ` in
//! shear with the compression the bond carries, `σ_c = k ⟨−δ_n⟩` (Mohr–
//! Coulomb, the material's `c` and `φ`). Along the current mode (`cos β =
//! ⟨δ_n⟩/δ_m`, `sin β = |δ_s|/δ_m`, `δ_m = √(⟨δ_n⟩² + δ_s²)`) damage starts
//! where the tractions meet the quadratic criterion `(t_n/T)² + (t_s/S)² =
//! 1`, at `δ_m⁰ = 1 / (k √((cos β / T)² + (sin β / S)²))`, and the traction
//! falls linearly to zero at `δ_m^f = 2 G_c / (k δ_m⁰)` with the mode's
//! fracture energy `G_c = G_I cos²β + G_II sin²β` (Camanho & Dávila 2002;
//! Benzeggagh & Kenane 1996 with exponent 1). `D` is the largest damage so
//! far. Pure opening dissipates `G_I = ½ T δ_c`, pure slip `G_II`, at any
//! normal stress: under compression `S` grows and the slip at failure
//! shrinks.
//!
//! **Isotropic** (bonds restored from a format ≤ 8 file, `mode` `None`):
//! traction `t = k (1 − D) d`, `D` driven by the largest opening
//! `δ_max = max |d|` along the linear envelope from `t₀` at `δ₀ = t₀/k` to
//! zero at `δ_c`: mode II costs what mode I does.
//!
//! Either way `½ t₀ δ_c = (1 − F̄)² G_f` in pure opening: band and bond
//! together dissipate `G_f`. A broken bond is dropped and the faces interact
//! by contact alone.
//!
//! **Bilinear softening** (materials with a bilinear curve, checkpoint
//! format 10). A bond made before its material's kink continues the curve
//! from there: its mixed-mode envelope falls from the peak `T_m = k δ_m⁰`
//! straight to a [`Kink`] (`q T_m` at `δ_m⁰ + a (δ_m^f − δ_m⁰)`), then
//! straight to zero at `δ_m^f`, the fractions `a` and `q` those of the
//! material's curve after `F̄`. Its area is still `G_c`, so `δ_m^f = δ_m⁰ +
//! (G_c − ½ T_m δ_m⁰) / (T_m (a + q)/2)`; `½ t₀ δ_c` is then the mode-I
//! energy `G_f` owes past `F̄`, no longer the opening where the traction
//! ends. Without a kink the envelope is the linear one.

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
    /// Opening `δ_c` (m) at which the traction reaches zero in pure
    /// opening on a straight envelope; generally `2 G_I / t₀`, with `G_I`
    /// the mode-I energy the bond dissipates (module notes: a bond with a
    /// [`Kink`] ends further out).
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
    /// The mixed-mode law and its damage; `None`: the isotropic law of a
    /// bond restored from a format ≤ 8 checkpoint. Checkpoints keep it
    /// beside the bonds (format 9).
    #[serde(skip)]
    pub mode: Option<MixedMode>,
}

/// The mixed-mode part of a bond: its crack's normal, shear strength and
/// mode-II fracture energy, and its damage (module notes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MixedMode {
    /// Unit normal of the crack (global frame), from `a`'s side to `b`'s:
    /// `δ_n = (x_b − x_a + offset)·n > 0` opens the crack. Fixed when the
    /// crack is inserted (a bond lives until its crack has opened or slid
    /// by tens of µm, over which its pieces turn little).
    pub normal: Vec2,
    /// Shear strength `c (1 − F̄)` (Pa) at zero normal stress.
    pub cohesion: f64,
    /// Friction coefficient `tan φ` (−) of the strength's pressure term.
    pub friction: f64,
    /// Mode-II fracture energy `G_II (1 − F̄)²` (J/m²) the bond dissipates
    /// in pure slip.
    pub shear_energy: f64,
    /// Damage `D` (0 to 1), the largest so far.
    pub damage: f64,
    /// The kink of a bilinear envelope; `None`: straight (module notes).
    /// Checkpoints keep it beside the bonds (format 10), so it is not part
    /// of this type's serial form.
    #[serde(skip)]
    pub kink: Option<Kink>,
}

/// Where a bilinear envelope bends, as fractions of the envelope of the
/// current mode (module notes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Kink {
    /// Position `a` along the softening span, from the onset (0) to the
    /// final opening (1), `0 < a < 1`.
    pub at: f64,
    /// Traction there `q`, as a fraction of the peak, `0 < q < 1`.
    pub traction: f64,
}

/// Opening `δ_n = d·n` and slip `δ_s = d·t`, `t = (−n_y, n_x)` (m), of
/// the opening `d` across the crack of normal `m.normal`.
#[inline]
fn components(m: &MixedMode, d: Vec2) -> (f64, f64) {
    let n = m.normal;
    (d[0] * n[0] + d[1] * n[1], d[1] * n[0] - d[0] * n[1])
}

/// The linear envelope of the current mode, in the mixed-mode opening
/// `δ_m` (m): damage onset `δ_m⁰` and final opening `δ_m^f`.
#[derive(Clone, Copy, Debug)]
struct Envelope {
    onset: f64,
    last: f64,
    kink: Option<Kink>,
}

impl Envelope {
    /// Damage `δ_m^f (δ − δ_m⁰) / (δ (δ_m^f − δ_m⁰))` at opening `delta`
    /// (m) on a straight envelope, `1 − t(δ)/(k δ)` on a kinked one: zero
    /// before onset, one at `δ_m^f`.
    #[inline]
    fn damage(&self, k: f64, delta: f64) -> f64 {
        if delta <= self.onset {
            0.0
        } else if delta >= self.last {
            1.0
        } else if self.kink.is_some() {
            1.0 - self.kinked_traction(k, delta) / (k * delta)
        } else {
            self.last * (delta - self.onset) / (delta * (self.last - self.onset))
        }
    }

    /// The kinked envelope's corners: peak `T`, the kink's opening and
    /// traction.
    #[inline]
    fn corners(&self, k: f64, kink: Kink) -> (f64, f64, f64) {
        let peak = k * self.onset;
        (peak, self.onset + kink.at * (self.last - self.onset), kink.traction * peak)
    }

    /// Traction (Pa) on a kinked envelope at `onset ≤ delta ≤ last`.
    #[inline]
    fn kinked_traction(&self, k: f64, delta: f64) -> f64 {
        let Some(kink) = self.kink else { return 0.0 };
        let (peak, dk, tk) = self.corners(k, kink);
        if delta <= dk {
            // a first branch of no length (a kink at the onset, to the
            // last bit) is the peak
            if dk > self.onset {
                peak - (peak - tk) * (delta - self.onset) / (dk - self.onset)
            } else {
                peak
            }
        } else {
            tk * (self.last - delta) / (self.last - dk)
        }
    }

    /// [`Self::dissipation`] on a kinked envelope: the opening at which
    /// the damage is `d` solves `t(δ) = k (1 − d) δ` on the branch where
    /// it falls, `δ = A / (k (1 − d) + B)` for a branch `t = A − B δ`.
    fn kinked_dissipation(&self, k: f64, kink: Kink, d: f64) -> f64 {
        let (a, f) = (self.onset, self.last);
        let (peak, dk, tk) = self.corners(k, kink);
        let b1 = if dk > a { (peak - tk) / (dk - a) } else { 0.0 };
        let b2 = tk / (f - dk);
        let delta = if d >= 1.0 {
            f
        } else if d <= 1.0 - tk / (k * dk) {
            ((peak + b1 * a) / (k * (1.0 - d) + b1)).clamp(a, dk)
        } else {
            ((b2 * f) / (k * (1.0 - d) + b2)).clamp(dk, f)
        };
        let t = self.kinked_traction(k, delta);
        let first = delta.min(dk);
        let mut area = 0.5 * peak * a + 0.5 * (peak + self.kinked_traction(k, first)) * (first - a);
        if delta > dk {
            area += 0.5 * (tk + t) * (delta - dk);
        }
        area - 0.5 * t * delta
    }

    /// Energy (J/m²) dissipated, along this mode, once the damage is `d`:
    /// the area under the envelope up to the opening at which the damage is
    /// `d`, less the elastic energy held there; `G_c` at `d = 1`.
    fn dissipation(&self, k: f64, d: f64) -> f64 {
        if d <= 0.0 {
            return 0.0;
        }
        if let Some(kink) = self.kink {
            return self.kinked_dissipation(k, kink, d);
        }
        let (a, f) = (self.onset, self.last);
        let span = f - a;
        // the opening at which this mode's damage is d
        let delta = if d >= 1.0 { f } else { (f * a / (f - d * span)).min(f) };
        let peak = k * a;
        let area = 0.5 * peak * a + peak * (delta - a) - 0.5 * peak * (delta - a).powi(2) / span;
        area - 0.5 * peak * (f - delta) / span * delta
    }
}

/// What one evaluation of a bond gives.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Opening at which softening begins in pure opening, `δ₀ = t₀ / k`
    /// (m) (for the isotropic law, in any direction).
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

    /// Secant stiffness `k (1 − D)` (Pa/m) of the isotropic law (and of
    /// the mixed law in pure opening) after a largest opening `δ_max`.
    #[inline]
    pub fn secant(&self, max_opening: f64) -> f64 {
        if max_opening <= self.elastic_limit() {
            self.stiffness
        } else {
            self.envelope(max_opening) / max_opening
        }
    }

    /// Energy (J/m² of crack) the isotropic law (and the mixed law in pure
    /// opening) has dissipated once the largest opening is `δ_max`: the
    /// area under the envelope up to `δ_max` less the elastic energy still
    /// held at `δ_max`. `½ t₀ δ_c` at `δ_c`.
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

    /// Fracture energy the bond dissipates in pure opening, `½ t₀ δ_c`
    /// (J/m²): all it can for the isotropic law; the mixed law's mode-I
    /// energy `G_I` (pure slip: [`MixedMode::shear_energy`]).
    pub fn fracture_energy(&self) -> f64 {
        0.5 * self.strength * self.final_opening
    }

    /// Updates the bond for positions `xa`, `xb` (m) and returns its force
    /// and energies.
    pub fn update(&mut self, xa: Vec2, xb: Vec2) -> BondResponse {
        let d = self.opening(xa, xb);
        let delta = (d[0] * d[0] + d[1] * d[1]).sqrt();
        if let Some(mut m) = self.mode {
            if delta > self.max_opening {
                self.max_opening = delta;
            }
            let (dn, ds) = components(&m, d);
            let (dm, env) = self.mixed_envelope(&m, dn, ds);
            let now = env.damage(self.stiffness, dm);
            // most bonds most steps hold or unload: no damage grows and
            // nothing is dissipated (what the difference below gives then)
            let mut dissipated = 0.0;
            if now > m.damage {
                let before = m.damage;
                m.damage = now;
                dissipated =
                    (env.dissipation(self.stiffness, now) - env.dissipation(self.stiffness, before)) * self.length;
                self.mode = Some(m);
            }
            let (force, elastic) = self.mixed_force(&m, dn, ds);
            return BondResponse { force, dissipated, elastic, broken: m.damage >= 1.0 };
        }
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
        let d = self.opening(xa, xb);
        match &self.mode {
            Some(m) => {
                let (dn, ds) = components(m, d);
                self.mixed_force(m, dn, ds).0
            }
            None => self.spring_force(self.current_secant(), d),
        }
    }

    /// The damage `D` (0 to 1) the bond holds.
    pub fn damage(&self) -> f64 {
        match &self.mode {
            Some(m) => m.damage,
            None => 1.0 - self.current_secant() / self.stiffness,
        }
    }

    /// The factor (at most 1) that brings an opening `o` (m), taken from
    /// zero damage, inside the elastic range: where the bond holds it
    /// without damage starting (`δ₀ / |o|` for the isotropic law; the onset
    /// of `o`'s mode over its mixed-mode opening for the mixed one).
    pub fn elastic_scale(&self, o: Vec2) -> f64 {
        match &self.mode {
            Some(m) => {
                let (dn, ds) = components(m, o);
                let (dm, env) = self.mixed_envelope(m, dn, ds);
                if dm <= env.onset {
                    1.0
                } else {
                    env.onset / dm
                }
            }
            None => (self.elastic_limit() / (o[0] * o[0] + o[1] * o[1]).sqrt()).min(1.0),
        }
    }

    /// The mixed-mode opening `δ_m = √(⟨δ_n⟩² + δ_s²)` (m) at opening `dn`
    /// and slip `ds` (m), and the envelope of their mode (module notes).
    #[inline]
    fn mixed_envelope(&self, m: &MixedMode, dn: f64, ds: f64) -> (f64, Envelope) {
        let k = self.stiffness;
        let open = dn.max(0.0);
        let t0 = self.strength;
        // the shear strength with the compression the bond carries; a
        // material without cohesion still gives a bond a little, so that
        // its envelope stays finite
        let s0 = (m.cohesion + m.friction * k * (-dn).max(0.0)).max(1e-3 * t0);
        let dm = (open * open + ds * ds).sqrt();
        let (c, s) = if dm > 0.0 { (open / dm, ds.abs() / dm) } else { (1.0, 0.0) };
        let onset = 1.0 / (k * ((c / t0).powi(2) + (s / s0).powi(2)).sqrt());
        let g = 0.5 * t0 * self.final_opening * c * c + m.shear_energy * s * s;
        let last = match m.kink {
            None => 2.0 * g / (k * onset),
            Some(kink) => {
                let peak = k * onset;
                onset + (g - 0.5 * peak * onset) / (0.5 * peak * (kink.at + kink.traction))
            }
        };
        (dm, Envelope { onset, last: last.max(onset * (1.0 + 1e-9)), kink: m.kink })
    }

    /// Force on node `b` and elastic energy of the mixed-mode law at
    /// opening `dn` and slip `ds` (m) with the damage `m` holds; nothing
    /// once broken.
    #[inline]
    fn mixed_force(&self, m: &MixedMode, dn: f64, ds: f64) -> (Vec2, f64) {
        if m.damage >= 1.0 {
            return ([0.0; 2], 0.0);
        }
        let (k, keep) = (self.stiffness, 1.0 - m.damage);
        let tn = if dn > 0.0 { keep * k * dn } else { k * dn };
        let ts = keep * k * ds;
        let n = m.normal;
        let s = -self.length;
        let force = [s * (tn * n[0] - ts * n[1]), s * (tn * n[1] + ts * n[0])];
        let open = dn.max(0.0);
        let closed = dn.min(0.0);
        let elastic = 0.5 * k * (keep * (open * open + ds * ds) + closed * closed) * self.length;
        (force, elastic)
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
            mode: None,
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

    /// A mixed-mode bond: T = 2 MPa, δ_c = 0.1 mm (G_I = 100 J/m²), S = 5 MPa
    /// at zero normal stress, tan φ = 0.8, G_II = 400 J/m², crack normal
    /// along (0.6, 0.8).
    fn mixed() -> Bond {
        Bond {
            mode: Some(MixedMode {
                normal: [0.6, 0.8],
                cohesion: 5e6,
                friction: 0.8,
                shear_energy: 400.0,
                damage: 0.0,
                kink: None,
            }),
            ..bond()
        }
    }

    /// Drives `b` along openings `(δ_n, δ_s)` (crack frame) and returns the
    /// dissipated energy, the largest normal and shear tractions (Pa) and
    /// whether it broke.
    fn drive(b: &mut Bond, path: impl Iterator<Item = (f64, f64)>) -> (f64, f64, f64, bool) {
        let n = b.mode.expect("mixed").normal;
        let (mut total, mut tn_max, mut ts_max, mut broken) = (0.0, 0.0_f64, 0.0_f64, false);
        for (dn, ds) in path {
            let d = [dn * n[0] - ds * n[1], dn * n[1] + ds * n[0]];
            let r = b.update([0.0; 2], d);
            total += r.dissipated;
            // traction on b's face, in the crack frame
            let t = [-r.force[0] / b.length, -r.force[1] / b.length];
            tn_max = tn_max.max(t[0] * n[0] + t[1] * n[1]);
            ts_max = ts_max.max((t[1] * n[0] - t[0] * n[1]).abs());
            broken |= r.broken;
        }
        (total, tn_max, ts_max, broken)
    }

    fn ramp(to: f64, steps: usize) -> impl Iterator<Item = f64> {
        (0..=steps).map(move |i| to * i as f64 / steps as f64)
    }

    /// Pure opening: the traction peaks at T and the bond dissipates
    /// `G_I ℓ = ½ T δ_c ℓ`, exactly (the closed form of the linear
    /// envelope, any step size).
    #[test]
    fn mixed_pure_opening_dissipates_g_i() {
        let mut b = mixed();
        let (w, tn, ts, broken) = drive(&mut b, ramp(1.2e-4, 300).map(|x| (x, 0.0)));
        assert!(broken);
        let expected = 0.5 * 2e6 * 1e-4 * b.length;
        assert!((w - expected).abs() < 1e-9 * expected, "{w} vs {expected}");
        assert!((tn - 2e6).abs() < 2e6 * 1e-2, "peak normal traction {tn}");
        assert!(ts < 1e-9 * tn, "shear traction {ts} in pure opening");
    }

    /// Pure slip at zero normal stress: the traction peaks at S = c and
    /// the bond dissipates `G_II ℓ`, whichever way it slides.
    #[test]
    fn mixed_pure_slip_dissipates_g_ii() {
        for sign in [1.0, -1.0] {
            let mut b = mixed();
            // G_II / S: δ_s^f = 2 · 400 / 5e6 = 0.16 mm
            let (w, tn, ts, broken) = drive(&mut b, ramp(sign * 2e-4, 4000).map(|x| (0.0, x)));
            assert!(broken);
            let expected = 400.0 * b.length;
            assert!((w - expected).abs() < 1e-9 * expected, "{w} vs {expected}");
            assert!((ts - 5e6).abs() < 5e6 * 1e-3, "peak shear traction {ts}");
            assert!(tn < 1e-9 * ts, "normal traction {tn} in pure slip");
        }
    }

    /// Under a compression σ_c the bond is stronger in shear, S = c +
    /// σ_c tan φ (Mohr–Coulomb), breaks at a smaller slip, still
    /// dissipates G_II, and its compression is not damaged.
    #[test]
    fn mixed_compression_strengthens_shear() {
        let k = 1e12;
        for sigma in [0.0, 2e6, 10e6] {
            let mut b = mixed();
            let dn = -sigma / k;
            let (w, _, ts, broken) = drive(&mut b, ramp(2e-4, 8000).map(|x| (dn, x)));
            assert!(broken);
            let strength = 5e6 + 0.8 * sigma;
            assert!((ts - strength).abs() < strength * 2e-3, "σ_c {sigma}: peak {ts} vs {strength}");
            let expected = 400.0 * b.length;
            assert!((w - expected).abs() < 1e-9 * expected, "σ_c {sigma}: {w} vs {expected}");
        }
        // half damaged in slip, then pushed shut: the full stiffness pushes back
        let mut b = mixed();
        drive(&mut b, ramp(1e-4, 1000).map(|x| (0.0, x)));
        let d = b.mode.expect("mixed").damage;
        assert!(d > 0.3 && d < 1.0, "damage {d}");
        let (_, _, _, _) = drive(&mut b, std::iter::once((-1e-6, 0.0)));
        let f = b.force([0.0; 2], [-0.6e-6, -0.8e-6]);
        // the force on b pushes it back to its side of the crack (along n)
        let push = (f[0] * 0.6 + f[1] * 0.8) / b.length;
        assert!((push - k * 1e-6).abs() < 1e-6 * k * 1e-6, "compression {push}");
    }

    /// A proportional path at mode angle β: damage starts where the
    /// tractions meet the quadratic criterion (t_n/T)² + (t_s/S)² = 1,
    /// and the bond dissipates `G_I cos²β + G_II sin²β`.
    #[test]
    fn mixed_proportional_path_follows_the_interaction() {
        for beta in [0.3_f64, 0.8, 1.2] {
            let mut b = mixed();
            let (c, s) = (beta.cos(), beta.sin());
            let mut onset = None;
            let n = b.mode.expect("mixed").normal;
            // steps of 1 nm: a twentieth of a per cent of the onset opening
            for x in ramp(3e-4, 300_000) {
                let d = [x * c * n[0] - x * s * n[1], x * c * n[1] + x * s * n[0]];
                let before = b;
                let r = b.update([0.0; 2], d);
                if onset.is_none() && b.mode.expect("mixed").damage > 0.0 {
                    // tractions of the last undamaged state
                    let f = before.force([0.0; 2], d);
                    let t = [-f[0] / b.length, -f[1] / b.length];
                    onset =
                        Some(((t[0] * n[0] + t[1] * n[1]) / 2e6).powi(2) + ((t[1] * n[0] - t[0] * n[1]) / 5e6).powi(2));
                }
                if r.broken {
                    break;
                }
            }
            let q = onset.expect("damage started");
            assert!((q - 1.0).abs() < 2e-3, "β {beta}: criterion {q} at onset");
        }
        for beta in [0.3_f64, 0.8, 1.2] {
            let mut b = mixed();
            let (c, s) = (beta.cos(), beta.sin());
            let (w, _, _, broken) = drive(&mut b, ramp(3e-4, 30000).map(|x| (x * c, x * s)));
            assert!(broken);
            let expected = (100.0 * c * c + 400.0 * s * s) * b.length;
            assert!((w - expected).abs() < 1e-9 * expected, "β {beta}: {w} vs {expected}");
        }
    }

    /// A bond on the rest of Petersson's curve from its start (kink at
    /// 2/9 of the span and a third of the peak): in pure opening the
    /// traction falls from T to T/3 at the kink and on to zero, each step's
    /// traction within 10⁻⁹ of the two straight branches (unloading and
    /// reloading on the secant), and the bond dissipates `G_I = ½ T δ_c`
    /// in all, in pure slip `G_II`, to 10⁻⁹ (the closed form of the
    /// kinked envelope's area).
    #[test]
    fn kinked_envelope_follows_its_branches_and_dissipates_g() {
        let kinked = || {
            let mut b = mixed();
            if let Some(m) = b.mode.as_mut() {
                m.kink = Some(Kink { at: 2.0 / 9.0, traction: 1.0 / 3.0 });
            }
            b
        };
        let mut b = kinked();
        let (k, t0) = (b.stiffness, b.strength);
        let onset = t0 / k;
        // G_I = 100 J/m²: the span from the envelope's area, (a + q)/2 = 5/18
        let last = onset + (100.0 - 0.5 * t0 * onset) / (t0 * 5.0 / 18.0);
        let knee = onset + 2.0 / 9.0 * (last - onset);
        let branch = |d: f64| {
            if d <= onset {
                k * d
            } else if d <= knee {
                t0 - (t0 - t0 / 3.0) * (d - onset) / (knee - onset)
            } else {
                (t0 / 3.0 * (last - d) / (last - knee)).max(0.0)
            }
        };
        let n = b.mode.expect("mixed").normal;
        let mut largest = 0.0_f64;
        let mut total = 0.0;
        let path: Vec<f64> = ramp(0.5 * knee, 500)
            .chain(ramp(0.5 * knee, 100).map(|x| 0.5 * knee - x))
            .chain(ramp(1.1 * last, 5000))
            .collect();
        for d in path {
            let r = b.update([0.0; 2], [d * n[0], d * n[1]]);
            total += r.dissipated;
            let t = -(r.force[0] * n[0] + r.force[1] * n[1]) / b.length;
            if d >= largest {
                assert!((t - branch(d)).abs() < 1e-9 * t0, "opening {d}: {t} against {}", branch(d));
            }
            largest = largest.max(d);
        }
        let expected = 100.0 * b.length;
        assert!((total - expected).abs() < 1e-9 * expected, "{total} vs {expected}");
        assert!(b.damage() >= 1.0);
        let mut b = kinked();
        let (w, _, ts, broken) = drive(&mut b, ramp(1e-3, 20_000).map(|x| (0.0, x)));
        assert!(broken);
        assert!((ts - 5e6).abs() < 5e6 * 1e-3, "peak shear traction {ts}");
        let expected = 400.0 * b.length;
        assert!((w - expected).abs() < 1e-9 * expected, "{w} vs {expected}");
    }

    /// `force` repeats the last update bit for bit for the mixed law too,
    /// and `elastic_scale` keeps an offset inside the elastic range.
    #[test]
    fn mixed_force_repeats_and_offsets_stay_elastic() {
        let mut b = mixed();
        let xa = [0.1, -0.2];
        for (i, &delta) in [0.3e-5, 0.6e-4, 0.2e-4, 0.9e-4].iter().enumerate() {
            let xb = [xa[0] + 0.3 * delta + 1e-7 * i as f64, xa[1] - 0.9 * delta];
            let r = b.update(xa, xb);
            assert_eq!(b.force(xa, xb), r.force);
        }
        for o in [[3e-6, 0.0], [0.0, 1e-5], [-2e-6, 4e-6], [1e-9, 1e-9]] {
            let mut fresh = mixed();
            let k = fresh.elastic_scale(o);
            assert!(k > 0.0 && k <= 1.0);
            fresh.offset = [o[0] * k, o[1] * k];
            let r = fresh.update([0.0; 2], [0.0; 2]);
            assert!(r.dissipated <= 1e-12 * r.elastic, "offset {o:?}: {}", r.dissipated);
            assert!(fresh.damage() < 1e-9);
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
