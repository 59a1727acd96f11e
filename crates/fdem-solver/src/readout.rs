//! Reading results out of a [`Simulation`]: copies, never views of arrays
//! that a topology change may reallocate. Rows and the ids inside them are
//! by id (creation order) whatever the solver's internal order
//! (`renumber.rs`).

use std::borrow::Cow;
use std::ops::Range;

use fdem_element::kinematics::{deformation_gradient, polar_rotation, signed_area};
use fdem_element::tensor::rotate;
use fdem_element::Vec2;
use fdem_material::PlasticState;

use crate::energy::Energies;
use crate::passes::NO_BC;
use crate::simulation::{ContactInfo, ContactStats, PhaseTimes, Simulation};
use crate::sums::chunk_tree_sum;
use crate::NONE;

impl Simulation {
    /// Current simulated time (s).
    pub fn time(&self) -> f64 {
        self.clock.time()
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.clock.step()
    }

    /// The step the next advance uses (s).
    pub fn time_step(&self) -> f64 {
        self.clock.dt()
    }

    /// Critical step of the mesh at its last evaluation, before the safety
    /// factor (s): `min_e 2/ω_e`.
    pub fn critical_time_step(&self) -> f64 {
        self.clock.dt_critical()
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

    /// Per-element rows computed in internal order, by id.
    fn elem_rows<T: Clone>(&self, rows: Vec<T>) -> Vec<T> {
        match self.layout.elems_by_id(&rows) {
            Cow::Borrowed(_) => rows,
            Cow::Owned(v) => v,
        }
    }

    /// Per-node rows computed in internal order, by id.
    fn node_rows<T: Clone>(&self, rows: Vec<T>) -> Vec<T> {
        match self.layout.nodes_by_id(&rows) {
            Cow::Borrowed(_) => rows,
            Cow::Owned(v) => v,
        }
    }

    /// Current node coordinates (m).
    pub fn positions(&self) -> Cow<'_, [Vec2]> {
        self.layout.nodes_by_id(&self.nodes.x)
    }

    /// Reference node coordinates (m).
    pub fn reference_positions(&self) -> Cow<'_, [Vec2]> {
        self.layout.nodes_by_id(&self.nodes.x0)
    }

    /// Element connectivity (node ids).
    pub fn triangles(&self) -> Cow<'_, [[u32; 3]]> {
        if self.layout.is_identity() {
            return Cow::Borrowed(&self.elems.conn);
        }
        let rows = self.elems.conn.iter().map(|t| t.map(|v| self.layout.node_id(v))).collect();
        Cow::Owned(self.elem_rows(rows))
    }

    /// Lumped nodal masses (kg per unit thickness).
    pub fn masses(&self) -> Cow<'_, [f64]> {
        self.layout.nodes_by_id(&self.nodes.mass)
    }

    /// Every element's density factor from selective mass scaling (1 where
    /// its mass is physical; see [`Settings::mass_scaling`](crate::Settings)).
    pub fn mass_scale(&self) -> Cow<'_, [f64]> {
        self.layout.elems_by_id(&self.elems.mass_scale)
    }

    /// Mass added by selective mass scaling to the active elements,
    /// `Σ (s_e − 1) ρ_e A_e` over reference areas (kg per unit thickness):
    /// the nodal masses sum to the physical mass plus this.
    pub fn added_mass(&self) -> f64 {
        let mut added = 0.0;
        for (e, t) in self.elems.conn.iter().enumerate() {
            let s = self.elems.mass_scale[e];
            if !self.elems.active[e] || s == 1.0 {
                continue;
            }
            let x = [self.nodes.x0[t[0] as usize], self.nodes.x0[t[1] as usize], self.nodes.x0[t[2] as usize]];
            added +=
                (s - 1.0) * self.materials[self.elems.material[e] as usize].density * fdem_element::signed_area(&x);
        }
        added
    }

    /// The material index of every element (pieces of a split element
    /// keep their parent's).
    pub fn element_materials(&self) -> Cow<'_, [u32]> {
        self.layout.elems_by_id(&self.elems.material)
    }

    /// Whether each element is in the model (not excavated).
    pub fn active(&self) -> Cow<'_, [bool]> {
        self.layout.elems_by_id(&self.elems.active)
    }

    /// Velocities at the current whole step (m/s):
    /// `vⁿ = (v^{n−½} + Δt^{n−½}/2 · f/m) / (1 + αΔt^{n−½}/2)`, which equals
    /// `(v^{n−½} + v^{n+½}) / 2` of the scheme, with constrained components
    /// at their prescribed values.
    pub fn velocities(&self) -> Vec<Vec2> {
        self.node_rows(self.velocities_by_index())
    }

    /// [`Self::velocities`] per internal index.
    pub(crate) fn velocities_by_index(&self) -> Vec<Vec2> {
        (0..self.n_nodes()).map(|i| self.whole_step_velocity(i)).collect()
    }

    /// `Σ ½ m |vⁿ − v^{n−½}|²` (J per unit thickness): how much the
    /// whole-step kinetic energy exceeds the half-step product `½ m
    /// v^{n−½}·v^{n+½}` that the central-difference scheme conserves with
    /// the elastic energy (for linear undamped motion, exactly; its
    /// accumulated work pairs forces with the centred displacements). Large
    /// only for modes near the stability limit.
    pub(crate) fn kinetic_lag(&self) -> f64 {
        let leaf = |r: Range<usize>| {
            r.map(|i| {
                let (w, h) = (self.whole_step_velocity(i), self.nodes.v[i]);
                0.5 * self.nodes.mass[i] * ((w[0] - h[0]) * (w[0] - h[0]) + (w[1] - h[1]) * (w[1] - h[1]))
            })
            .fold(0.0, |a, b| a + b)
        };
        self.pool.install(|| chunk_tree_sum(self.n_nodes(), 0.0, &leaf, &|a, b| a + b))
    }

    /// The whole-step velocity of node `i` (see [`Self::velocities`]),
    /// without allocating: the energy watchdog evaluates it inside the
    /// time loop.
    pub(crate) fn whole_step_velocity(&self, i: usize) -> Vec2 {
        let h = 0.5 * self.clock.dt_prev();
        let m = self.nodes.mass[i];
        let mut v = self.nodes.v[i];
        if m > 0.0 && h > 0.0 {
            let f = self.net_force(i);
            let denom = 1.0 + self.settings.mass_damping * h;
            v = [(v[0] + h * f[0] / m) / denom, (v[1] + h * f[1] / m) / denom];
        }
        let b = self.nodes.bc[i];
        if b != NO_BC {
            let c = &self.loads.constraints[b as usize];
            let a = c.amplitude.map_or(1.0, |k| self.loads.amplitudes[k as usize].at(self.clock.time()));
            for d in 0..2 {
                if c.fixed[d] {
                    v[d] = c.value[d] * a;
                }
            }
        }
        v
    }

    /// Resets the half-step velocities so that the whole-step velocities
    /// are `v_n` under the current forces: `v^{n−½} = (1 + αh) vⁿ − h f/m`,
    /// the central-difference start from a known state. Used after an
    /// instantaneous change of the forces at `tⁿ` (an excavation), which
    /// cannot change the velocities of the nodes that stay. Nodes without
    /// mass and prescribed components are left alone.
    pub(crate) fn keep_whole_step_velocities(&mut self, v_n: &[Vec2]) {
        let h = 0.5 * self.clock.dt_prev();
        if h == 0.0 {
            return;
        }
        for (i, &vn) in v_n.iter().enumerate() {
            self.set_whole_step_velocity(i, vn);
        }
    }

    /// Sets node `i`'s half-step velocity so that its whole-step velocity
    /// under the current forces is `vn` (see
    /// [`Self::keep_whole_step_velocities`]).
    pub(crate) fn set_whole_step_velocity(&mut self, i: usize, vn: Vec2) {
        let h = 0.5 * self.clock.dt_prev();
        let m = self.nodes.mass[i];
        if h == 0.0 || m <= 0.0 {
            return;
        }
        let denom = 1.0 + self.settings.mass_damping * h;
        let f = self.net_force(i);
        let b = self.nodes.bc[i];
        for d in 0..2 {
            if b != NO_BC && self.loads.constraints[b as usize].fixed[d] {
                continue;
            }
            self.nodes.v[i][d] = vn[d] * denom - h * f[d] / m;
        }
    }

    /// Net force on node `i` at the current configuration (N).
    fn net_force(&self, i: usize) -> Vec2 {
        let m = self.nodes.mass[i];
        let (p, c) = self.surface_force(i);
        let r = self.loads.release_force.get(i).copied().unwrap_or([0.0; 2]);
        let mut f = [m * self.loads.gravity[0] + p[0] + c[0] + r[0], m * self.loads.gravity[1] + p[1] + c[1] + r[1]];
        for &item in self.node_elems.row(i) {
            let fe = self.elems.force[item as usize];
            f[0] -= fe[0];
            f[1] -= fe[1];
        }
        f
    }

    /// Pressure and contact force on node `i` (N).
    fn surface_force(&self, i: usize) -> (Vec2, Vec2) {
        let b = self.surface.index_of[i];
        if b == NONE {
            return ([0.0; 2], [0.0; 2]);
        }
        (
            self.loads.pressure_force[b as usize],
            self.node_forces.contact_force.get(b as usize).copied().unwrap_or([0.0; 2]),
        )
    }

    /// Rotation `R` (cos, sin) of element `e` at the current configuration.
    fn rotation(&self, e: usize) -> (f64, f64) {
        let t = self.elems.conn[e];
        let x = [self.nodes.x[t[0] as usize], self.nodes.x[t[1] as usize], self.nodes.x[t[2] as usize]];
        polar_rotation(deformation_gradient(&self.elems.reference[e], &x))
    }

    /// Cauchy stress `σ = R σ̂ Rᵀ` of every element, `[xx, yy, zz, xy]` (Pa).
    pub fn stress(&self) -> Vec<[f64; 4]> {
        self.elem_rows(
            (0..self.n_elements())
                .map(|e| {
                    let (c, s) = self.rotation(e);
                    rotate(self.elems.stress[e], c, s)
                })
                .collect(),
        )
    }

    /// Plastic state of every element (co-rotational frame; defaults for
    /// elastic materials).
    pub fn plastic_states(&self) -> Cow<'_, [PlasticState]> {
        self.layout.elems_by_id(&self.elems.state)
    }

    /// Failure factor `F = κ H / f_t` of every element (eq. 2.21); 0 for
    /// elastic materials.
    pub fn failure_factors(&self) -> Vec<f64> {
        self.elem_rows(
            (0..self.n_elements())
                .map(|e| match &self.materials[self.elems.material[e] as usize].plastic {
                    Some(law) => law.failure_factor(&self.elems.state[e]),
                    None => 0.0,
                })
                .collect(),
        )
    }

    /// Direction of σ1 at the last tensile plastic step of every element in
    /// the current frame (rad from x): the rotating crack's normal.
    pub fn crack_directions(&self) -> Vec<f64> {
        self.elem_rows(self.crack_directions_by_index())
    }

    fn crack_directions_by_index(&self) -> Vec<f64> {
        (0..self.n_elements())
            .map(|e| {
                let (c, s) = self.rotation(e);
                let a = self.elems.state[e].crack_angle() + s.atan2(c);
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
        self.elem_rows(
            (0..self.n_elements())
                .map(|e| {
                    let (c, s) = self.rotation(e);
                    rotate(self.elems.state[e].plastic_strain, c, s)
                })
                .collect(),
        )
    }

    /// Spatial renumberings of nodes and elements so far
    /// ([`Settings::renumber`](crate::Settings::renumber)).
    pub fn renumberings(&self) -> u64 {
        self.layout.count
    }

    /// Cracks inserted so far (nodes opened), or `None` without fracture.
    pub fn insertions(&self) -> Option<u64> {
        self.fracture.as_ref().map(|f| f.insertions)
    }

    /// Steps between fracture checks (DESIGN §4.4), or `None` without
    /// fracture.
    pub fn fracture_interval(&self) -> Option<u32> {
        self.fracture.as_ref().map(|f| f.interval)
    }

    /// The largest relative change of mass and momentum any insertion has
    /// caused, or `None` without fracture.
    pub fn insertion_audit(&self) -> Option<crate::fracture::InsertionAudit> {
        self.fracture.as_ref().map(|f| f.audit)
    }

    /// The intact cohesive bonds across young cracks (empty without
    /// fracture).
    pub fn bonds(&self) -> Cow<'_, [crate::Bond]> {
        let bonds = self.fracture.as_ref().map_or(&[][..], |f| &f.bonds);
        if self.layout.is_identity() {
            return Cow::Borrowed(bonds);
        }
        Cow::Owned(bonds.iter().map(|b| crate::Bond { nodes: b.nodes.map(|v| self.layout.node_id(v)), ..*b }).collect())
    }

    /// Wall-clock time spent in each phase so far.
    pub fn phase_times(&self) -> PhaseTimes {
        self.diagnostics.phase_times
    }

    /// Counters of the contact search.
    pub fn contact_stats(&self) -> ContactStats {
        self.diagnostics.contact_stats
    }

    /// The free-surface facets `(start, end, law)` (node ids), oriented with
    /// the body on their left, in the order of the element and edge they
    /// belong to (element ids, edges 0, 1, 2).
    pub fn surface_facets(&self) -> Vec<([u32; 2], u16)> {
        let l = &self.layout;
        let mut rows: Vec<(u32, [u32; 2], u16)> =
            self.surface.facets.iter().map(|f| (3 * l.elem_id(f.key / 3) + f.key % 3, f.nodes, f.law)).collect();
        if !l.is_identity() {
            rows.sort_unstable_by_key(|r| r.0);
        }
        rows.into_iter().map(|(_, nodes, law)| (nodes.map(|v| l.node_id(v)), law)).collect()
    }

    /// The active contacts of the last step: every node's first contact,
    /// then the second contacts of corner nodes, each by node id.
    pub fn contacts(&self) -> Vec<ContactInfo> {
        let Some(c) = &self.contact else { return Vec::new() };
        let mut order: Vec<(usize, usize)> = (0..2).flat_map(|k| (0..c.out.len()).map(move |b| (k, b))).collect();
        if !self.layout.is_identity() {
            order.sort_by_key(|&(k, b)| (k, self.layout.node_id(self.surface.nodes[b])));
        }
        order
            .into_iter()
            .map(|(k, b)| (b, if k == 0 { (&c.out[b], &c.states[b]) } else { (&c.corner_out[b], &c.corner_states[b]) }))
            .filter(|(_, (o, _))| o.facet != NONE)
            .map(|(b, (o, m))| ContactInfo {
                node: self.layout.node_id(self.surface.nodes[b]),
                facet: self.surface.facets[o.facet as usize].nodes.map(|v| self.layout.node_id(v)),
                xi: o.xi,
                gap: o.gap,
                normal_force: o.normal_force,
                tangential_force: o.tangential_force,
                slipping: o.slipping,
                offset: m.offset,
            })
            .collect()
    }

    /// Current element areas (m²).
    pub fn areas(&self) -> Vec<f64> {
        self.elem_rows(
            self.elems
                .conn
                .iter()
                .map(|t| {
                    signed_area(&[
                        self.nodes.x[t[0] as usize],
                        self.nodes.x[t[1] as usize],
                        self.nodes.x[t[2] as usize],
                    ])
                })
                .collect(),
        )
    }

    /// Kinetic energy at the current whole step (J per unit thickness),
    /// summed per chunk of nodes, then over chunks ([`chunk_tree_sum`]: the
    /// same bits on any thread count).
    pub fn kinetic_energy(&self) -> f64 {
        let leaf = |r: Range<usize>| {
            r.map(|i| {
                let v = self.whole_step_velocity(i);
                0.5 * self.nodes.mass[i] * (v[0] * v[0] + v[1] * v[1])
            })
            .fold(0.0, |a, b| a + b)
        };
        self.pool.install(|| chunk_tree_sum(self.n_nodes(), 0.0, &leaf, &|a, b| a + b))
    }

    /// Elastic strain energy `Σ A ½ σ̂ : C⁻¹ : σ̂` (J per unit thickness),
    /// summed per chunk of elements, then over chunks ([`chunk_tree_sum`]).
    pub fn elastic_energy(&self) -> f64 {
        let x = &self.nodes.x;
        let leaf = |r: Range<usize>| {
            r.filter(|&e| self.elems.active[e])
                .map(|e| {
                    let t = self.elems.conn[e];
                    let area = signed_area(&[x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]]);
                    let mat = &self.materials[self.elems.material[e] as usize];
                    area * mat.elastic.energy_density(self.elems.stress[e])
                })
                .fold(0.0, |a, b| a + b)
        };
        self.pool.install(|| chunk_tree_sum(self.n_elements(), 0.0, &leaf, &|a, b| a + b))
    }

    /// Node `i`'s share of the energy account at the current whole step:
    /// `[kinetic, external, support, mass damping, contact, contact
    /// damping]`, the last five the pending second halves of the work of
    /// the last step (see [`Self::energies`]).
    pub(crate) fn node_energy_terms(&self, i: usize) -> [f64; 6] {
        let h = 0.5 * self.clock.dt_prev();
        let alpha = self.settings.mass_damping;
        let g = self.loads.gravity;
        let m = self.nodes.mass[i];
        let v = self.whole_step_velocity(i);
        let kinetic = 0.5 * m * (v[0] * v[0] + v[1] * v[1]);
        if m <= 0.0 || h == 0.0 {
            return [kinetic, 0.0, 0.0, 0.0, 0.0, 0.0];
        }
        let half = self.nodes.v[i];
        let dx = [h * half[0], h * half[1]];
        let (p, c) = self.surface_force(i);
        let r = self.loads.release_force.get(i).copied().unwrap_or([0.0; 2]);
        let external = (m * g[0] + p[0] + r[0]) * dx[0] + (m * g[1] + p[1] + r[1]) * dx[1];
        let contact = c[0] * dx[0] + c[1] * dx[1];
        let mut contact_damping = 0.0;
        let bn = self.surface.index_of[i];
        if bn != NONE {
            if let Some(fd) = self.node_forces.contact_damping_force.get(bn as usize) {
                contact_damping = -(fd[0] * dx[0] + fd[1] * dx[1]);
            }
        }
        let damping = alpha * m * (v[0] * dx[0] + v[1] * dx[1]);
        let r = self.reaction_at(i, v);
        let support = r[0] * dx[0] + r[1] * dx[1];
        [kinetic, external, support, damping, contact, contact_damping]
    }

    /// The force node `i`'s support exerts on it at the current whole step
    /// (N per unit thickness), zero in its free components and without a
    /// support: `R = m (vⁿ − v^{n−½}) / (Δt^{n−½}/2) + α m vⁿ − f(xⁿ)` on
    /// each held component, the force that brings the node from its last
    /// half-step velocity to the prescribed whole-step velocity `vⁿ`
    /// against the net force `f` of elements, loads, gravity and contact
    /// (the same term the support work accumulates, DESIGN §4.2). `v` is
    /// [`Self::whole_step_velocity`] of the node.
    fn reaction_at(&self, i: usize, v: Vec2) -> Vec2 {
        let b = self.nodes.bc[i];
        let h = 0.5 * self.clock.dt_prev();
        let m = self.nodes.mass[i];
        let mut r = [0.0; 2];
        if b == NO_BC || m <= 0.0 {
            return r;
        }
        let f = self.net_force(i);
        let c = &self.loads.constraints[b as usize];
        let alpha = self.settings.mass_damping;
        let half = self.nodes.v[i];
        for d in 0..2 {
            if c.fixed[d] {
                // before the first step there is no last half step: the
                // support holds the node in static balance
                let inertia = if h > 0.0 { m * (v[d] - half[d]) / h } else { 0.0 };
                r[d] = inertia + alpha * m * v[d] - f[d];
            }
        }
        r
    }

    /// The node of the model each node descends from (by node id): itself
    /// for a node of the model or one crack insertion placed on a split
    /// edge, the node it was copied from for a copy (so a support's copies
    /// are found by the support's nodes).
    pub fn node_origins(&self) -> Vec<u32> {
        self.node_rows(self.ancestor.clone())
    }

    /// Reaction forces: the force each node's support (a fixed or
    /// prescribed velocity component) exerts on the model at the current
    /// whole step (N per unit thickness), by node id, zero for free nodes
    /// and components. The model exerts the opposite force on the support:
    /// summed over a platen's nodes, that is the load of a load–displacement
    /// curve. The sum of all reactions, loads, gravity and inertia is zero
    /// (the node's equation of motion).
    pub fn reaction_forces(&self) -> Vec<Vec2> {
        let rows = (0..self.n_nodes()).map(|i| self.reaction_at(i, self.whole_step_velocity(i))).collect();
        self.node_rows(rows)
    }

    /// The energy account at the current step.
    ///
    /// The accumulated work pairs the force of step `n` with the centred
    /// displacement `(Δx^{n−½} + Δx^{n+½}) / 2`; at a whole step the second
    /// half of the last displacement is still pending and is added here, so
    /// that the account matches the whole-step kinetic energy.
    pub fn energies(&self) -> Energies {
        // nodes by chunks along the same tree as `kinetic_energy` (so the
        // kinetic energy is its, to the bit), in one pass, in parallel and
        // without allocating (the energy watchdog calls this inside the
        // time loop)
        let leaf = |r: Range<usize>| {
            let mut sum = [0.0; 6];
            for i in r {
                let t = self.node_energy_terms(i);
                for k in 0..6 {
                    sum[k] += t[k];
                }
            }
            sum
        };
        let add = |a: [f64; 6], b: [f64; 6]| std::array::from_fn(|k| a[k] + b[k]);
        let sum = self.pool.install(|| chunk_tree_sum(self.n_nodes(), [0.0; 6], &leaf, &add));
        let [kinetic, external, support, damping, contact, contact_damping] = sum;
        let acc = &self.ledger.account;
        Energies {
            kinetic,
            elastic: self.elastic_energy(),
            external_work: acc.external_work + external,
            support_work: acc.support_work + support,
            mass_damping: acc.mass_damping + damping,
            contact_work: acc.contact_work + contact,
            contact_damping: acc.contact_damping + contact_damping,
            ..*acc
        }
    }
}
