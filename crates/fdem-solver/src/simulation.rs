//! [`Simulation`]: the state, its construction from a [`ModelSpec`], the
//! time loop and the read-out of results.

use std::collections::BTreeMap;
use std::sync::Arc;

use fdem_element::kinematics::{deformation_gradient, polar_rotation, reference_inverse, signed_area};
use fdem_element::tensor::rotate;
use fdem_element::{lumped_mass, ReferenceShape, Vec2};
use fdem_material::{CrackBand, Elastic, MohrCoulombRankine, PlasticState};
use fdem_mesh::{boundary_facets, node_elements, validate, Csr};

use crate::energy::{ElementPartial, Energies, NodePartial};
use crate::error::{RunError, SetupError};
use crate::loads::{Amplitude, Constraint};
use crate::model::{LawSpec, ModelSpec, Settings};
use crate::passes::{self, ElementInputs, Material, NodeInputs, NO_BC};
use crate::CHUNK;

/// Nodal arrays.
#[derive(Clone, Debug)]
struct Nodes {
    /// Reference coordinates (m).
    x0: Vec<Vec2>,
    /// Current coordinates `xⁿ` (m).
    x: Vec<Vec2>,
    /// Half-step velocities `v^{n−½}` (m/s).
    v: Vec<Vec2>,
    /// Lumped mass (kg per unit thickness).
    mass: Vec<f64>,
    /// Surface-load forces at `xⁿ` (N).
    aux: Vec<Vec2>,
    /// Index into the constraint table, or [`NO_BC`].
    bc: Vec<u32>,
}

/// Element arrays.
#[derive(Clone, Debug)]
struct Elements {
    conn: Vec<[u32; 3]>,
    reference: Vec<ReferenceShape>,
    material: Vec<u32>,
    active: Vec<bool>,
    /// Co-rotational Cauchy stress `σ̂` (Pa).
    stress: Vec<[f64; 4]>,
    /// Plastic state (unused for elastic materials).
    state: Vec<PlasticState>,
    /// Internal nodal forces at `xⁿ`, three per element (N).
    force: Vec<Vec2>,
}

/// A running explicit FDEM simulation: all state, and the thread pool that
/// advances it.
pub struct Simulation {
    nodes: Nodes,
    elems: Elements,
    materials: Vec<Material>,
    node_elems: Csr,
    constraints: Vec<Constraint>,
    amplitudes: Vec<Amplitude>,
    amplitude_values: Vec<f64>,
    /// Pressure facets oriented with the body on the left.
    pressure_facets: Vec<([u32; 2], f64, Option<u32>)>,
    pressure_nodes: Vec<u32>,
    gravity: Vec2,
    settings: Settings,
    time: f64,
    step: u64,
    /// `Δt^{n+½}`, the next position step (s).
    dt: f64,
    /// `Δt^{n−½}`, the last position step (s); zero before the first step.
    dt_prev: f64,
    /// Critical step of the mesh before the safety factor (s).
    dt_critical: f64,
    energies: Energies,
    node_partials: Vec<NodePartial>,
    elem_partials: Vec<ElementPartial>,
    /// Worker threads; every public entry point that steps runs inside it
    /// once, so the passes' parallel loops cost no cross-thread hand-off.
    pool: Arc<rayon::ThreadPool>,
}

fn invalid<T>(msg: String) -> Result<T, SetupError> {
    Err(SetupError::Invalid(msg))
}

impl Simulation {
    /// Builds a simulation from a model description on `threads` worker
    /// threads (0: as many as the machine has). Every input is checked and a
    /// problem is reported with the entity it concerns.
    pub fn new(spec: ModelSpec, threads: usize) -> Result<Self, SetupError> {
        let n = spec.points.len();
        let m = spec.triangles.len();
        if m == 0 {
            return invalid("the mesh has no elements".into());
        }
        if !spec.may_coincide.is_empty() && spec.may_coincide.len() != n {
            return invalid(format!("may_coincide has {} entries for {n} nodes", spec.may_coincide.len()));
        }
        validate(&spec.points, &spec.triangles, &spec.may_coincide)?;
        let conn: Vec<[u32; 3]> = spec.triangles.iter().map(|t| t.map(|v| v as u32)).collect();

        let mut materials = Vec::with_capacity(spec.materials.len());
        for (index, ms) in spec.materials.iter().enumerate() {
            let elastic = Elastic::new(ms.young, ms.poisson).map_err(|error| SetupError::Material { index, error })?;
            let plastic = match ms.law {
                LawSpec::Elastic => None,
                LawSpec::MohrCoulombRankine {
                    cohesion,
                    friction,
                    dilation,
                    tensile_strength,
                    fracture_energy,
                    crack_band,
                } => Some(
                    MohrCoulombRankine::new(
                        elastic,
                        cohesion,
                        friction,
                        dilation,
                        tensile_strength,
                        fracture_energy,
                        crack_band,
                    )
                    .map_err(|error| SetupError::Material { index, error })?,
                ),
            };
            if !(ms.density > 0.0 && ms.density.is_finite()) {
                let error = fdem_material::ParameterError {
                    parameter: "rho",
                    value: ms.density,
                    requirement: "density must be positive".into(),
                };
                return Err(SetupError::Material { index, error });
            }
            materials.push(Material { density: ms.density, elastic, plastic });
        }
        if spec.element_material.len() != m {
            return invalid(format!("element_material has {} entries for {m} elements", spec.element_material.len()));
        }
        if let Some(e) = spec.element_material.iter().position(|&k| k as usize >= materials.len()) {
            return invalid(format!(
                "element {e} uses material {}, but only {} materials are defined",
                spec.element_material[e],
                materials.len()
            ));
        }
        check_settings(&spec.settings)?;
        if !spec.gravity.iter().all(|g| g.is_finite()) {
            return invalid("gravity must be finite".into());
        }

        let mut reference = Vec::with_capacity(m);
        let mut mass = vec![0.0; n];
        for (e, t) in conn.iter().enumerate() {
            let x = [spec.points[t[0] as usize], spec.points[t[1] as usize], spec.points[t[2] as usize]];
            let shape = reference_inverse(&x).ok_or_else(|| {
                SetupError::Invalid(format!("element {e} has no positive area in the reference configuration"))
            })?;
            if let Some(law) = &materials[spec.element_material[e] as usize].plastic {
                let g = passes::reference_geometry(&shape);
                let size = match law.crack_band {
                    CrackBand::Oliver => g.diameter(),
                    CrackBand::Equivalent => (4.0 * g.area() / std::f64::consts::PI).sqrt(),
                };
                let limit = law.snap_back_size();
                if size > limit {
                    return invalid(format!(
                        "element {e} is {size:.4} m across, larger than the snap-back limit 2 E' Gf / ft^2 = {limit:.4} m \
                         of its material {}: refine the mesh there or raise Gf",
                        spec.element_material[e]
                    ));
                }
            }
            reference.push(shape);
            let nodal = lumped_mass(materials[spec.element_material[e] as usize].density, signed_area(&x));
            for &v in t {
                mass[v as usize] += nodal;
            }
        }

        for (k, a) in spec.amplitudes.iter().enumerate() {
            a.check(k).map_err(SetupError::Invalid)?;
        }
        let n_amp = spec.amplitudes.len();
        let check_amp = |amp: Option<u32>, what: String| match amp {
            Some(k) if k as usize >= n_amp => {
                invalid(format!("{what} refers to amplitude {k}, but only {n_amp} are defined"))
            }
            _ => Ok(()),
        };

        // One constraint per node: merge the components of repeated entries.
        let mut merged: BTreeMap<u32, Constraint> = BTreeMap::new();
        for c in &spec.constraints {
            if c.node as usize >= n {
                return invalid(format!("a support refers to node {}, but the mesh has {n} nodes", c.node));
            }
            if !c.value.iter().all(|v| v.is_finite()) {
                return invalid(format!("prescribed velocity of node {} is not finite", c.node));
            }
            check_amp(c.amplitude, format!("the support of node {}", c.node))?;
            let entry = merged.entry(c.node).or_insert(Constraint { fixed: [false; 2], ..*c });
            for d in 0..2 {
                if c.fixed[d] {
                    if entry.fixed[d] && (entry.value[d] != c.value[d] || entry.amplitude != c.amplitude) {
                        return invalid(format!(
                            "node {} has two different prescribed velocities in direction {}",
                            c.node,
                            ["x", "y"][d]
                        ));
                    }
                    if entry.fixed[1 - d] && entry.amplitude != c.amplitude {
                        return invalid(format!(
                            "node {}: prescribed x and y velocities must share one amplitude",
                            c.node
                        ));
                    }
                    entry.fixed[d] = true;
                    entry.value[d] = c.value[d];
                    entry.amplitude = c.amplitude;
                }
            }
        }
        let constraints: Vec<Constraint> = merged.into_values().collect();
        let mut bc = vec![NO_BC; n];
        for (k, c) in constraints.iter().enumerate() {
            bc[c.node as usize] = k as u32;
        }

        let facets = boundary_facets(&conn);
        let mut facet_dir: BTreeMap<(u32, u32), [u32; 2]> = BTreeMap::new();
        for f in &facets {
            let [a, b] = f.nodes;
            facet_dir.insert((a.min(b), a.max(b)), f.nodes);
        }
        let mut pressure_facets = Vec::with_capacity(spec.pressures.len());
        for p in &spec.pressures {
            let [a, b] = p.nodes;
            let Some(&dir) = facet_dir.get(&(a.min(b), a.max(b))) else {
                return invalid(format!("pressure facet ({a}, {b}) is not an edge on the boundary of the mesh"));
            };
            if !p.pressure.is_finite() {
                return invalid(format!("pressure on facet ({a}, {b}) is not finite"));
            }
            check_amp(p.amplitude, format!("the pressure on facet ({a}, {b})"))?;
            pressure_facets.push((dir, p.pressure, p.amplitude));
        }
        let mut pressure_nodes: Vec<u32> = pressure_facets.iter().flat_map(|f| f.0).collect();
        pressure_nodes.sort_unstable();
        pressure_nodes.dedup();

        let mut v = vec![[0.0; 2]; n];
        if let Some(v0) = &spec.initial_velocity {
            if v0.len() != n {
                return invalid(format!("initial velocity has {} rows for {n} nodes", v0.len()));
            }
            if let Some(i) = v0.iter().position(|p| !(p[0].is_finite() && p[1].is_finite())) {
                return invalid(format!("initial velocity of node {i} is not finite"));
            }
            v.copy_from_slice(v0);
        }
        let mut stress = vec![[0.0; 4]; m];
        if let Some(s0) = &spec.initial_stress {
            if s0.len() != m {
                return invalid(format!("initial stress has {} rows for {m} elements", s0.len()));
            }
            if let Some(e) = s0.iter().position(|s| !s.iter().all(|c| c.is_finite())) {
                return invalid(format!("initial stress of element {e} is not finite"));
            }
            stress.copy_from_slice(s0);
        }

        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| SetupError::Invalid(format!("cannot start {threads} threads: {e}")))?;
        let node_elems = node_elements(n, &conn);
        let mut sim = Simulation {
            nodes: Nodes { x0: spec.points.clone(), x: spec.points, v, mass, aux: vec![[0.0; 2]; n], bc },
            elems: Elements {
                conn,
                reference,
                material: spec.element_material,
                active: vec![true; m],
                stress,
                state: vec![PlasticState::default(); m],
                force: vec![[0.0; 2]; 3 * m],
            },
            materials,
            node_elems,
            constraints,
            amplitude_values: vec![1.0; spec.amplitudes.len()],
            amplitudes: spec.amplitudes,
            pressure_facets,
            pressure_nodes,
            gravity: spec.gravity,
            settings: spec.settings,
            time: 0.0,
            step: 0,
            dt: 0.0,
            dt_prev: 0.0,
            dt_critical: f64::INFINITY,
            energies: Energies::default(),
            node_partials: vec![NodePartial::default(); n.div_ceil(CHUNK)],
            elem_partials: vec![ElementPartial::default(); m.div_ceil(CHUNK)],
            pool: Arc::new(pool),
        };
        let pool = Arc::clone(&sim.pool);
        pool.install(|| {
            sim.apply_prescribed_initial_velocity();
            sim.refresh_forces();
            sim.update_time_step();
        });
        sim.energies.elastic_initial = sim.elastic_energy();
        sim.energies.kinetic_initial = sim.kinetic_energy();
        Ok(sim)
    }

    /// Holds the constrained components of the initial velocity at their
    /// prescribed values at `t = 0`.
    fn apply_prescribed_initial_velocity(&mut self) {
        self.eval_amplitudes(self.time);
        for c in &self.constraints {
            let amp = c.amplitude.map_or(1.0, |k| self.amplitude_values[k as usize]);
            for d in 0..2 {
                if c.fixed[d] {
                    self.nodes.v[c.node as usize][d] = c.value[d] * amp;
                }
            }
        }
    }

    fn eval_amplitudes(&mut self, t: f64) {
        for (val, a) in self.amplitude_values.iter_mut().zip(&self.amplitudes) {
            *val = a.at(t);
        }
    }

    fn element_inputs(&self, dt: f64) -> ElementInputs<'_> {
        ElementInputs {
            x: &self.nodes.x,
            v: &self.nodes.v,
            conn: &self.elems.conn,
            reference: &self.elems.reference,
            material: &self.elems.material,
            active: &self.elems.active,
            materials: &self.materials,
            beta: self.settings.stiffness_damping,
            dt,
        }
    }

    /// Recomputes element and surface forces at the current configuration
    /// without advancing the stress.
    fn refresh_forces(&mut self) {
        let Simulation { nodes, elems, elem_partials, .. } = self;
        let inp = ElementInputs {
            x: &nodes.x,
            v: &nodes.v,
            conn: &elems.conn,
            reference: &elems.reference,
            material: &elems.material,
            active: &elems.active,
            materials: &self.materials,
            beta: 0.0,
            dt: 0.0,
        };
        passes::element_pass(&inp, &mut elems.stress, &mut elems.state, &mut elems.force, elem_partials);
        self.eval_amplitudes(self.time);
        passes::pressure_forces(
            &self.nodes.x,
            &self.pressure_facets,
            &self.amplitude_values,
            &self.pressure_nodes,
            &mut self.nodes.aux,
        );
    }

    /// Re-evaluates the stable step: `s · min_e Δt_e`, or the fixed step.
    pub fn update_time_step(&mut self) {
        let inp = self.element_inputs(0.0);
        let crit = self.pool.install(|| passes::stable_time_step(&inp));
        self.dt_critical = crit;
        self.dt = self.settings.fixed_dt.unwrap_or(self.settings.safety * crit);
    }

    /// Advances one step.
    fn step_once(&mut self) -> Result<(), RunError> {
        let dt = self.dt;
        let dt_avg = 0.5 * (self.dt_prev + dt);
        self.eval_amplitudes(self.time + 0.5 * dt);
        {
            let Simulation { nodes, elems, node_partials, .. } = self;
            let inp = NodeInputs {
                mass: &nodes.mass,
                aux: &nodes.aux,
                bc: &nodes.bc,
                node_elems: &self.node_elems,
                elem_force: &elems.force,
                constraints: &self.constraints,
                amplitude_values: &self.amplitude_values,
                gravity: self.gravity,
                alpha: self.settings.mass_damping,
                dt_avg,
                dt,
                dt_prev: self.dt_prev,
            };
            passes::node_pass(&inp, &mut nodes.x, &mut nodes.v, node_partials);
        }
        self.time += dt;
        self.step += 1;
        self.dt_prev = dt;
        let mut bad_node = None;
        for p in &self.node_partials {
            self.energies.external_work += p.external;
            self.energies.support_work += p.support;
            self.energies.mass_damping += p.damping;
            bad_node = bad_node.or(p.bad_node);
        }
        if let Some((node, quantity)) = bad_node {
            return Err(RunError::NonFinite { node, quantity, step: self.step, time: self.time });
        }
        {
            let Simulation { nodes, elems, elem_partials, .. } = self;
            let inp = ElementInputs {
                x: &nodes.x,
                v: &nodes.v,
                conn: &elems.conn,
                reference: &elems.reference,
                material: &elems.material,
                active: &elems.active,
                materials: &self.materials,
                beta: self.settings.stiffness_damping,
                dt,
            };
            passes::element_pass(&inp, &mut elems.stress, &mut elems.state, &mut elems.force, elem_partials);
        }
        let mut bad_element = None;
        for p in &self.elem_partials {
            self.energies.internal_work += p.internal;
            self.energies.viscous_damping += p.viscous;
            self.energies.plastic += p.plastic;
            self.energies.fracture += p.fracture;
            bad_element = bad_element.or(p.bad_element);
        }
        if let Some(element) = bad_element {
            return Err(RunError::InvertedElement { element, step: self.step, time: self.time });
        }
        self.eval_amplitudes(self.time);
        passes::pressure_forces(
            &self.nodes.x,
            &self.pressure_facets,
            &self.amplitude_values,
            &self.pressure_nodes,
            &mut self.nodes.aux,
        );
        if self.settings.fixed_dt.is_none() && self.step % self.settings.dt_interval as u64 == 0 {
            self.update_time_step();
        }
        Ok(())
    }

    /// Advances `steps` steps, or until an error.
    pub fn step(&mut self, steps: u64) -> Result<(), RunError> {
        let pool = Arc::clone(&self.pool);
        pool.install(|| {
            for _ in 0..steps {
                self.step_once()?;
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
            while self.time < until && taken < max_steps {
                self.step_once()?;
                taken += 1;
            }
            Ok(taken)
        })
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
            let b = self.nodes.bc.get(node as usize).copied().unwrap_or(NO_BC);
            if b == NO_BC {
                return invalid(format!("node {node} has no prescribed velocity to change"));
            }
            if !(value[0].is_finite() && value[1].is_finite()) {
                return invalid(format!("prescribed velocity of node {node} is not finite"));
            }
            self.constraints[b as usize].value = value;
        }
        Ok(())
    }

    /// Current simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// The step the next advance uses (s).
    pub fn time_step(&self) -> f64 {
        self.dt
    }

    /// Critical step of the mesh at its last evaluation, before the safety
    /// factor (s): `min_e 2/ω_e`.
    pub fn critical_time_step(&self) -> f64 {
        self.dt_critical
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.x.len()
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elems.conn.len()
    }

    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Current node coordinates (m).
    pub fn positions(&self) -> &[Vec2] {
        &self.nodes.x
    }

    /// Reference node coordinates (m).
    pub fn reference_positions(&self) -> &[Vec2] {
        &self.nodes.x0
    }

    /// Element connectivity.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.elems.conn
    }

    /// Lumped nodal masses (kg per unit thickness).
    pub fn masses(&self) -> &[f64] {
        &self.nodes.mass
    }

    /// Whether each element is active.
    pub fn active(&self) -> &[bool] {
        &self.elems.active
    }

    /// Velocities at the current whole step (m/s):
    /// `vⁿ = (v^{n−½} + Δt^{n−½}/2 · f/m) / (1 + αΔt^{n−½}/2)`, which equals
    /// `(v^{n−½} + v^{n+½}) / 2` of the scheme, with constrained components
    /// at their prescribed values.
    pub fn velocities(&self) -> Vec<Vec2> {
        let h = 0.5 * self.dt_prev;
        let denom = 1.0 + self.settings.mass_damping * h;
        let mut amp = self.amplitude_values.clone();
        for (val, a) in amp.iter_mut().zip(&self.amplitudes) {
            *val = a.at(self.time);
        }
        (0..self.n_nodes())
            .map(|i| {
                let m = self.nodes.mass[i];
                let mut v = self.nodes.v[i];
                if m > 0.0 && h > 0.0 {
                    let f = self.net_force(i);
                    v = [(v[0] + h * f[0] / m) / denom, (v[1] + h * f[1] / m) / denom];
                }
                let b = self.nodes.bc[i];
                if b != NO_BC {
                    let c = &self.constraints[b as usize];
                    let a = c.amplitude.map_or(1.0, |k| amp[k as usize]);
                    for d in 0..2 {
                        if c.fixed[d] {
                            v[d] = c.value[d] * a;
                        }
                    }
                }
                v
            })
            .collect()
    }

    /// Net force on node `i` at the current configuration (N).
    fn net_force(&self, i: usize) -> Vec2 {
        let m = self.nodes.mass[i];
        let mut f = [m * self.gravity[0] + self.nodes.aux[i][0], m * self.gravity[1] + self.nodes.aux[i][1]];
        for &item in self.node_elems.row(i) {
            let fe = self.elems.force[item as usize];
            f[0] -= fe[0];
            f[1] -= fe[1];
        }
        f
    }

    /// Rotation `R` (cos, sin) of element `e` at the current configuration.
    fn rotation(&self, e: usize) -> (f64, f64) {
        let t = self.elems.conn[e];
        let x = [self.nodes.x[t[0] as usize], self.nodes.x[t[1] as usize], self.nodes.x[t[2] as usize]];
        polar_rotation(deformation_gradient(&self.elems.reference[e], &x))
    }

    /// Cauchy stress `σ = R σ̂ Rᵀ` of every element, `[xx, yy, zz, xy]` (Pa).
    pub fn stress(&self) -> Vec<[f64; 4]> {
        (0..self.n_elements())
            .map(|e| {
                let (c, s) = self.rotation(e);
                rotate(self.elems.stress[e], c, s)
            })
            .collect()
    }

    /// Plastic state of every element (co-rotational frame; defaults for
    /// elastic materials).
    pub fn plastic_states(&self) -> &[PlasticState] {
        &self.elems.state
    }

    /// Failure factor `F = κ H / f_t` of every element (eq. 2.21); 0 for
    /// elastic materials.
    pub fn failure_factors(&self) -> Vec<f64> {
        (0..self.n_elements())
            .map(|e| match &self.materials[self.elems.material[e] as usize].plastic {
                Some(law) => law.failure_factor(&self.elems.state[e]),
                None => 0.0,
            })
            .collect()
    }

    /// Direction of σ1 at the last tensile plastic step of every element in
    /// the current frame (rad from x): the rotating crack's normal.
    pub fn crack_directions(&self) -> Vec<f64> {
        (0..self.n_elements())
            .map(|e| {
                let (c, s) = self.rotation(e);
                let a = self.elems.state[e].direction + s.atan2(c);
                // a direction, not an orientation: keep it in (−π/2, π/2]
                let half = std::f64::consts::FRAC_PI_2;
                if a > half {
                    a - std::f64::consts::PI
                } else if a <= -half {
                    a + std::f64::consts::PI
                } else {
                    a
                }
            })
            .collect()
    }

    /// Plastic strain of every element rotated to the current frame,
    /// `[xx, yy, zz, xy]` (tensor shear).
    pub fn plastic_strain(&self) -> Vec<[f64; 4]> {
        (0..self.n_elements())
            .map(|e| {
                let (c, s) = self.rotation(e);
                rotate(self.elems.state[e].plastic_strain, c, s)
            })
            .collect()
    }

    /// Current element areas (m²).
    pub fn areas(&self) -> Vec<f64> {
        self.elems
            .conn
            .iter()
            .map(|t| {
                signed_area(&[self.nodes.x[t[0] as usize], self.nodes.x[t[1] as usize], self.nodes.x[t[2] as usize]])
            })
            .collect()
    }

    /// Kinetic energy at the current whole step (J per unit thickness).
    pub fn kinetic_energy(&self) -> f64 {
        let v = self.velocities();
        let per_chunk: Vec<f64> = v
            .chunks(CHUNK)
            .zip(self.nodes.mass.chunks(CHUNK))
            .map(|(vc, mc)| vc.iter().zip(mc).map(|(v, m)| 0.5 * m * (v[0] * v[0] + v[1] * v[1])).sum())
            .collect();
        per_chunk.iter().sum()
    }

    /// Elastic strain energy `Σ A ½ σ̂ : C⁻¹ : σ̂` (J per unit thickness).
    pub fn elastic_energy(&self) -> f64 {
        let areas = self.areas();
        (0..self.n_elements())
            .filter(|&e| self.elems.active[e])
            .map(|e| {
                let mat = &self.materials[self.elems.material[e] as usize];
                areas[e] * mat.elastic.energy_density(self.elems.stress[e])
            })
            .sum()
    }

    /// The energy account at the current step.
    ///
    /// The accumulated work pairs the force of step `n` with the centred
    /// displacement `(Δx^{n−½} + Δx^{n+½}) / 2`; at a whole step the second
    /// half of the last displacement is still pending and is added here, so
    /// that the account matches the whole-step kinetic energy.
    pub fn energies(&self) -> Energies {
        let v = self.velocities();
        let h = 0.5 * self.dt_prev;
        let (mut external, mut support, mut damping) = (0.0, 0.0, 0.0);
        for i in 0..self.n_nodes() {
            let m = self.nodes.mass[i];
            if m <= 0.0 || h == 0.0 {
                continue;
            }
            let half = self.nodes.v[i];
            let dx = [h * half[0], h * half[1]];
            let g = self.gravity;
            let aux = self.nodes.aux[i];
            external += (m * g[0] + aux[0]) * dx[0] + (m * g[1] + aux[1]) * dx[1];
            let alpha = self.settings.mass_damping;
            damping += alpha * m * (v[i][0] * dx[0] + v[i][1] * dx[1]);
            let b = self.nodes.bc[i];
            if b != NO_BC {
                let f = self.net_force(i);
                let c = &self.constraints[b as usize];
                for d in 0..2 {
                    if c.fixed[d] {
                        let reaction = m * (v[i][d] - half[d]) / h + alpha * m * v[i][d] - f[d];
                        support += reaction * dx[d];
                    }
                }
            }
        }
        Energies {
            kinetic: self.kinetic_energy(),
            elastic: self.elastic_energy(),
            external_work: self.energies.external_work + external,
            support_work: self.energies.support_work + support,
            mass_damping: self.energies.mass_damping + damping,
            ..self.energies
        }
    }
}

fn check_settings(s: &Settings) -> Result<(), SetupError> {
    if !(s.mass_damping >= 0.0 && s.mass_damping.is_finite()) {
        return invalid(format!("mass damping alpha = {} must be finite and >= 0", s.mass_damping));
    }
    if !(s.stiffness_damping >= 0.0 && s.stiffness_damping.is_finite()) {
        return invalid(format!("stiffness damping beta = {} must be finite and >= 0", s.stiffness_damping));
    }
    if !(s.safety > 0.0 && s.safety <= 1.0) {
        return invalid(format!("time-step safety factor = {} must lie in (0, 1]", s.safety));
    }
    if let Some(dt) = s.fixed_dt {
        if !(dt > 0.0 && dt.is_finite()) {
            return invalid(format!("fixed time step dt = {dt} must be positive"));
        }
    }
    if s.dt_interval == 0 {
        return invalid("dt_interval must be at least 1".into());
    }
    Ok(())
}
