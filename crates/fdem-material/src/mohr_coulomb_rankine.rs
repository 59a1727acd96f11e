//! Combined Mohr–Coulomb and Rankine multi-surface plasticity with
//! fracture-energy softening (paper appendices A–C, DESIGN §4.3).
//!
//! In principal space (`σ1 ≥ σ2 ≥ σ3`, tension positive, `σ_zz` one of the
//! three) the surfaces are planes:
//!
//! * Mohr–Coulomb, perfectly plastic, non-associated (dilation `ψ`), written
//!   as twice the paper's A.1:
//!   `f_ij = σ_i (1 + sin φ) − σ_j (1 − sin φ) − 2 c cos φ` for the pairs
//!   `P13` (main plane), `P12` (with P13: the right edge, `σ2 = σ3`) and
//!   `P23` (with P13: the left edge, `σ1 = σ2`); all three: the apex.
//!   Potentials `r_ij` are the same with `ψ`.
//! * Rankine, associated: `g_k = σ_k − σ_y(κ)`, `σ_y = max(f_t − H κ, 0)`,
//!   `H = h_c f_t² / (2 G_f)` (B.1–B.4). One fracturing strain `κ` is shared
//!   by the tensile planes, its increment the sum of their multipliers
//!   (the paper's κ1..κ3 by principal order have no consistent return once a
//!   softened σ1 drops below σ2; DESIGN §4.3). With bilinear softening
//!   ([`Softening`], docs/fracture.md "Softening laws") `σ_y(κ)` has two
//!   straight branches meeting at a kink, and a return is solved on the
//!   branch `κ` is on, then, if it crosses the kink, on the second.
//!
//! For an active set `A` the return `σ = σ^tr − Σ Δγ_β C n_β`,
//! `κ = κⁿ + Σ_{β∈R} Δγ_β` keeps every active function at zero: the linear
//! system `G Δγ = f(σ^tr)` with `G_αβ = a_α · C n_β − H [α,β ∈ R]` (C.1–C.24
//! in one form). Candidate sets are tried in order of increasing size and the
//! first consistent one is taken: multipliers ≥ 0, every function ≤ 0,
//! principal order kept. No iteration, no allocation.
//!
//! With softening and non-associated flow more than one set can be
//! consistent (about 1% of random trials beyond both surfaces): typically a
//! Mohr–Coulomb return that lands inside the tension cut-off, and one that
//! also activates a tensile plane and softens down to the returned σ1. The
//! rule, in order: fewer active planes first; among equally many,
//! Mohr–Coulomb-only sets before sets with tensile planes (a crack only
//! opens when the shear return alone cannot satisfy the cut-off); then the
//! linear softening branch before the exhausted one. The tests check this
//! rule against a brute-force enumeration of all 63 plane combinations.
//!
//! Over 800 lines without tests: the return mapping is one algorithm (the
//! trial, the active sets in order, their closed-form solutions, the
//! consistency test and the softening branches), each part written against
//! the invariants of the others; its tests are in `tests/return_mapping.rs`.

pub use crate::crack_band::{CrackBand, Geometry};
use crate::dense::{solve, MAX};
use crate::elastic::Elastic;
use crate::principal::{DirectionCode, Order, Spectral};
use crate::softening::Softening;
use crate::{check, ParameterError};

/// The six planes, as bits of an active set.
pub mod surface {
    /// Mohr–Coulomb main plane (σ1, σ3).
    pub const P13: u8 = 1;
    /// Mohr–Coulomb plane (σ1, σ2).
    pub const P12: u8 = 2;
    /// Mohr–Coulomb plane (σ2, σ3).
    pub const P23: u8 = 4;
    /// Rankine plane on σ1.
    pub const R1: u8 = 8;
    /// Rankine plane on σ2.
    pub const R2: u8 = 16;
    /// Rankine plane on σ3.
    pub const R3: u8 = 32;
    /// All Mohr–Coulomb planes.
    pub const MC: u8 = P13 | P12 | P23;
    /// All Rankine planes.
    pub const RANKINE: u8 = R1 | R2 | R3;
    /// Bits in plane order.
    pub const ALL: [u8; 6] = [P13, P12, P23, R1, R2, R3];
}
use surface::*;

/// The candidate active sets: main plane; σ1 plane; left edge; right edge;
/// σ1+σ2 planes; main + σ1 (C.10); apex; tensile corner (C.4); right edge +
/// σ1 (C.13); left edge + σ1 + σ2 (C.19).
pub const CANDIDATES: [u8; 10] = [
    P13,
    R1,
    P13 | P23,
    P13 | P12,
    R1 | R2,
    P13 | R1,
    P13 | P12 | P23,
    R1 | R2 | R3,
    P13 | P12 | R1,
    P13 | P23 | R1 | R2,
];

/// The order in which `(set, exhausted branch)` returns are tried: by number
/// of planes, then Mohr–Coulomb-only before tensile, then the linear
/// softening branch before the exhausted one (module notes).
pub const RETURN_ORDER: [(u8, bool); 16] = [
    (P13, false),
    (R1, false),
    (R1, true),
    (P13 | P23, false),
    (P13 | P12, false),
    (R1 | R2, false),
    (P13 | R1, false),
    (R1 | R2, true),
    (P13 | R1, true),
    (P13 | P12 | P23, false),
    (R1 | R2 | R3, false),
    (P13 | P12 | R1, false),
    (R1 | R2 | R3, true),
    (P13 | P12 | R1, true),
    (P13 | P23 | R1 | R2, false),
    (P13 | P23 | R1 | R2, true),
];

/// The material parameters, checked.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MohrCoulombRankine {
    /// Elastic constants.
    pub elastic: Elastic,
    /// Cohesion `c` (Pa).
    pub cohesion: f64,
    /// Friction angle `φ` (rad).
    pub friction: f64,
    /// Dilation angle `ψ` (rad).
    pub dilation: f64,
    /// Tensile strength `f_t` (Pa).
    pub tensile_strength: f64,
    /// Fracture energy `G_f` (N/m = J/m²).
    pub fracture_energy: f64,
    /// Crack-band rule.
    pub crack_band: CrackBand,
    /// Shape of the softening curve ([`Softening`]); linear unless set by
    /// [`Self::with_softening`]. Checkpoints keep it beside the materials
    /// (format 10), so it is not part of this type's serial form.
    #[serde(skip)]
    pub softening: Softening,
    sin_phi: f64,
    cos_phi: f64,
    sin_psi: f64,
    /// Potential gradient `n_β` of each plane (constant for these linear surfaces).
    n: [[f64; 3]; 6],
    /// `C n_β` of each plane.
    cn: [[f64; 3]; 6],
    /// `a_α · C n_β` of each pair of planes.
    acn: [[f64; 6]; 6],
}

/// What the law remembers per material point.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlasticState {
    /// Fracturing strain `κ` (−), the shared Rankine hardening variable.
    pub kappa: f64,
    /// Crack-band width `h_c` (m); zero until the point first reaches `f_t`.
    pub crack_band: f64,
    /// Direction of σ1 in the co-rotational frame at the last tensile
    /// plastic step, the rotating crack's normal, as a
    /// [`DirectionCode`](crate::principal::DirectionCode) (0: the x axis):
    /// see [`PlasticState::crack_angle`].
    pub direction_code: f64,
    /// Plastic strain `[xx, yy, zz, xy]` (co-rotational, tensor shear).
    pub plastic_strain: [f64; 4],
    /// Accumulated equivalent plastic strain `Σ √(2/3 Δεᵖ:Δεᵖ)`.
    pub equivalent_plastic_strain: f64,
}

impl PlasticState {
    /// Direction of the crack normal (rad from x, co-rotational frame, in
    /// `[−π/2, π/2]`).
    pub fn crack_angle(&self) -> f64 {
        DirectionCode::angle(self.direction_code)
    }

    /// The crack normal as the doubled-angle unit vector `(cos 2θ, sin 2θ)`
    /// (co-rotational frame), without a trigonometric call.
    pub fn crack_doubled(&self) -> [f64; 2] {
        DirectionCode::doubled(self.direction_code)
    }
}

/// The result of one update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Update {
    /// New co-rotational stress `[xx, yy, zz, xy]` (Pa).
    pub stress: [f64; 4],
    /// Active set (bits of [`surface`]); 0 for an elastic step.
    pub active: u8,
    /// Mohr–Coulomb plastic dissipation of the step (J/m³).
    pub plastic_dissipation: f64,
    /// Tensile (fracture) dissipation of the step (J/m³).
    pub fracture_dissipation: f64,
}

/// What every return from one trial shares: the sorted trial principal
/// stresses, the fracturing strain, the tensile strength and softening
/// modulus there, and the six yield functions on the linear softening
/// branch (those past full softening, zero strength, are worked out only
/// if a return on that branch is tried). Worked out once per
/// update instead of once per active set tried (most plastic points try
/// two or more). A return with a multiplier `x` such that `2G x < −reject`
/// (Pa) is refused as soon as it is solved: the consistency check with
/// tolerance `reject` would refuse it (most candidate sets fail so).
struct Trial {
    s: [f64; 3],
    kappa: f64,
    band: f64,
    sy: f64,
    h: f64,
    f: [f64; 6],
    reject: f64,
}

impl Trial {
    fn new(law: &MohrCoulombRankine, s: [f64; 3], kappa: f64, crack_band: f64, reject: f64) -> Self {
        let (sy, h) = law.strength(kappa, crack_band);
        Self { s, kappa, band: crack_band, sy, h, f: law.yield_functions(s, sy), reject }
    }
}

/// A return in principal space, before it is accepted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipalReturn {
    /// Returned principal stresses (sorted as the trial was).
    pub stress: [f64; 3],
    /// Multipliers per plane, in [`surface::ALL`] order.
    pub multipliers: [f64; 6],
    /// New fracturing strain.
    pub kappa: f64,
    /// Tensile strength at `kappa`.
    pub strength: f64,
}

impl MohrCoulombRankine {
    /// Checked parameters. Angles in radians: `0 ≤ ψ ≤ φ < π/2`; `c ≥ 0`,
    /// `0 < f_t ≤ c cot φ` (the tension cut-off inside the Mohr–Coulomb apex),
    /// `G_f > 0`. Errors name the parameter as the Python API spells it.
    pub fn new(
        elastic: Elastic,
        cohesion: f64,
        friction: f64,
        dilation: f64,
        tensile_strength: f64,
        fracture_energy: f64,
        crack_band: CrackBand,
    ) -> Result<Self, ParameterError> {
        let quarter = std::f64::consts::FRAC_PI_2;
        check("c", cohesion, cohesion >= 0.0, "cohesion must be >= 0")?;
        check(
            "phi",
            friction.to_degrees(),
            (0.0..quarter).contains(&friction),
            "friction angle must lie in [0, 90) degrees",
        )?;
        check(
            "psi",
            dilation.to_degrees(),
            (0.0..quarter).contains(&dilation),
            "dilation angle must lie in [0, 90) degrees",
        )?;
        check("psi", dilation.to_degrees(), dilation <= friction, "dilation angle must not exceed the friction angle")?;
        check("ft", tensile_strength, tensile_strength > 0.0, "tensile strength must be positive")?;
        let apex = if friction > 0.0 { cohesion / friction.tan() } else { f64::INFINITY };
        check(
            "ft",
            tensile_strength,
            tensile_strength <= apex * (1.0 + 1e-12),
            &format!("tensile strength must not exceed c*cot(phi) = {apex:.6e} Pa (the Mohr-Coulomb apex)"),
        )?;
        check("Gf", fracture_energy, fracture_energy > 0.0, "fracture energy must be positive")?;
        let mut law = Self {
            elastic,
            cohesion,
            friction,
            dilation,
            tensile_strength,
            fracture_energy,
            crack_band,
            softening: Softening::Linear,
            sin_phi: friction.sin(),
            cos_phi: friction.cos(),
            sin_psi: dilation.sin(),
            n: [[0.0; 3]; 6],
            cn: [[0.0; 3]; 6],
            acn: [[0.0; 6]; 6],
        };
        for (j, &b) in ALL.iter().enumerate() {
            law.n[j] = law.gradients(b).1;
            law.cn[j] = law.c_times(law.n[j]);
        }
        for (i, &b) in ALL.iter().enumerate() {
            let a = law.gradients(b).0;
            for j in 0..6 {
                law.acn[i][j] = a[0] * law.cn[j][0] + a[1] * law.cn[j][1] + a[2] * law.cn[j][2];
            }
        }
        Ok(law)
    }

    /// The law with softening curve `softening`, checked.
    pub fn with_softening(mut self, softening: Softening) -> Result<Self, ParameterError> {
        self.softening = softening.checked()?;
        Ok(self)
    }

    /// Critical crack opening `w_c = G_f / (f_t ∫s)` (m), at which the
    /// traction reaches zero: `2 G_f / f_t` for linear softening.
    pub fn critical_opening(&self) -> f64 {
        self.fracture_energy / (self.tensile_strength * self.softening.area())
    }

    /// Uniaxial compressive strength `2 c cos φ / (1 − sin φ)` (Pa).
    pub fn ucs(&self) -> f64 {
        2.0 * self.cohesion * self.cos_phi / (1.0 - self.sin_phi)
    }

    /// `N_φ = (1 + sin φ) / (1 − sin φ)`.
    pub fn n_phi(&self) -> f64 {
        (1.0 + self.sin_phi) / (1.0 - self.sin_phi)
    }

    /// `N_ψ = (1 + sin ψ) / (1 − sin ψ)`.
    pub fn n_psi(&self) -> f64 {
        (1.0 + self.sin_psi) / (1.0 - self.sin_psi)
    }

    /// Largest element size without snap-back (m): the band whose
    /// steepest softening slope equals the plane-strain modulus
    /// `E' = E / (1 − ν²)`, `E' w_c / (f_t max|s'|)`; `2 E' G_f / f_t²` for
    /// linear softening.
    pub fn snap_back_size(&self) -> f64 {
        match self.softening {
            Softening::Linear => {
                2.0 * self.elastic.plane_strain_modulus() * self.fracture_energy
                    / (self.tensile_strength * self.tensile_strength)
            }
            s => self.elastic.plane_strain_modulus() * self.critical_opening() / (self.tensile_strength * s.steepest()),
        }
    }

    /// Initial softening modulus (Pa) for a band `h_c` (m): `H = h_c f_t² /
    /// (2 G_f)` for linear softening, the first branch's `h_c f_t (1 − s_k)
    /// / (F_k w_c)` for bilinear.
    pub fn softening_modulus(&self, crack_band: f64) -> f64 {
        match self.softening {
            Softening::Linear => {
                crack_band * self.tensile_strength * self.tensile_strength / (2.0 * self.fracture_energy)
            }
            Softening::Bilinear { kink_stress, kink_opening } => {
                crack_band * self.tensile_strength * (1.0 - kink_stress) / (kink_opening * self.critical_opening())
            }
        }
    }

    /// Crack-band width `h_c` (m) of an element of shape `geometry` for a
    /// crack normal at `angle` (rad, co-rotational frame), by the law's rule.
    pub fn band_width(&self, geometry: &Geometry, angle: f64) -> f64 {
        match self.crack_band {
            CrackBand::Oliver => geometry.width_along(angle),
            CrackBand::Equivalent => geometry.equivalent_diameter(),
        }
    }

    /// The widest crack band `h_c` (m) the law's rule gives an element of
    /// shape `geometry`, over every crack direction: the longest edge for
    /// [`CrackBand::Oliver`], the one width of [`CrackBand::Equivalent`].
    /// An element is fit for the law when this is at most
    /// [`snap_back_size`](Self::snap_back_size).
    pub fn largest_band_width(&self, geometry: &Geometry) -> f64 {
        match self.crack_band {
            CrackBand::Oliver => geometry.diameter(),
            CrackBand::Equivalent => geometry.equivalent_diameter(),
        }
    }

    /// Re-regularises a softening state for a piece of a split element
    /// (DESIGN §4.4): `h_c` scales with the piece's width over the parent's,
    /// both measured along the crack normal (the band rule's width for
    /// [`CrackBand::Equivalent`]), and κ by the inverse, so that the failure
    /// factor and the softened strength are continuous and what the piece has
    /// left to dissipate is `r(F) G_f` per unit crack area (`(1 − F)²` for
    /// linear softening; [`Softening::remaining`]), as for its
    /// parent. A piece keeping the parent's wider band would be more brittle
    /// than the material: it would fail with `G_f h_piece / h_parent`.
    /// States that have not cracked are left alone.
    pub fn rebase(&self, state: &mut PlasticState, parent: &Geometry, piece: &Geometry) {
        if state.crack_band <= 0.0 {
            return;
        }
        let angle = state.crack_angle();
        let (before, after) = (self.band_width(parent, angle), self.band_width(piece, angle));
        if before > 0.0 && after > 0.0 {
            let ratio = after / before;
            state.kappa /= ratio;
            state.crack_band *= ratio;
        }
    }

    /// Failure factor `F = κ h_c / w_c` (eq. 2.21: `κ / ε_c^f`, `κ H / f_t`
    /// for linear softening), the crack opening over the critical one; 1
    /// means fully softened, 0 before the first crack.
    pub fn failure_factor(&self, state: &PlasticState) -> f64 {
        if state.crack_band > 0.0 {
            match self.softening {
                Softening::Linear => state.kappa * self.softening_modulus(state.crack_band) / self.tensile_strength,
                Softening::Bilinear { .. } => state.kappa * state.crack_band / self.critical_opening(),
            }
        } else {
            0.0
        }
    }

    /// Tensile strength and effective softening modulus at `kappa` for a
    /// band `crack_band`: `(max(f_t − Hκ, 0), H or 0 once fully softened)`
    /// for linear softening; for bilinear, the branch `κ` is on.
    fn strength(&self, kappa: f64, crack_band: f64) -> (f64, f64) {
        let h = self.softening_modulus(crack_band);
        let s = self.tensile_strength - h * kappa;
        if let Softening::Bilinear { kink_stress, .. } = self.softening {
            if s <= kink_stress * self.tensile_strength {
                let (h2, kappa_max) = self.second_branch(crack_band);
                return if kappa < kappa_max { (h2 * (kappa_max - kappa), h2) } else { (0.0, 0.0) };
            }
        }
        if s > 0.0 {
            (s, h)
        } else {
            (0.0, 0.0)
        }
    }

    /// The second branch of bilinear softening for a band `crack_band`
    /// (m): its modulus `h_c f_t s_k / ((1 − F_k) w_c)` (Pa) and the
    /// fracturing strain `w_c / h_c` at which it reaches zero.
    fn second_branch(&self, crack_band: f64) -> (f64, f64) {
        let w_c = self.critical_opening();
        let (s_k, f_k) = match self.softening {
            Softening::Bilinear { kink_stress, kink_opening } => (kink_stress, kink_opening),
            Softening::Linear => (0.0, 0.0),
        };
        (crack_band * self.tensile_strength * s_k / ((1.0 - f_k) * w_c), w_c / crack_band)
    }

    /// The six yield functions at sorted principal stresses `s` and tensile
    /// strength `sy`, in [`surface::ALL`] order (Pa; the MC ones doubled as
    /// in the module notes).
    pub fn yield_functions(&self, s: [f64; 3], sy: f64) -> [f64; 6] {
        let (sp, k) = (self.sin_phi, 2.0 * self.cohesion * self.cos_phi);
        let mc = |i: usize, j: usize| s[i] * (1.0 + sp) - s[j] * (1.0 - sp) - k;
        [mc(0, 2), mc(0, 1), mc(1, 2), s[0] - sy, s[1] - sy, s[2] - sy]
    }

    /// Gradient `a` of the yield function and `n` of the potential of plane
    /// `bit` in principal space.
    pub fn gradients(&self, bit: u8) -> ([f64; 3], [f64; 3]) {
        let (sp, ss) = (self.sin_phi, self.sin_psi);
        let pair = |i: usize, j: usize, s: f64| {
            let mut v = [0.0; 3];
            v[i] = 1.0 + s;
            v[j] = -(1.0 - s);
            v
        };
        match bit {
            P13 => (pair(0, 2, sp), pair(0, 2, ss)),
            P12 => (pair(0, 1, sp), pair(0, 1, ss)),
            P23 => (pair(1, 2, sp), pair(1, 2, ss)),
            R1 => ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
            R2 => ([0.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
            _ => ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
        }
    }

    /// `C n` in principal space: `λ (n1 + n2 + n3) + 2G n_k`.
    fn c_times(&self, n: [f64; 3]) -> [f64; 3] {
        let l = self.elastic.lambda * (n[0] + n[1] + n[2]);
        let g = 2.0 * self.elastic.mu;
        [l + g * n[0], l + g * n[1], l + g * n[2]]
    }

    /// The return to the planes of `active` from sorted trial principal
    /// stresses `s`, fracturing strain `kappa` and band `crack_band`, on one
    /// branch of the softening law: `exhausted = false` for linear softening
    /// (the strength must stay ≥ 0), `true` for the part past full softening
    /// (zero strength; valid only if the step's `Δκ` reaches `f_t/H`).
    /// `None` when the branch does not apply or its system is singular
    /// (for bilinear softening, a first branch's return with a multiplier
    /// negative beyond [`Self::tolerance`] gives way to the second
    /// branch's). Not checked for consistency.
    pub fn principal_return(
        &self,
        s: [f64; 3],
        active: u8,
        kappa: f64,
        crack_band: f64,
        exhausted: bool,
    ) -> Option<PrincipalReturn> {
        self.return_to(&Trial::new(self, s, kappa, crack_band, f64::INFINITY), active, exhausted)
    }

    /// [`Self::principal_return`] from a trial whose strength and yield
    /// functions are worked out once for every set tried.
    fn return_to(&self, t: &Trial, active: u8, exhausted: bool) -> Option<PrincipalReturn> {
        if !exhausted {
            let on_branch = self.solve_set(t.s, active, t.kappa, t.sy, t.h, &t.f, t.reject);
            let Softening::Bilinear { kink_stress, .. } = self.softening else {
                return on_branch.filter(|r| r.strength >= 0.0);
            };
            if t.h == 0.0 || active & RANKINE == 0 {
                // exhausted, or no tensile plane: κ does not move
                return on_branch.filter(|r| r.strength >= 0.0);
            }
            let (h2, kappa_max) = self.second_branch(t.band);
            if t.h == h2 {
                // on the second branch already
                return on_branch.filter(|r| r.strength >= 0.0);
            }
            // on the first branch: its return if it stays before the kink,
            // else the second branch's. With one tensile plane the residual
            // falls strictly with Δκ (no branch steeper than the stiffness
            // below the snap-back size), so exactly one branch holds. With
            // two or three (stiffness λ + μ or the bulk modulus, below E')
            // the first branch can be steeper than the set's stiffness; its
            // solution then has Δκ < 0, which `solve_set` refuses (`reject`),
            // and the second branch's or the exhausted one's is taken.
            let kink = kink_stress * self.tensile_strength;
            // (a negative multiplier is refused here too, as `update`'s
            // `reject` does, so that `principal_return` agrees)
            let (g2, tol) = (2.0 * self.elastic.mu, self.tolerance(t.s));
            let admissible = |r: &PrincipalReturn| r.multipliers.iter().all(|&x| x * g2 >= -tol);
            if let Some(r) = on_branch.filter(|r| r.strength >= kink * (1.0 - 1e-12) && admissible(r)) {
                return Some(r);
            }
            let sy = h2 * (kappa_max - t.kappa);
            return self
                .solve_set(t.s, active, t.kappa, sy, h2, &self.yield_functions(t.s, sy), t.reject)
                .filter(|r| r.strength >= 0.0 && r.strength <= kink * (1.0 + 1e-12));
        }
        if t.h == 0.0 || active & RANKINE == 0 {
            return None; // already exhausted: the linear branch covers it
        }
        let kappa_max = match self.softening {
            Softening::Linear => self.tensile_strength / t.h,
            Softening::Bilinear { .. } => self.second_branch(t.band).1,
        };
        self.solve_set(t.s, active, t.kappa, 0.0, 0.0, &self.yield_functions(t.s, 0.0), t.reject)
            .filter(|r| r.kappa >= kappa_max * (1.0 - 1e-12))
            .map(|mut r| {
                r.strength = 0.0;
                r
            })
    }

    /// The return to the planes of `active` with strength `sy`, softening
    /// modulus `h` and `f` the yield functions at `s` for `sy`; `None` also
    /// when a multiplier `x` has `2G x < −reject` (Pa), which
    /// [`Self::is_consistent`] with tolerance `reject` would refuse.
    #[allow(clippy::too_many_arguments)]
    fn solve_set(
        &self,
        s: [f64; 3],
        active: u8,
        kappa: f64,
        sy: f64,
        h: f64,
        f: &[f64; 6],
        reject: f64,
    ) -> Option<PrincipalReturn> {
        let g2 = 2.0 * self.elastic.mu;
        if active == P13 | P23 | R1 | R2 {
            return self.left_edge_tensile_corner(s, kappa, sy, h, f);
        }
        if active.count_ones() == 1 {
            // one plane (bit k is plane k of ALL): a single division
            let k = active.trailing_zeros() as usize;
            let tensile = k >= 3;
            let g = self.acn[k][k] - if tensile { h } else { 0.0 };
            if g.is_nan() || g <= 0.0 {
                return None;
            }
            let x = f[k] / g;
            if x * g2 < -reject {
                return None;
            }
            let cn = &self.cn[k];
            let mut multipliers = [0.0; 6];
            multipliers[k] = x;
            let dk = if tensile { x } else { 0.0 };
            return Some(PrincipalReturn {
                stress: [s[0] - x * cn[0], s[1] - x * cn[1], s[2] - x * cn[2]],
                multipliers,
                kappa: kappa + dk,
                strength: sy - h * dk,
            });
        }
        // plane indices (positions in ALL) of the active set
        let mut idx = [0usize; MAX];
        let mut n = 0;
        for (k, b) in ALL.iter().enumerate() {
            if active & b != 0 {
                if n == MAX {
                    return None;
                }
                idx[n] = k;
                n += 1;
            }
        }
        let mut g = [[0.0; MAX]; MAX];
        let mut rhs = [0.0; MAX];
        for i in 0..n {
            rhs[i] = f[idx[i]];
            for j in 0..n {
                g[i][j] = self.acn[idx[i]][idx[j]];
                if idx[i] >= 3 && idx[j] >= 3 {
                    g[i][j] -= h;
                }
            }
        }
        let x = solve(g, rhs, n)?;
        if x[..n].iter().any(|&x| x * g2 < -reject) {
            return None;
        }
        let mut out = s;
        let mut multipliers = [0.0; 6];
        let mut dk = 0.0;
        for j in 0..n {
            let cn = &self.cn[idx[j]];
            for k in 0..3 {
                out[k] -= x[j] * cn[k];
            }
            multipliers[idx[j]] = x[j];
            if idx[j] >= 3 {
                dk += x[j];
            }
        }
        Some(PrincipalReturn { stress: out, multipliers, kappa: kappa + dk, strength: sy - h * dk })
    }

    /// The corner of C.19: left edge (P13 + P23) with the σ1 and σ2 planes.
    /// With σ1 = σ2 = σ_y the two Mohr–Coulomb conditions coincide, so the
    /// four-plane system is singular: the stress is unique, the split of the
    /// Mohr–Coulomb multiplier between `n13` and `n23` is not. Since
    /// `n23 = n13 − (1 + sin ψ)(e1 − e2)`, moving `b` from P13 to P23 changes
    /// the σ1 and σ2 multipliers by `±b (1 + sin ψ)` and leaves the plastic
    /// strain and κ unchanged. Solve P13 + R1 + R2, then take the middle of
    /// the range of `b` that keeps all four multipliers non-negative.
    fn left_edge_tensile_corner(
        &self,
        s: [f64; 3],
        kappa: f64,
        sy: f64,
        h: f64,
        f: &[f64; 6],
    ) -> Option<PrincipalReturn> {
        // (its multipliers are redistributed below: none refused early)
        let mut r = self.solve_set(s, P13 | R1 | R2, kappa, sy, h, f, f64::INFINITY)?;
        let (total, c0, d0) = (r.multipliers[0], r.multipliers[3], r.multipliers[4]);
        let k = 1.0 + self.sin_psi;
        let lo = 0.0f64.max(-c0 / k);
        let hi = total.min(d0 / k);
        let b = if lo <= hi { 0.5 * (lo + hi) } else { 0.0 };
        r.multipliers[0] = total - b;
        r.multipliers[2] = b;
        r.multipliers[3] = c0 + b * k;
        r.multipliers[4] = d0 - b * k;
        Some(r)
    }

    /// Whether a return is admissible: multipliers ≥ 0, every yield
    /// function ≤ 0 and the principal order kept, within `tol` (Pa).
    pub fn is_consistent(&self, r: &PrincipalReturn, tol: f64) -> bool {
        // written with `&=` over comparisons so that a NaN anywhere fails
        let g2 = 2.0 * self.elastic.mu;
        let s = r.stress;
        let mut ok = s[0] >= s[1] - tol && s[1] >= s[2] - tol;
        for x in r.multipliers {
            ok &= x * g2 >= -tol;
        }
        if !ok {
            // most candidate sets fail here: skip their yield functions
            return false;
        }
        for f in self.yield_functions(s, r.strength) {
            ok &= f <= tol;
        }
        ok
    }

    /// Stress tolerance of the consistency checks for trial `s` (Pa).
    pub fn tolerance(&self, s: [f64; 3]) -> f64 {
        1e-9 * (s[0].abs().max(s[2].abs()) + self.cohesion + self.tensile_strength)
    }

    /// The elastic-plastic update of one material point.
    ///
    /// `old` is the co-rotational stress at the start of the step, `trial`
    /// the elastic trial `old + C : D̂ Δt` (Pa); `geometry` is called for the
    /// element's shape only when the point first reaches `f_t`. Updates `state` and returns
    /// the new stress with the dissipation of the step, measured as
    /// `½ (σⁿ + σⁿ⁺¹) : Δεᵖ`, which makes the internal work equal to the
    /// change of elastic energy plus the dissipation exactly.
    pub fn update(
        &self,
        old: [f64; 4],
        trial: [f64; 4],
        state: &mut PlasticState,
        geometry: impl FnOnce() -> Geometry,
    ) -> Update {
        // before the first crack κ = 0 and the strength is f_t whatever the band
        let band = if state.crack_band > 0.0 { state.crack_band } else { 1.0 };
        let sy = self.strength(state.kappa, band).0;
        let elastic = Update { stress: trial, active: 0, plastic_dissipation: 0.0, fracture_dissipation: 0.0 };
        if self.surely_elastic(trial, sy) {
            return elastic;
        }
        let sp = Spectral::of(trial);
        let (s, order) = Order::sort(sp.a, sp.b, trial[2]);
        let tol = self.tolerance(s);
        // σ1 ≥ σ2 ≥ σ3 makes the main plane and the σ1 plane the largest of
        // their families: the point is elastic if both are inside
        let main = s[0] * (1.0 + self.sin_phi) - s[2] * (1.0 - self.sin_phi) - 2.0 * self.cohesion * self.cos_phi;
        let tensile = s[0] - sy;
        if main <= tol && tensile <= tol {
            return elastic;
        }
        if state.crack_band == 0.0 && tensile > tol {
            let geometry = geometry();
            state.crack_band = self.band_width(&geometry, sp.angle());
        }
        let band = if state.crack_band > 0.0 { state.crack_band } else { 1.0 };
        let t = Trial::new(self, s, state.kappa, band, tol);
        let mut chosen: Option<(u8, PrincipalReturn)> = None;
        for &(set, exhausted) in &RETURN_ORDER {
            if set & RANKINE != 0 && state.crack_band == 0.0 {
                continue;
            }
            if let Some(r) = self.return_to(&t, set, exhausted) {
                if self.is_consistent(&r, tol) {
                    chosen = Some((set, r));
                    break;
                }
            }
        }
        let Some((active, r)) = chosen.or_else(|| self.least_violating(&t, state)) else {
            return Update { stress: trial, active: 0, plastic_dissipation: 0.0, fracture_dissipation: 0.0 };
        };
        // plastic strain increments in principal space, split MC / tensile
        let mut de_mc = [0.0; 3];
        let mut de_t = [0.0; 3];
        for k in 0..6 {
            let x = r.multipliers[k];
            if x == 0.0 {
                continue;
            }
            let target = if k >= 3 { &mut de_t } else { &mut de_mc };
            for i in 0..3 {
                target[i] += x * self.n[k][i];
            }
        }
        let [a, b, zz] = order.unsort(r.stress);
        let stress = sp.compose(a, b, zz);
        // Δεᵖ is coaxial with the trial, so ½(σⁿ + σⁿ⁺¹) : Δεᵖ only needs the
        // normal components of σⁿ on the trial's principal axes
        let old_on_axes = order.sort_like(sp.normal_components(old));
        let work = |d: [f64; 3]| (0..3).map(|k| 0.5 * (old_on_axes[k] + r.stress[k]) * d[k]).sum::<f64>();
        let total = [de_mc[0] + de_t[0], de_mc[1] + de_t[1], de_mc[2] + de_t[2]];
        let [ta, tb, tz] = order.unsort(total);
        let increment = sp.compose(ta, tb, tz);
        for k in 0..4 {
            state.plastic_strain[k] += increment[k];
        }
        let sq = total[0] * total[0] + total[1] * total[1] + total[2] * total[2];
        state.equivalent_plastic_strain += (2.0 / 3.0 * sq).sqrt();
        if active & RANKINE != 0 {
            state.kappa = r.kappa;
            state.direction_code = sp.direction_code();
        }
        Update { stress, active, plastic_dissipation: work(de_mc), fracture_dissipation: work(de_t) }
    }

    /// Whether trial `[xx, yy, zz, xy]` is inside both the main plane and
    /// the cut-off at strength `sy` by the test of [`Self::update`], shown
    /// without the square root of the principal stresses: with the in-plane
    /// radius bounded by `r ≤ |σ_xx − σ_yy|/2 + |σ_xy|` (padded by 10⁻¹⁵
    /// against round-off), upper and lower bounds of σ1 and σ3 put into the
    /// same expressions (floating-point operations are monotone) give upper
    /// bounds of the main-plane and cut-off functions, and the tolerance is
    /// at least its value at zero stress. `false` says nothing: the full
    /// test decides. Most points of a loaded rock mass are well inside and
    /// pass here (at 3.5 s of the paper-scale caving run, two thirds of the
    /// updates are elastic).
    #[inline]
    fn surely_elastic(&self, trial: [f64; 4], sy: f64) -> bool {
        let mean = 0.5 * (trial[0] + trial[1]);
        let half = 0.5 * (trial[0] - trial[1]);
        let r_up = (half.abs() + trial[3].abs()) * (1.0 + 1e-15);
        let (a_up, b_lo, zz) = (mean + r_up, mean - r_up, trial[2]);
        // written with comparisons, not `max`/`min`, so that a NaN in the
        // in-plane part carries into `main_up` and fails the test; a NaN
        // `σ_zz` fails it explicitly (it would not reach the in-plane
        // forces, so the full test must see it)
        let s1_up = if zz >= a_up { zz } else { a_up };
        let s3_lo = if zz <= b_lo { zz } else { b_lo };
        let main_up = s1_up * (1.0 + self.sin_phi) - s3_lo * (1.0 - self.sin_phi) - 2.0 * self.cohesion * self.cos_phi;
        let tol_lo = self.tolerance([0.0; 3]);
        main_up <= tol_lo && s1_up - sy <= tol_lo && !zz.is_nan()
    }

    /// Fallback when no candidate is consistent within tolerance (a round-off
    /// corner case): the candidate with non-negative multipliers and the
    /// smallest violation.
    fn least_violating(&self, t: &Trial, state: &PlasticState) -> Option<(u8, PrincipalReturn)> {
        let mut best: Option<(f64, u8, PrincipalReturn)> = None;
        for &(set, exhausted) in &RETURN_ORDER {
            if set & RANKINE != 0 && state.crack_band == 0.0 {
                continue;
            }
            let Some(r) = self.return_to(t, set, exhausted) else {
                continue;
            };
            if r.multipliers.iter().any(|&x| x < 0.0) {
                continue;
            }
            let v = self.yield_functions(r.stress, r.strength).iter().fold(0.0f64, |m, &f| m.max(f));
            if best.is_none_or(|(bv, _, _)| v < bv) {
                best = Some((v, set, r));
            }
        }
        best.map(|(_, set, r)| (set, r))
    }
}
