//! The description of a model as the solver receives it.

use fdem_material::{CrackBand, Softening};

use fdem_element::Vec2;

use crate::loads::{Amplitude, Constraint, PressureLoad};

/// A material as given by the user: density, elastic constants and law.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialSpec {
    /// Density `ρ` (kg/m³).
    pub density: f64,
    /// Young's modulus `E` (Pa).
    pub young: f64,
    /// Poisson's ratio `ν` (−).
    pub poisson: f64,
    /// The constitutive law beyond elasticity.
    pub law: LawSpec,
}

/// The constitutive law of a material.
#[derive(Clone, Debug, PartialEq)]
pub enum LawSpec {
    /// Linear elasticity only.
    Elastic,
    /// Mohr–Coulomb + Rankine plasticity with fracture-energy softening
    /// (DESIGN §4.3). Angles in radians.
    MohrCoulombRankine {
        /// Cohesion `c` (Pa).
        cohesion: f64,
        /// Friction angle `φ` (rad).
        friction: f64,
        /// Dilation angle `ψ` (rad).
        dilation: f64,
        /// Tensile strength `f_t` (Pa).
        tensile_strength: f64,
        /// Fracture energy `G_f` (N/m): mode I, of the crack band and of
        /// the bonds' opening.
        fracture_energy: f64,
        /// Mode-II fracture energy `G_II` (N/m) of the cohesive bonds
        /// across young cracks: what a bond dissipates in pure slip
        /// (docs/fracture.md, "Mixed-mode bonds"; the continuum's shear
        /// law is perfectly plastic and has none).
        shear_fracture_energy: f64,
        /// Crack-band rule.
        crack_band: CrackBand,
        /// Shape of the softening curve (linear: the paper's).
        softening: Softening,
    },
}

impl LawSpec {
    /// The plastic law this spec describes with the elastic constants
    /// `elastic`, checked (`None` for linear elasticity).
    pub fn plastic(
        &self,
        elastic: fdem_material::Elastic,
    ) -> Result<Option<fdem_material::MohrCoulombRankine>, fdem_material::ParameterError> {
        match *self {
            LawSpec::Elastic => Ok(None),
            LawSpec::MohrCoulombRankine {
                cohesion,
                friction,
                dilation,
                tensile_strength,
                fracture_energy,
                crack_band,
                softening,
                ..
            } => fdem_material::MohrCoulombRankine::new(
                elastic,
                cohesion,
                friction,
                dilation,
                tensile_strength,
                fracture_energy,
                crack_band,
            )
            .and_then(|law| law.with_softening(softening))
            .map(Some),
        }
    }
}

/// Run settings that may change between stages.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Settings {
    /// Mass-proportional damping `α` (1/s).
    pub mass_damping: f64,
    /// Stiffness-proportional (element viscous) damping `β` (s).
    pub stiffness_damping: f64,
    /// Safety factor `s` on the critical step, `0 < s ≤ 1`.
    pub safety: f64,
    /// A fixed step (s) instead of the automatic one, if set.
    pub fixed_dt: Option<f64>,
    /// Steps between re-evaluations of the automatic stable step.
    pub dt_interval: u32,
    /// Energy-growth watchdog: the run stops when the balance shows more
    /// energy created than this fraction of its largest term (default
    /// 0.05), measured with the energy the central-difference scheme
    /// conserves, or with the whole-step energy while the held energy has
    /// grown sixteenfold since the last check (an instability); checked
    /// every [`ENERGY_CHECK_INTERVAL`](crate::ENERGY_CHECK_INTERVAL) steps;
    /// 0 turns the check off.
    pub energy_growth: f64,
    /// Selective mass scaling: the time step `Δt` (s, after the safety
    /// factor) to hold. Where an element or a contact node would need a
    /// shorter step, its elements' density is raised by the factor that
    /// makes it meet `Δt / safety` (docs/mass_scaling.md); `None` leaves
    /// every mass physical.
    // written after the format-1 state in checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub mass_scaling: Option<f64>,
    /// Spatial renumbering (docs/renumbering.md): once crack insertion has
    /// grown the element count by this fraction since the last renumbering
    /// (or the start), and at every multiple of `renumber_every` steps,
    /// nodes and elements are put back in the order of a Hilbert curve
    /// through their positions, for memory locality. Ids, and so
    /// everything read out, stay in creation order. `None`: never.
    // written in format 4 of checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub renumber: Option<f64>,
    /// With `renumber` set, also renumber at every multiple of this many
    /// steps, whatever the growth: falling, mixing rock spoils the order
    /// too (the caving case: [`RENUMBER_INTERVAL`](crate::RENUMBER_INTERVAL)).
    /// `None`: on growth only, so that a run that hardly cracks (a
    /// laboratory test) is never renumbered.
    // written in format 11 of checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub renumber_every: Option<u64>,
    /// Local (non-viscous) damping coefficient `α_L`, `0 ≤ α_L < 1`, as in
    /// FLAC and UDEC (Cundall 1987): each free velocity component of a
    /// node feels `−α_L |f| sign(v)` on top of its net force `f` (`v` its
    /// velocity at the half step before). It damps what moves, not rigid
    /// motion or steady flow, and a linear oscillator loses the same
    /// fraction of its amplitude every half cycle,
    /// `√((1 − α_L)/(1 + α_L))`, whatever its frequency. For quasi-static
    /// stages (equilibrium, excavation); 0 (off) by default. Its work is
    /// booked as damping.
    // written in format 8 of checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub local_damping: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            mass_damping: 0.0,
            stiffness_damping: 0.0,
            safety: 0.8,
            fixed_dt: None,
            dt_interval: 100,
            energy_growth: 0.05,
            mass_scaling: None,
            renumber: None,
            renumber_every: None,
            local_damping: 0.0,
        }
    }
}

/// Everything needed to start a simulation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ModelSpec {
    /// Node reference coordinates (m).
    pub points: Vec<[f64; 2]>,
    /// Triangles, counter-clockwise node ids (u64 so that out-of-range ids
    /// from the caller are reported, not truncated).
    pub triangles: Vec<[u64; 3]>,
    /// Nodes allowed to coincide with another (both sides of an interface).
    pub may_coincide: Vec<bool>,
    /// Material table.
    pub materials: Vec<MaterialSpec>,
    /// Material index of each element.
    pub element_material: Vec<u32>,
    /// Gravitational acceleration (m/s²).
    pub gravity: [f64; 2],
    /// Supports and prescribed velocities.
    pub constraints: Vec<Constraint>,
    /// Surface pressures.
    pub pressures: Vec<PressureLoad>,
    /// Time histories referred to by constraints and pressures.
    pub amplitudes: Vec<Amplitude>,
    /// Initial nodal velocities (m/s), if any.
    pub initial_velocity: Option<Vec<[f64; 2]>>,
    /// Initial element stresses `[xx, yy, zz, xy]` (Pa), if any.
    pub initial_stress: Option<Vec<[f64; 4]>>,
    /// Contact between free surfaces, if enabled.
    pub contact: Option<ContactSpec>,
    /// Crack insertion, if enabled (needs contact).
    pub fracture: Option<FractureSpec>,
    /// Excavation stages: element groups deactivated at given times.
    pub stages: Vec<ExcavationStage>,
    /// Run settings.
    pub settings: Settings,
}

/// One excavation stage (DESIGN §4.6): the elements removed once the
/// simulated time reaches `time`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExcavationStage {
    /// Simulated time (s) at which the stage is excavated.
    pub time: f64,
    /// The elements removed (ids; already removed ones are skipped), with
    /// every piece crack insertion has cut from them.
    pub elements: Vec<u32>,
    /// Release time (s): the forces the removed elements exerted on the
    /// nodes that stay are applied to them as loads that fall linearly to
    /// zero over this time (gradual excavation, as in FLAC and UDEC);
    /// 0 removes them at once.
    // written in format 8 of checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub ramp: f64,
}

/// The loads of a gradual excavation ([`ExcavationStage::ramp`]): the
/// forces the removed elements exerted on the nodes that stay, applied to
/// them from `start` and falling linearly to zero at `start + ramp`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Release {
    /// Time (s) the elements were removed.
    pub start: f64,
    /// Time (s) over which the loads fall to zero.
    pub ramp: f64,
    /// The nodes that carried the removed elements (internal indices).
    pub nodes: Vec<u32>,
    /// Their loads at `start` (N per unit thickness).
    pub forces: Vec<Vec2>,
}

impl Release {
    /// The share of the loads applied at time `t`: 1 at `start`, 0 from
    /// `start + ramp` on.
    pub fn share(&self, t: f64) -> f64 {
        (1.0 - (t - self.start) / self.ramp).clamp(0.0, 1.0)
    }
}

/// Crack insertion (paper 2.4, DESIGN §4.4, docs/fracture.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FractureSpec {
    /// Where cracks go and which triangles they may create.
    pub params: fdem_fracture::FractureParams,
    /// Steps between checks (≥ 1).
    pub interval: u32,
    /// Nodal failure factor `F̄` at which a crack is inserted, in `(0, 1]`.
    /// At 1 (the paper) the band has fully softened and the crack is
    /// traction-free; below 1 the crack is inserted earlier and a cohesive
    /// bond across it dissipates the remaining `(1 − F̄)² G_f`, which avoids
    /// the stress locking of softening bands in triangles.
    pub insert_at: f64,
}

/// Contact between the free surfaces (DESIGN §4.5).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactSpec {
    /// Interface laws; law 0 applies to every facet not listed in
    /// `facet_laws` (free boundaries).
    pub laws: Vec<InterfaceSpec>,
    /// Facets (node pairs, either order) with another law than 0, e.g. the
    /// faces of joints.
    pub facet_laws: Vec<([u32; 2], u16)>,
    /// Law of the faces of cracks inserted during the run.
    pub crack_law: u16,
    /// Broad-phase box enlargement (m); default a fifth of the mean facet
    /// length.
    pub margin: Option<f64>,
}

/// The parameters of one interface law, per unit thickness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceSpec {
    /// Normal stiffness `k_n` (Pa/m): contact pressure per unit penetration.
    pub normal_stiffness: f64,
    /// Shear stiffness `k_s` (Pa/m).
    pub shear_stiffness: f64,
    /// Friction coefficient `μ = tan φ` (−).
    pub friction: f64,
    /// Cohesion (Pa).
    pub cohesion: f64,
    /// Damping ratio of the normal dashpot (−).
    pub damping_ratio: f64,
}
