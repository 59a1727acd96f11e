//! Staged excavation, the clock reset after an equilibrium stage, and
//! fragments (DESIGN §4.6, issue 6).
//!
//! Removing elements takes their mass and forces off their nodes (with
//! the pieces crack insertion has cut from them: `lineage.rs`); a node
//! left without elements leaves the model (zero mass: the node pass skips
//! it, it is on no surface, its bonds go). What the removal takes away, the
//! elements' elastic energy, the kinetic energy of the mass that left and
//! the elastic energy of dropped bonds, is booked as `excavated`, so the
//! energy account still closes.

use fdem_element::Vec2;

use crate::error::SetupError;
use crate::simulation::Simulation;
use crate::{Energies, ExcavationStage};

/// The excavation stages of a run and where it stands in them.
#[derive(Default)]
pub(crate) struct Staging {
    /// Excavation stages in time order.
    pub stages: Vec<ExcavationStage>,
    /// The next one to run.
    pub next_stage: usize,
    /// Elastic stage: plastic laws and crack insertion off (equilibrium).
    pub elastic_stage: bool,
}

impl Simulation {
    /// Removes `elements` from the model now (ids; ones already removed are
    /// skipped) and returns how many were removed. With `descendants`, also
    /// every piece crack insertion has cut from them (`lineage.rs`): an id
    /// then names the rock that element was when it was made, as the
    /// model's element sets and excavation stages mean it. Without, exactly
    /// the elements named. Errors name the first id out of range; nothing
    /// is changed then.
    pub fn deactivate(&mut self, elements: &[u32], descendants: bool) -> Result<usize, SetupError> {
        self.deactivate_gradually(elements, descendants, 0.0)
    }

    /// [`Self::deactivate`], with the forces the removed elements exerted
    /// on the nodes that stay applied to those nodes as loads that fall
    /// linearly to zero over `ramp` (s; 0: at once): gradual excavation,
    /// as FLAC and UDEC users know it. The rock around the opening then
    /// unloads over the ramp instead of in one step, which keeps the
    /// dynamic spalling of an instantaneous excavation out of a
    /// quasi-static one. The loads' work is external work.
    pub fn deactivate_gradually(
        &mut self,
        elements: &[u32],
        descendants: bool,
        ramp: f64,
    ) -> Result<usize, SetupError> {
        if !(ramp >= 0.0 && ramp.is_finite()) {
            return Err(SetupError::Invalid(format!("release time {ramp} must be finite and >= 0")));
        }
        let m = self.elems.conn.len();
        if let Some(&e) = elements.iter().find(|&&e| e as usize >= m) {
            return Err(SetupError::Invalid(format!("element {e} does not exist (the model has {m})")));
        }
        let remove: Vec<usize> = {
            let mut r: Vec<usize> = if descendants {
                let marked = self.descendants(elements);
                (0..m as u32).filter(|&id| marked[id as usize]).map(|id| self.layout.elem_index(id) as usize).collect()
            } else {
                elements.iter().map(|&e| self.layout.elem_index(e) as usize).collect()
            };
            r.retain(|&e| self.elems.active[e]);
            r.sort_unstable();
            r.dedup();
            r
        };
        if remove.is_empty() {
            return Ok(0);
        }
        // Removal happens at the whole step t_n. The work done up to t_n is
        // what it was, so the reported work terms (whose pending half-step
        // parts depend on the nodal masses and forces) are kept continuous;
        // the stored and kinetic energy the removal takes away is booked
        // as excavated: the removed elements' strain energy, the kinetic
        // energy of the mass that left, dropped bonds and contacts. The
        // nodes that stay keep their whole-step velocities.
        let before = self.energies();
        let v_n = self.velocities_by_index();
        // the removed elements' forces on their nodes, which the nodes that
        // stay go on feeling as loads over the ramp
        let mut load: Vec<(u32, Vec2)> = Vec::new();
        if ramp > 0.0 {
            for &e in &remove {
                for (k, &v) in self.elems.conn[e].iter().enumerate() {
                    let f = self.elems.force[3 * e + k];
                    load.push((v, [-f[0], -f[1]]));
                }
            }
            load.sort_by_key(|&(v, _)| v);
        }
        for &e in &remove {
            self.elems.active[e] = false;
        }
        self.rebuild_structure(&[], None);
        for (v, &m) in self.nodes.v.iter_mut().zip(&self.nodes.mass) {
            if m <= 0.0 {
                *v = [0.0; 2];
            }
        }
        if let Some(fr) = &mut self.fracture {
            let mass = &self.nodes.mass;
            fr.bonds.retain(|b| b.nodes.iter().all(|&n| mass[n as usize] > 0.0));
            fr.bond_gather.invalidate();
        }
        self.refresh_forces();
        // the loads act from now: before the whole-step velocities are kept
        if !load.is_empty() {
            let mut release = crate::Release { start: self.clock.time(), ramp, nodes: Vec::new(), forces: Vec::new() };
            for (v, f) in load {
                if self.nodes.mass[v as usize] <= 0.0 {
                    continue; // the node left with the elements
                }
                if release.nodes.last() == Some(&v) {
                    let last = release.forces.last_mut().expect("a force per node");
                    *last = [last[0] + f[0], last[1] + f[1]];
                } else {
                    release.nodes.push(v);
                    release.forces.push(f);
                }
            }
            self.loads.released.push(release);
            self.update_release();
        }
        self.keep_whole_step_velocities(&v_n);
        let after = self.energies();
        self.ledger.account.excavated += self.keep_work_continuous(&before, &after);
        // after the booking: mass scaling books its own change
        self.update_time_step();
        Ok(remove.len())
    }

    /// After an instantaneous change of the model at the whole step `tⁿ`
    /// (`before` and `after` it): keeps the reported work terms (whose
    /// pending half-step parts depend on nodal masses and forces)
    /// continuous, and returns the held energy (kinetic, elastic, contact
    /// and bond springs) the change took away, for the caller to book.
    pub(crate) fn keep_work_continuous(&mut self, before: &Energies, after: &Energies) -> f64 {
        let held = |e: &Energies| e.kinetic + e.elastic + e.contact_elastic + e.cohesive_elastic;
        let acc = &mut self.ledger.account;
        acc.external_work += before.external_work - after.external_work;
        acc.support_work += before.support_work - after.support_work;
        acc.mass_damping += before.mass_damping - after.mass_damping;
        acc.contact_work += before.contact_work - after.contact_work;
        acc.contact_damping += before.contact_damping - after.contact_damping;
        held(before) - held(after)
    }

    /// Runs the stages that are due at the current time; returns whether
    /// any ran.
    pub(crate) fn excavate_due(&mut self) -> bool {
        let mut ran = false;
        while self.staging.next_stage < self.staging.stages.len()
            && self.staging.stages[self.staging.next_stage].time <= self.clock.time()
        {
            let stage = std::mem::take(&mut self.staging.stages[self.staging.next_stage].elements);
            // ids were checked at set-up; a stage removes the pieces
            // cracks have cut from its elements too
            let ramp = self.staging.stages[self.staging.next_stage].ramp;
            let _ = self.deactivate_gradually(&stage, true, ramp);
            self.staging.stages[self.staging.next_stage].elements = stage;
            self.staging.next_stage += 1;
            ran = true;
        }
        ran
    }

    /// The excavation stages, and how many have run.
    pub fn stages(&self) -> (&[ExcavationStage], usize) {
        (&self.staging.stages, self.staging.next_stage)
    }

    /// Starts the clock again at `t = 0` from the current state (after an
    /// equilibrium stage): time and step count are reset, and the energy
    /// account starts afresh with the current kinetic and stored energy as
    /// its initial values (its residual is zero right after). Excavation
    /// stages are timed from the new zero.
    pub fn restart_clock(&mut self) {
        let e = self.energies();
        let pending = |reported: f64, accumulated: f64| accumulated - reported;
        let old = self.ledger.account;
        self.ledger.account = Energies {
            kinetic_initial: e.kinetic,
            elastic_initial: e.elastic + e.contact_elastic + e.cohesive_elastic,
            // the work still pending at this whole step is booked against
            // the new start, so that the reported terms start at zero
            external_work: pending(e.external_work, old.external_work),
            support_work: pending(e.support_work, old.support_work),
            mass_damping: pending(e.mass_damping, old.mass_damping),
            contact_work: pending(e.contact_work, old.contact_work),
            contact_damping: pending(e.contact_damping, old.contact_damping),
            contact_elastic: old.contact_elastic,
            cohesive_elastic: old.cohesive_elastic,
            ..Energies::default()
        };
        self.clock.restart();
        self.staging.next_stage = 0;
        while self.staging.next_stage < self.staging.stages.len()
            && self.staging.stages[self.staging.next_stage].time < 0.0
        {
            self.staging.next_stage += 1;
        }
    }

    /// For every element (by id) the fragment (body) it belongs to: active
    /// elements that share a node are in the same fragment; fragments are
    /// numbered 0, 1, … in order of their smallest element id; removed
    /// elements get `u32::MAX`. Linear in the element count.
    pub fn fragment_labels(&self) -> Vec<u32> {
        let labels = self.fragment_labels_by_index();
        if self.layout.is_identity() {
            return labels;
        }
        // in id order, numbered again by first appearance
        let labels = self.layout.elems_by_id(&labels).into_owned();
        let mut renamed = vec![u32::MAX; labels.len()];
        let mut next = 0u32;
        labels
            .iter()
            .map(|&l| {
                if l == u32::MAX {
                    return l;
                }
                if renamed[l as usize] == u32::MAX {
                    renamed[l as usize] = next;
                    next += 1;
                }
                renamed[l as usize]
            })
            .collect()
    }

    /// [`Self::fragment_labels`] per internal index, numbered in internal
    /// order.
    fn fragment_labels_by_index(&self) -> Vec<u32> {
        let n = self.nodes.x.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut i: u32) -> u32 {
            while parent[i as usize] != i {
                let g = parent[parent[i as usize] as usize];
                parent[i as usize] = g;
                i = g;
            }
            i
        }
        for (e, t) in self.elems.conn.iter().enumerate() {
            if !self.elems.active[e] {
                continue;
            }
            for k in 1..3 {
                let (a, b) = (find(&mut parent, t[0]), find(&mut parent, t[k]));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
        let mut label_of_root = vec![u32::MAX; n];
        let mut next = 0u32;
        let mut labels = vec![u32::MAX; self.elems.conn.len()];
        for (e, t) in self.elems.conn.iter().enumerate() {
            if !self.elems.active[e] {
                continue;
            }
            let r = find(&mut parent, t[0]) as usize;
            if label_of_root[r] == u32::MAX {
                label_of_root[r] = next;
                next += 1;
            }
            labels[e] = label_of_root[r];
        }
        labels
    }
}
