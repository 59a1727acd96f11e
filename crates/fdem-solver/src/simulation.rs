//! [`Simulation`]: the state and the time loop. Construction is in
//! `setup.rs`, the stable step in `stable_step.rs`, read-out of results in
//! `readout.rs`.

use std::sync::Arc;
use std::time::Instant;

use fdem_contact::Surface;
use fdem_element::{ReferenceShape, Vec2};
use fdem_material::PlasticState;
use fdem_mesh::Csr;

use crate::clock::Clock;
use crate::contact::{AssemblyOut, ContactModel, NodeForces};
use crate::energy::EnergyLedger;
use crate::error::{RunError, SetupError};
use crate::excavation::Staging;
use crate::loads::Loads;
use crate::model::Settings;
use crate::passes::{self, Material, NodeInputs, NO_BC};
use crate::stable_step::Frequencies;

/// Nodal arrays.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Nodes {
    /// Reference coordinates (m).
    pub x0: Vec<Vec2>,
    /// Current coordinates `xⁿ` (m).
    pub x: Vec<Vec2>,
    /// Half-step velocities `v^{n−½}` (m/s).
    pub v: Vec<Vec2>,
    /// Lumped mass (kg per unit thickness).
    pub mass: Vec<f64>,
    /// Index into the constraint table, or [`NO_BC`].
    pub bc: Vec<u32>,
}

/// Element arrays.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub(crate) struct Elements {
    pub conn: Vec<[u32; 3]>,
    pub reference: Vec<ReferenceShape>,
    pub material: Vec<u32>,
    pub active: Vec<bool>,
    /// Co-rotational Cauchy stress `σ̂` (Pa).
    pub stress: Vec<[f64; 4]>,
    /// Density factor of selective mass scaling (1: physical mass);
    /// written after the format-1 state in checkpoints (checkpoint.rs).
    #[serde(skip)]
    pub mass_scale: Vec<f64>,
    /// Plastic state (unused for elastic materials).
    pub state: Vec<PlasticState>,
    /// The element (id) each element was cut from by crack insertion; an
    /// element of the model is its own parent. Ids, not internal indices,
    /// and a parent's id is below its child's (`lineage.rs`). Written after
    /// the format-6 state in checkpoints (checkpoint.rs).
    #[serde(skip)]
    pub parent: Vec<u32>,
    /// Internal nodal forces at `xⁿ`, three per element (N).
    pub force: Vec<Vec2>,
}

/// Counters of the contact search, for benchmarks and diagnostics.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactStats {
    /// Candidate (node, facet) pairs evaluated so far.
    pub pairs_evaluated: u64,
    /// Broad-phase builds (rebuilds and refits) so far.
    pub broad_phase_builds: u64,
    /// Candidate pairs in the current list.
    pub candidate_pairs: u64,
    /// Active contacts at the last step.
    pub contacts: u64,
}

/// Wall-clock seconds spent in each phase of the step so far (for
/// benchmarks; results never depend on them).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Node pass (gather, integrate, supports).
    pub nodes: f64,
    /// Element pass (kinematics, material, forces).
    pub elements: f64,
    /// Contact broad phase (candidate lists).
    pub broad_phase: f64,
    /// Contact narrow phase and assembly, pressure loads. The contact's
    /// assembly runs beside the element pass (`rayon::join`), so their clocks
    /// overlap.
    pub surface: f64,
    /// Stable-step updates.
    pub time_step: f64,
    /// Fracture checks: failure factors, nodal averages, planning the
    /// insertions, bonds.
    pub fracture: f64,
    /// Applying insertions: topology edits, rebuilt adjacency, masses,
    /// surfaces and contact state, forces of the new mesh, the new stable
    /// step.
    pub topology: f64,
}

/// One active contact, for read-out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactInfo {
    /// The contacting node.
    pub node: u32,
    /// The facet it touches (its two nodes).
    pub facet: [u32; 2],
    /// Position of its projection on the facet, `ξ ∈ [0, 1]`.
    pub xi: f64,
    /// Normal gap (m, negative = penetration).
    pub gap: f64,
    /// Normal force (N/m).
    pub normal_force: f64,
    /// Tangential force (N/m).
    pub tangential_force: f64,
    /// Whether it slipped in the last step.
    pub slipping: bool,
    /// Penetration (m, ≥ 0) its spring does not count: the depth at which
    /// the node was found already inside the facet's element
    /// (docs/contact.md, "Which facet a node touches", item 7); 0 for a
    /// contact entered through the facet's line.
    pub offset: f64,
}

/// A running explicit FDEM simulation: all state, and the thread pool that
/// advances it.
pub struct Simulation {
    pub(crate) nodes: Nodes,
    pub(crate) elems: Elements,
    pub(crate) materials: Vec<Material>,
    pub(crate) node_elems: Csr,
    /// Supports, prescribed velocities, gravity, pressure and the loads of
    /// gradual excavations, with their time histories and resolved forces.
    pub(crate) loads: Loads,
    /// The original node each node descends from (itself for a node of the
    /// model or a new node on a split edge; the split node for a copy).
    pub(crate) ancestor: Vec<u32>,
    /// The free surfaces of the current mesh.
    pub(crate) surface: Surface,
    /// Contact and bond forces per boundary node and the node pass's
    /// dashpot scratch.
    pub(crate) node_forces: NodeForces,
    pub(crate) contact: Option<ContactModel>,
    pub(crate) fracture: Option<crate::fracture::FractureModel>,
    /// Excavation stages and the elastic stage.
    pub(crate) staging: Staging,
    /// Contact statistics and phase timings (read out, never read back).
    pub(crate) diagnostics: Diagnostics,
    /// The elements' and contact nodes' highest frequencies at the last
    /// stable-step update.
    pub(crate) frequencies: Frequencies,
    pub(crate) settings: Settings,
    /// Time, step count and the step sizes around the current step.
    pub(crate) clock: Clock,
    /// The energy account, the passes' partial sums that feed it, and the
    /// watchdog's last look.
    pub(crate) ledger: EnergyLedger,
    /// Internal index ↔ id of nodes and elements (spatial renumbering).
    pub(crate) layout: crate::renumber::Layout,
    /// Worker threads; every public entry point that steps runs inside it
    /// once, so the passes' parallel loops cost no cross-thread hand-off.
    pub(crate) pool: Arc<rayon::ThreadPool>,
}

/// Contact statistics and the time spent in each phase: what the run
/// reports about itself. The statistics are saved in checkpoints (they
/// count over the whole run); the timings are not.
#[derive(Default)]
pub(crate) struct Diagnostics {
    pub contact_stats: ContactStats,
    pub phase_times: PhaseTimes,
}

pub(crate) fn invalid<T>(msg: String) -> Result<T, SetupError> {
    Err(SetupError::Invalid(msg))
}

impl Simulation {
    /// Holds the constrained components of the initial velocity at their
    /// prescribed values at `t = 0`.
    pub(crate) fn apply_prescribed_initial_velocity(&mut self) {
        self.loads.eval_amplitudes(self.clock.time());
        for c in &self.loads.constraints {
            let amp = c.amplitude.map_or(1.0, |k| self.loads.amplitude_values[k as usize]);
            for d in 0..2 {
                if c.fixed[d] {
                    self.nodes.v[c.node as usize][d] = c.value[d] * amp;
                }
            }
        }
    }

    /// Recomputes element and surface forces at the current configuration
    /// without advancing the stress.
    pub(crate) fn refresh_forces(&mut self) {
        let inp = passes::element_inputs!(self, beta: 0.0, dt: 0.0);
        let Simulation { elems: Elements { stress, state, force, .. }, ledger, .. } = self;
        passes::element_pass(&inp, stress, state, force, &mut ledger.elem_partials);
        self.surface_forces(0.0);
    }

    /// Element forces after a topology change: the listed (new or
    /// reshaped) elements' internal forces from their stress; the other
    /// elements keep theirs. The caller then recomputes the pressure,
    /// contact and bond forces on the new surfaces ([`Self::surface_forces`]).
    pub(crate) fn refresh_element_forces_of(&mut self, touched: &[u32]) {
        let inp = passes::element_inputs!(self, beta: 0.0, dt: 0.0);
        passes::element_forces_of(&inp, touched, &self.elems.stress, &mut self.elems.force);
    }

    /// Pressure and contact forces at the current configuration; `dt` is the
    /// step just taken (for the tangential slip increment).
    pub(crate) fn surface_forces(&mut self, dt: f64) {
        let contact = self.contact.as_mut().map(|c| {
            let out = AssemblyOut {
                forces: &mut self.node_forces.contact_force,
                damping: &mut self.node_forces.contact_damping_force,
                damped: &mut self.node_forces.contact_damped,
            };
            evaluate_contact(c, &self.surface, &self.nodes, dt, out)
        });
        self.finish_surface_forces(contact);
    }

    /// What follows the contact evaluation ([`evaluate_contact`], `None`
    /// without contact): the pressure loads at the current positions, the
    /// contact's energies and counts, the bonds across young cracks, and the
    /// phase clocks.
    fn finish_surface_forces(&mut self, contact: Option<ContactOutcome>) {
        let clock = Instant::now();
        self.loads.eval_amplitudes(self.clock.time());
        passes::pressure_forces(
            &self.nodes.x,
            &self.loads.pressure,
            &self.loads.amplitude_values,
            &mut self.loads.pressure_force,
        );
        if let (Some(contact), Some(out)) = (&self.contact, contact) {
            self.ledger.account.friction += out.sum.friction;
            self.ledger.account.contact_elastic = out.sum.stored;
            self.diagnostics.contact_stats = ContactStats {
                pairs_evaluated: contact.pairs_evaluated,
                broad_phase_builds: contact.broad.builds,
                candidate_pairs: contact.broad.pairs() as u64,
                contacts: out.sum.contacts,
            };
            self.diagnostics.phase_times.broad_phase += out.broad_secs;
            self.diagnostics.phase_times.surface += out.narrow_secs;
            self.bond_forces();
        }
        self.diagnostics.phase_times.surface += clock.elapsed().as_secs_f64();
    }

    /// The contact forces added up again from the contact records, with the
    /// damped nodes and the list of dashpots, and the intact bonds' forces
    /// added as the last step added them: the surface forces the step left,
    /// rebuilt outside a step (restore, renumbering). Nothing without
    /// contact (bonds act through the contact forces only).
    pub(crate) fn reassemble_surface_forces(&mut self) {
        let Some(c) = self.contact.as_mut() else { return };
        let out = AssemblyOut {
            forces: &mut self.node_forces.contact_force,
            damping: &mut self.node_forces.contact_damping_force,
            damped: &mut self.node_forces.contact_damped,
        };
        c.reassemble(out);
        self.add_bond_forces();
    }

    /// Advances one step in the order of ARCHITECTURE.md's "One step":
    /// excavation stages due at `tⁿ`, the node pass, the element pass with
    /// the surface forces, then the checks that follow a step (fracture,
    /// stable step, renumbering).
    fn step_once(&mut self) -> Result<(), RunError> {
        if !self.staging.elastic_stage
            && self.staging.next_stage < self.staging.stages.len()
            && self.staging.stages[self.staging.next_stage].time <= self.clock.time()
        {
            let clock = Instant::now();
            self.excavate_due();
            self.diagnostics.phase_times.topology += clock.elapsed().as_secs_f64();
        }
        let dt = self.node_pass()?;
        self.element_and_surface_pass(dt)?;
        if !self.staging.elastic_stage && self.fracture.as_ref().is_some_and(|f| self.clock.every(f.interval as u64)) {
            let clock = Instant::now();
            let topology = self.diagnostics.phase_times.topology;
            // a change of topology rebuilds forces (and contact) itself
            let changed = self.fracture_check();
            self.diagnostics.phase_times.fracture +=
                clock.elapsed().as_secs_f64() - (self.diagnostics.phase_times.topology - topology);
            if changed {
                self.renumber_if_due(true);
                return Ok(()); // rebuilt forces, contact and the stable step
            }
        }
        if self.settings.fixed_dt.is_none() && self.clock.every(self.settings.dt_interval as u64) {
            self.update_time_step_for(None, false);
        }
        self.renumber_if_due(false);
        Ok(())
    }

    /// Step 1 of ARCHITECTURE.md's "One step", the node pass: `v^{n+½}`
    /// and `x^{n+1}` from the forces at `xⁿ` (with contact dashpots in two
    /// stages), the clock advanced, its work added to the ledger. Returns
    /// the step taken (s).
    fn node_pass(&mut self) -> Result<f64, RunError> {
        let (dt, dt_avg) = (self.clock.dt(), self.clock.dt_avg());
        self.loads.eval_amplitudes(self.clock.mid_step());
        let clock = Instant::now();
        {
            let n = self.nodes.x.len();
            if self.node_forces.pred_v.len() != n {
                // sized to the mesh: changes only with the topology
                self.node_forces.pred_v.resize(n, [0.0; 2]);
                self.node_forces.pred_f.resize(n, [0.0; 2]);
            }
            if self.node_forces.dashpot_force.len() != self.node_forces.contact_damped.len() {
                self.node_forces.dashpot_force.resize(self.node_forces.contact_damped.len(), [0.0; 2]);
            }
            let Simulation {
                nodes,
                elems,
                ledger,
                node_forces: NodeForces { pred_v, pred_f, dashpot_force, .. },
                contact,
                ..
            } = self;
            let node_partials = &mut ledger.node_partials;
            let inp = NodeInputs {
                mass: &nodes.mass,
                bnode: &self.surface.index_of,
                pressure: &self.loads.pressure_force,
                contact: &self.node_forces.contact_force,
                contact_damping: &self.node_forces.contact_damping_force,
                bc: &nodes.bc,
                node_elems: &self.node_elems,
                elem_force: &elems.force,
                constraints: &self.loads.constraints,
                amplitude_values: &self.loads.amplitude_values,
                gravity: self.loads.gravity,
                alpha: self.settings.mass_damping,
                local: self.settings.local_damping,
                release: &self.loads.release_force,
                dt_avg,
                dt,
                dt_prev: self.clock.dt_prev(),
            };
            // with contact dashpots in two stages: the damped nodes'
            // predicted velocities, the dashpots on them, those nodes moved
            let damped = &self.node_forces.contact_damped[..];
            passes::node_pass(&inp, &mut nodes.x, &mut nodes.v, node_partials, damped, pred_v, pred_f);
            if let Some(c) = contact.as_mut().filter(|c| c.has_dashpots()) {
                let h = dt_avg / (1.0 + 0.5 * self.settings.mass_damping * dt_avg);
                c.dashpots(&self.surface.nodes, damped, &nodes.mass, pred_v, h, dashpot_force);
                passes::node_pass_damped(
                    &inp,
                    &mut nodes.x,
                    &mut nodes.v,
                    node_partials,
                    damped,
                    pred_f,
                    dashpot_force,
                );
            }
        }
        self.diagnostics.phase_times.nodes += clock.elapsed().as_secs_f64();
        self.clock.advance();
        if !self.loads.released.is_empty() || !self.loads.release_force.is_empty() {
            self.update_release();
        }
        let (max_speed2, bad_node) = self.ledger.add_node_partials();
        if let Some((node, quantity)) = bad_node {
            let node = self.layout.node_id(node);
            return Err(RunError::NonFinite { node, quantity, step: self.clock.step(), time: self.clock.time() });
        }
        // how far the step can have moved any node: lets the broad phase
        // skip its scan of the boundary nodes while no node can be near
        // half its margin
        if let Some(c) = self.contact.as_mut() {
            c.broad.note_motion(dt * max_speed2.sqrt());
        }
        Ok(dt)
    }

    /// Steps 2 and 3 of "One step" at `x^{n+1}`: the element pass and the
    /// surface forces (contact beside the element pass, pressure, bonds);
    /// `dt` is the step just taken.
    fn element_and_surface_pass(&mut self, dt: f64) -> Result<(), RunError> {
        // The element pass and the contact evaluation read the same
        // positions and velocities and write disjoint arrays, so they may
        // run in any order or side by side. The contact's narrow phase runs
        // first, on every worker; then its serial assembly runs beside the
        // element pass, which the other workers share. (Run side by side
        // whole, the element pass finished first and left the assembly at
        // the end of the step to one worker: 9% of a late step on 2
        // threads.) Each is deterministic by itself, so the results do not
        // depend on how the two interleave (their clocks overlap).
        let searched = self.contact.as_mut().map(|c| search_contact(c, &self.surface, &self.nodes, dt));
        let contact = {
            let inp = passes::element_inputs!(self, beta: self.settings.stiffness_damping, dt: dt);
            let Simulation {
                elems: Elements { stress, state, force, .. },
                ledger,
                contact,
                node_forces: NodeForces { contact_force, contact_damping_force, contact_damped, .. },
                ..
            } = self;
            let (elements, contact) = rayon::join(
                || {
                    let clock = Instant::now();
                    passes::element_pass(&inp, stress, state, force, &mut ledger.elem_partials);
                    clock.elapsed().as_secs_f64()
                },
                || {
                    let (c, clocks) = contact.as_mut().zip(searched)?;
                    let out =
                        AssemblyOut { forces: contact_force, damping: contact_damping_force, damped: contact_damped };
                    Some(assemble_contact(c, clocks, out))
                },
            );
            self.diagnostics.phase_times.elements += elements;
            contact
        };
        if let Some(element) = self.ledger.add_element_partials() {
            let element = self.layout.elem_id(element);
            return Err(RunError::InvertedElement { element, step: self.clock.step(), time: self.clock.time() });
        }
        // Contact at x^{n+1} on the surfaces the step moved (evaluated
        // above, beside the element pass): this step's slip and friction,
        // its stored energy. A crack insertion after it re-forms the
        // contacts at the same positions without slip, so the change of held
        // energy it causes is the topology's alone (`Energies::resurfacing`).
        // Evaluating contact only after the insertion, with no slip, lost the
        // step's friction: μ f_n × one step of slip per sliding node at
        // every insertion step (measured: 1.5×10⁶ J in 300 steps of the
        // block-caving case).
        self.finish_surface_forces(contact);
        Ok(())
    }

    /// One step, then the energy-growth watchdog every
    /// [`ENERGY_CHECK_INTERVAL`](crate::ENERGY_CHECK_INTERVAL) steps.
    fn step_watched(&mut self) -> Result<(), RunError> {
        self.step_once()?;
        let limit = self.settings.energy_growth;
        if limit > 0.0 && self.clock.every(crate::ENERGY_CHECK_INTERVAL) {
            // (the rules and why: `EnergyLedger::watch`)
            let e = self.energies();
            let lag = self.kinetic_lag();
            self.ledger.watch(&e, lag, limit, &self.clock)?;
        }
        Ok(())
    }

    /// Advances `steps` steps, or until an error.
    pub fn step(&mut self, steps: u64) -> Result<(), RunError> {
        let pool = Arc::clone(&self.pool);
        pool.install(|| {
            for _ in 0..steps {
                self.step_watched()?;
            }
            Ok(())
        })
    }

    /// Advances until the time reaches `until` (s) or `max_steps` steps were
    /// taken; returns the number of steps taken. The last step is not
    /// shortened to land on `until`: a run's result does not depend on how
    /// often it is stopped for output.
    pub fn advance(&mut self, until: f64, max_steps: u64) -> Result<u64, RunError> {
        let pool = Arc::clone(&self.pool);
        pool.install(|| {
            let mut taken = 0;
            while self.clock.time() < until && taken < max_steps {
                self.step_watched()?;
                taken += 1;
            }
            Ok(taken)
        })
    }

    /// Switches an elastic stage on or off: while on, every material
    /// responds elastically (no plastic flow, softening or damage growth)
    /// and no cracks are inserted or excavation stages run. Used for the
    /// equilibrium stage from a geostatic stress (DESIGN §4.6), whose
    /// transient would otherwise fracture the rock before it is loaded.
    pub fn set_elastic_stage(&mut self, on: bool) {
        self.staging.elastic_stage = on;
    }

    /// Sets the steps between fracture checks (DESIGN §4.4) from now on: a
    /// check follows every step whose count is a multiple of `steps`. It is
    /// saved with the run. The delay with which a due node is cut is up to
    /// this many steps; how long it may be before the crack pattern
    /// changes is measured in docs/fracture.md.
    pub fn set_fracture_interval(&mut self, steps: u32) -> Result<(), SetupError> {
        let Some(fr) = self.fracture.as_mut() else {
            return Err(SetupError::Invalid("the model has no fracture: no check interval to set".into()));
        };
        fr.interval = crate::fracture::check_interval(steps)?;
        Ok(())
    }

    /// Whether an elastic stage is on (see [`Self::set_elastic_stage`]).
    pub fn elastic_stage(&self) -> bool {
        self.staging.elastic_stage
    }

    /// The run settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Replaces the run settings (damping, safety, fixed step) between stages.
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), SetupError> {
        check_settings(&settings)?;
        self.settings = settings;
        self.update_time_step();
        Ok(())
    }

    /// Sets the prescribed velocity values of constrained nodes (m/s); every
    /// node must already carry a constraint on the components it sets.
    pub fn set_prescribed_velocity(&mut self, nodes: &[u32], values: &[Vec2]) -> Result<(), SetupError> {
        for (&node, &value) in nodes.iter().zip(values) {
            let b = self.nodes.bc.get(self.layout.node_index(node) as usize).copied().unwrap_or(NO_BC);
            if b == NO_BC {
                return invalid(format!("node {node} has no prescribed velocity to change"));
            }
            if !(value[0].is_finite() && value[1].is_finite()) {
                return invalid(format!("prescribed velocity of node {node} is not finite"));
            }
            self.loads.constraints[b as usize].value = value;
        }
        Ok(())
    }
}

pub(crate) fn check_settings(s: &Settings) -> Result<(), SetupError> {
    if !(s.mass_damping >= 0.0 && s.mass_damping.is_finite()) {
        return invalid(format!("mass damping alpha = {} must be finite and >= 0", s.mass_damping));
    }
    if !(s.stiffness_damping >= 0.0 && s.stiffness_damping.is_finite()) {
        return invalid(format!("stiffness damping beta = {} must be finite and >= 0", s.stiffness_damping));
    }
    if !(s.local_damping >= 0.0 && s.local_damping < 1.0) {
        return invalid(format!("local damping = {} must lie in [0, 1)", s.local_damping));
    }
    if !(s.safety > 0.0 && s.safety <= 1.0) {
        return invalid(format!("time-step safety factor = {} must lie in (0, 1]", s.safety));
    }
    if let Some(dt) = s.fixed_dt {
        if !(dt > 0.0 && dt.is_finite()) {
            return invalid(format!("fixed time step dt = {dt} must be positive"));
        }
    }
    if let Some(f) = s.renumber {
        if !(f > 0.0 && f.is_finite()) {
            return invalid(format!("renumber = {f} must be positive (a fraction of the element count)"));
        }
    }
    if s.renumber_every == Some(0) {
        return invalid("renumber_every = 0 steps must be positive".into());
    }
    if let Some(dt) = s.mass_scaling {
        if !(dt > 0.0 && dt.is_finite()) {
            return invalid(format!("mass_scaling (the time step to hold) = {dt} must be positive"));
        }
    }
    if s.dt_interval == 0 {
        return invalid("dt_interval must be at least 1".into());
    }
    if !(s.energy_growth >= 0.0 && s.energy_growth.is_finite()) {
        return invalid(format!("energy_growth = {} must be finite and >= 0 (0 turns the check off)", s.energy_growth));
    }
    Ok(())
}

/// What one contact evaluation gives back: the summed partials and its
/// clocks (s): the broad phase, then the narrow phase with the assembly.
struct ContactOutcome {
    sum: fdem_contact::narrow::ContactPartial,
    broad_secs: f64,
    narrow_secs: f64,
}

/// One contact evaluation at the nodes' current positions and half-step
/// velocities: [`search_contact`], then [`assemble_contact`] into `force`
/// and `damping` (per boundary node).
fn evaluate_contact(
    contact: &mut ContactModel,
    surface: &Surface,
    nodes: &Nodes,
    dt: f64,
    out: AssemblyOut<'_>,
) -> ContactOutcome {
    let clocks = search_contact(contact, surface, nodes, dt);
    assemble_contact(contact, clocks, out)
}

/// The first part of a contact evaluation (parallel): the broad phase
/// brought up to date, then the narrow phase. Returns their clocks (s).
fn search_contact(contact: &mut ContactModel, surface: &Surface, nodes: &Nodes, dt: f64) -> (f64, f64) {
    let clock = Instant::now();
    contact.broad.update(surface, &nodes.x);
    let broad_secs = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    contact.search(surface, &nodes.x, &nodes.x0, &nodes.v, &nodes.mass, dt);
    (broad_secs, clock.elapsed().as_secs_f64())
}

/// The second part (serial): the assembly into `out`, with the clocks of
/// the first.
fn assemble_contact(
    contact: &mut ContactModel,
    (broad_secs, search_secs): (f64, f64),
    out: AssemblyOut<'_>,
) -> ContactOutcome {
    let clock = Instant::now();
    let sum = contact.assemble(out);
    ContactOutcome { sum, broad_secs, narrow_secs: search_secs + clock.elapsed().as_secs_f64() }
}

impl Simulation {
    /// [`Loads::update_release`] at the current time.
    pub(crate) fn update_release(&mut self) {
        self.loads.update_release(self.clock.time(), self.nodes.x.len());
    }
}
