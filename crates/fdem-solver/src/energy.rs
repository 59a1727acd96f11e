//! Energy bookkeeping (DESIGN §4.2, §6).
//!
//! Work terms are accumulated each step from per-chunk partial sums reduced in
//! chunk order. A force acting at step `n` is paired with the centred
//! displacement `(Δx^{n−½} + Δx^{n+½}) / 2`, which makes the half-step
//! kinetic-energy change of the central-difference scheme exact; kinetic and
//! elastic energy are evaluated at whole steps when reported.
//!
//! [`EnergyLedger`] holds what a run accumulates: the account, the passes'
//! per-chunk partial sums and the energy-growth watchdog's last look.

use crate::clock::Clock;
use crate::error::RunError;

/// Energies of the whole model (J per unit thickness).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Energies {
    /// Kinetic energy at the current whole step.
    pub kinetic: f64,
    /// Elastic strain energy `Σ A ½ σ : C⁻¹ : σ`.
    pub elastic: f64,
    /// Elastic strain energy at the start of the run (initial stress).
    pub elastic_initial: f64,
    /// Kinetic energy at the start of the run.
    pub kinetic_initial: f64,
    /// Work of gravity and surface loads.
    pub external_work: f64,
    /// Work of the reactions of supports and prescribed velocities.
    pub support_work: f64,
    /// Dissipated by mass-proportional damping.
    pub mass_damping: f64,
    /// Dissipated by stiffness-proportional (element viscous) damping.
    pub viscous_damping: f64,
    /// Dissipated by Mohr–Coulomb plastic flow.
    pub plastic: f64,
    /// Dissipated by fracture: tensile softening in the elements and the
    /// damage of cohesive bonds.
    pub fracture: f64,
    /// Dissipated by friction (slip) on contacts.
    pub friction: f64,
    /// Dissipated by the contact dashpots.
    pub contact_damping: f64,
    /// Elastic energy in the contact penalty springs now.
    pub contact_elastic: f64,
    /// Elastic energy in the cohesive bonds across young cracks now (their
    /// dissipation is part of `fracture`).
    pub cohesive_elastic: f64,
    /// Kinetic energy lost when cracks are inserted (mass moved to new nodes
    /// with interpolated velocities; ≥ 0, second order in the velocity
    /// differences across the split edges).
    pub remeshing: f64,
    /// Energy held in contact springs and cohesive bonds that crack
    /// insertions released (positive) or created (negative) by re-forming
    /// the contacts on the new surfaces at unchanged positions: a node's
    /// tributary length changes with its facets, a contact at a facet that
    /// no longer exists is resumed or dropped. Measured at each insertion as
    /// the held energy after the re-evaluation minus before, so that it is
    /// kept apart from the dynamics' balance (docs/caving.md).
    pub resurfacing: f64,
    /// Taken out of the model by excavation: the elastic energy of the
    /// removed elements, the kinetic energy of the mass that left with them,
    /// and the elastic energy of bonds to nodes that left.
    pub excavated: f64,
    /// Kinetic energy taken by selective mass scaling: a node whose mass
    /// is raised during the run keeps its momentum, so its kinetic energy
    /// drops by `(1 − m_old/m_new)` (an inelastic accretion; ≥ 0).
    // written after the format-1 state in checkpoints (checkpoint.rs)
    #[serde(skip)]
    pub mass_scaling: f64,
    /// Work done on the nodes by contact and bond forces (a diagnostic:
    /// ideally `−(contact_elastic + friction + contact_damping +
    /// cohesive_elastic + bond dissipation)`).
    pub contact_work: f64,
    /// Internal work `∫ σ : D dV dt` done on the elements; equals the elastic
    /// energy change plus plastic and fracture dissipation up to the
    /// integration error (a diagnostic).
    pub internal_work: f64,
}

impl Energies {
    /// The energy-balance residual `W_ext + W_support + E_kin,0 + E_el,0 −
    /// (E_kin + E_el + dissipation)`; zero for an exact integration.
    pub fn residual(&self) -> f64 {
        let supplied = self.external_work + self.support_work + self.kinetic_initial + self.elastic_initial;
        supplied - self.kinetic - self.elastic - self.dissipated()
    }

    /// The largest magnitude among the terms of the balance (J per unit
    /// thickness): the scale the residual is judged against.
    pub fn largest_term(&self) -> f64 {
        [
            self.kinetic,
            self.elastic,
            self.elastic_initial,
            self.kinetic_initial,
            self.external_work,
            self.support_work,
            self.mass_damping,
            self.viscous_damping,
            self.plastic,
            self.fracture,
            self.friction,
            self.contact_damping,
            self.contact_elastic,
            self.cohesive_elastic,
            self.remeshing,
            self.resurfacing,
            self.excavated,
            self.mass_scaling,
        ]
        .iter()
        .fold(0.0, |m, t| m.max(t.abs()))
    }

    /// Everything dissipated, held outside the elements, or taken out so
    /// far: damping, plastic flow, fracture, friction, contact damping, the
    /// energy in contact springs and bonds, remeshing losses, energy held in
    /// contacts released by re-forming them at insertions, excavation, mass
    /// scaling.
    pub fn dissipated(&self) -> f64 {
        self.mass_damping
            + self.viscous_damping
            + self.plastic
            + self.fracture
            + self.friction
            + self.contact_damping
            + self.contact_elastic
            + self.cohesive_elastic
            + self.remeshing
            + self.resurfacing
            + self.excavated
            + self.mass_scaling
    }
}

/// Per-chunk partial sums of the node pass.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct NodePartial {
    pub external: f64,
    pub contact: f64,
    pub contact_damping: f64,
    pub support: f64,
    pub damping: f64,
    /// Largest `|v^{n+½}|²` of the chunk (m²/s²; NaN if any is).
    pub max_speed2: f64,
    pub bad_node: Option<(u32, &'static str)>,
}

impl NodePartial {
    /// Adds `o`'s sums to these (the second stage of a node pass).
    pub fn merge(&mut self, o: &NodePartial) {
        self.external += o.external;
        self.contact += o.contact;
        self.contact_damping += o.contact_damping;
        self.support += o.support;
        self.damping += o.damping;
        if o.max_speed2 > self.max_speed2 || o.max_speed2.is_nan() {
            self.max_speed2 = o.max_speed2;
        }
        self.bad_node = self.bad_node.or(o.bad_node);
    }
}

/// Per-chunk partial sums of the element pass.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct ElementPartial {
    pub internal: f64,
    pub plastic: f64,
    pub fracture: f64,
    pub viscous: f64,
    pub bad_element: Option<u32>,
}

/// The energy account of a run and what feeds it: the per-chunk partial
/// sums the node and element passes fill each step (sized to the mesh's
/// chunk counts, [`Self::size_partials`]), added to the account in chunk
/// order, and the held energy at the watchdog's last check.
///
/// Checkpoints write the account and the held energy (in this order; the
/// partials are scratch): the bytes of the two loose fields the saved
/// state had before the ledger was a struct.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct EnergyLedger {
    /// The work and dissipation terms accumulated step by step, without
    /// the pending second halves of the last step's work
    /// ([`Simulation::energies`](crate::Simulation::energies) adds them).
    pub account: Energies,
    /// Held energy (kinetic + elastic) at the last energy-growth check.
    held_seen: f64,
    /// Partial sums of the node pass, one per chunk of nodes.
    #[serde(skip)]
    pub node_partials: Vec<NodePartial>,
    /// Partial sums of the element pass, one per chunk of elements.
    #[serde(skip)]
    pub elem_partials: Vec<ElementPartial>,
}

impl EnergyLedger {
    /// A fresh account with partial sums for `nodes` nodes and `elems`
    /// elements.
    pub fn new(nodes: usize, elems: usize) -> Self {
        let mut ledger = EnergyLedger::default();
        ledger.size_partials(nodes, elems);
        ledger
    }

    /// Sizes the partial sums for a mesh of `nodes` nodes and `elems`
    /// elements (the passes never resize them).
    pub fn size_partials(&mut self, nodes: usize, elems: usize) {
        self.node_partials.resize(nodes.div_ceil(crate::CHUNK), Default::default());
        self.elem_partials.resize(elems.div_ceil(crate::CHUNK), Default::default());
    }

    /// Adds the node pass's partial sums to the account, in chunk order.
    /// Returns the largest `|v^{n+½}|²` (NaN if any is) and the first node
    /// found with a non-finite value.
    pub fn add_node_partials(&mut self) -> (f64, Option<(u32, &'static str)>) {
        let mut bad_node = None;
        let mut max_speed2 = 0.0f64;
        let acc = &mut self.account;
        for p in &self.node_partials {
            // a NaN is kept (the run stops at the bad node anyway)
            if p.max_speed2 > max_speed2 || p.max_speed2.is_nan() {
                max_speed2 = p.max_speed2;
            }
            acc.external_work += p.external;
            acc.contact_work += p.contact;
            acc.contact_damping -= p.contact_damping;
            acc.support_work += p.support;
            acc.mass_damping += p.damping;
            bad_node = bad_node.or(p.bad_node);
        }
        (max_speed2, bad_node)
    }

    /// Adds the element pass's partial sums to the account, in chunk
    /// order. Returns the first inverted element (internal index).
    pub fn add_element_partials(&mut self) -> Option<u32> {
        let mut bad_element = None;
        let acc = &mut self.account;
        for p in &self.elem_partials {
            acc.internal_work += p.internal;
            acc.viscous_damping += p.viscous;
            acc.plastic += p.plastic;
            acc.fracture += p.fracture;
            bad_element = bad_element.or(p.bad_element);
        }
        bad_element
    }

    /// The energy-growth watchdog ([`Settings::energy_growth`](crate::Settings::energy_growth)
    /// `limit`), given the energies reported at this whole step and their
    /// kinetic lag (`Simulation::kinetic_lag`).
    ///
    /// Energy created is `−residual`, with the whole-step kinetic energy.
    /// That of a mode with `ω Δt / 2 = s` differs from the energy the
    /// central-difference scheme conserves by up to the factor
    /// `1 / (1 − s²)` (5.3 at s = 0.9): a stable run with its energy in the
    /// highest modes shows several percent "created". The scheme conserves
    /// `½ m v^{n−½}·v^{n+½} + E_el` exactly for linear undamped motion; its
    /// kinetic part is the whole-step one less `½ m |vⁿ − v^{n−½}|²` (the
    /// kinetic lag). Energy created in that measure (a contact switched on
    /// and off out of phase, a wrong force) stops the run. That measure
    /// stays constant through a linear instability, though (it is
    /// indefinite there), so growth stops the run too: the held energy
    /// grown at least sixteenfold since the last check while the whole-step
    /// balance shows the energy created, which a bounded oscillation cannot
    /// do below s = 0.96. Until 2026-11-25 only the second rule stopped
    /// runs, and two bars whose contact tripled their energy in a few
    /// hundred steps ran on with a warning (issue 32).
    pub fn watch(&mut self, e: &Energies, kinetic_lag: f64, limit: f64, clock: &Clock) -> Result<(), RunError> {
        let held = e.kinetic + e.elastic;
        let before = std::mem::replace(&mut self.held_seen, held);
        let created = -e.residual();
        let largest = e.largest_term();
        let growing = before > 0.0 && held >= 16.0 * before;
        let conserved_created = created - kinetic_lag;
        if conserved_created > limit * largest || (growing && created > limit * largest) {
            return Err(RunError::EnergyGrowth {
                created,
                largest,
                held: [before, held],
                step: clock.step(),
                time: clock.time(),
            });
        }
        Ok(())
    }
}
