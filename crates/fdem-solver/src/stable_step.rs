//! The stable step (DESIGN §4.2, docs/contact.md "Stable step"): the
//! critical step of the elements, the boundary nodes with their contact
//! springs and the bonds, kept in the [`Clock`](crate::clock::Clock); and
//! selective mass scaling (docs/mass_scaling.md), which raises the masses
//! that would need a shorter step than the one asked for.

use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;

use fdem_element::Vec2;

use crate::contact::ContactModel;
use crate::passes;
use crate::simulation::Simulation;

/// The highest frequencies the stable step is worked out from, kept
/// between its evaluations.
#[derive(Default)]
pub(crate) struct Frequencies {
    /// Highest frequency of every element at the last stable-step update
    /// (rad/s; saved in checkpoints).
    pub omega: Vec<f64>,
    /// Per boundary node: its frequency with its contact springs
    /// ([`Simulation::contact_node_frequency`]) at the last stable-step
    /// evaluation (scratch; sized by it).
    pub contact_omega: Vec<Option<NodeOmega>>,
    /// What a crack insertion needs to carry [`Self::contact_omega`] over
    /// to the new surface instead of working every boundary node out again
    /// ([`Simulation::carry_contact_omega`]; scratch).
    pub omega_carry: OmegaCarry,
}

/// Scratch for carrying the boundary nodes' contact frequencies over a
/// topology change ([`Simulation::carry_contact_omega`]).
#[derive(Default)]
pub(crate) struct OmegaCarry {
    /// The nodes (mesh ids, ascending) whose contact frequency the last
    /// topology change made stale: to be worked out again by the next
    /// stable-step evaluation after it.
    pub stale: Vec<u32>,
    /// The node masses before the last rebuild (a frequency whose node's
    /// mass changed in any bit is stale).
    pub old_mass: Vec<f64>,
    /// The frequencies' buffer before the carry-over (reused).
    pub spare: Vec<Option<NodeOmega>>,
}

/// A boundary node's frequencies with its contact springs
/// ([`Simulation::contact_node_frequency`]), kept between stable-step
/// evaluations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct NodeOmega {
    /// The frequency (rad/s) that bounds the step at the node,
    /// [`contact_bound`]: its critical step is `2 / bound`.
    pub bound: f64,
    /// `ω_e² + 4 k ℓ / m` (rad²/s²), the node's elements and contact
    /// springs, to which a bond at the node adds its own term. Kept so that
    /// the bonds' pass after a crack insertion reads it instead of walking
    /// every bond node's elements and facets again (3.3% of the 10⁴
    /// fragmenting impact at one thread went there).
    pub squared: f64,
}

impl Simulation {
    /// Re-evaluates the stable step (DESIGN §4.2): `s · min` over the
    /// elements of `2/ω_e` and, with contact, over the boundary nodes of
    /// `2/ω` with `ω` from [`contact_bound`] (`ω_c² = 4 k ℓ / m`: a node's
    /// contact spring is the stiffness k times its tributary length ℓ;
    /// two-pass contact doubles it, a free partner node doubles the relative
    /// frequency²), and over the bonds; or the fixed step. With mass
    /// scaling on, first raises the masses that would need a shorter step
    /// than the target ([`Self::scale_masses`]).
    pub fn update_time_step(&mut self) {
        self.update_time_step_for(None, true);
    }

    /// [`Self::update_time_step`], re-evaluating only the listed elements'
    /// frequencies (the others are unchanged since the last evaluation) when
    /// `touched` is given: after a topology change. `rescale` allows mass
    /// scaling (at set-up, settings changes and topology changes; the
    /// periodic re-evaluation in the time loop never changes masses).
    pub(crate) fn update_time_step_for(&mut self, touched: Option<&[u32]>, rescale: bool) {
        let clock = Instant::now();
        let mut crit = self.critical_step(touched);
        if let (true, Some(target), None) = (rescale, self.settings.mass_scaling, self.settings.fixed_dt) {
            if self.settings.safety * crit < target {
                let changed = self.scale_masses(target / self.settings.safety);
                if !changed.is_empty() {
                    // only the changed elements' frequencies and their
                    // nodes' masses moved: their nodes' contact
                    // frequencies are worked out again, the others kept
                    let mut moved: Vec<u32> = changed.iter().flat_map(|&e| self.elems.conn[e as usize]).collect();
                    moved.sort_unstable();
                    moved.dedup();
                    crit = self.critical_step_of(Some(&changed), Some(&moved));
                }
            }
        }
        self.clock.set_step(crit, &self.settings);
        self.diagnostics.phase_times.time_step += clock.elapsed().as_secs_f64();
    }

    /// The critical step before the safety factor (s), updating the stored
    /// element frequencies (all, or the listed elements') and the boundary
    /// nodes' contact frequencies: every node's, or with `touched` (after
    /// a topology change) those the change left stale.
    fn critical_step(&mut self, touched: Option<&[u32]>) -> f64 {
        if touched.is_none() {
            return self.critical_step_of(None, None);
        }
        // after a topology change: the contact frequencies it left stale
        // (the others were carried over, `carry_contact_omega`; when they
        // could not be, the list is ignored and every node evaluated)
        let stale = std::mem::take(&mut self.frequencies.omega_carry.stale);
        let crit = self.critical_step_of(touched, Some(&stale));
        self.frequencies.omega_carry.stale = stale;
        crit
    }

    /// [`Self::critical_step`], re-evaluating the contact frequencies of
    /// the boundary nodes among `nodes` (mesh ids) only, when given: those
    /// whose mass or elements' frequencies changed since the last
    /// evaluation (the others' are exactly what they were; the minimum is
    /// the same as over a full evaluation). Mass scaling at an insertion
    /// used to evaluate every boundary node three times.
    fn critical_step_of(&mut self, touched: Option<&[u32]>, nodes: Option<&[u32]>) -> f64 {
        let pool = Arc::clone(&self.pool);
        let element_crit = pool.install(|| {
            let inp = passes::element_inputs!(self, beta: self.settings.stiffness_damping, dt: 0.0);
            let (scale, omega) = (&self.elems.mass_scale, &mut self.frequencies.omega);
            match touched {
                None => passes::element_frequencies(&inp, scale, omega),
                Some(list) => {
                    passes::element_frequencies_of(&inp, scale, list, omega);
                    passes::critical_from_frequencies(omega, self.settings.stiffness_damping)
                }
            }
        });
        // the contact nodes' frequencies read the elements' just updated;
        // each node's critical step is `2/ω` (a minimum does not depend on
        // the order, so the passes are parallel)
        let mut crit = element_crit;
        if let Some(contact) = &self.contact {
            let nb = self.surface.nodes.len();
            let mut wr = std::mem::take(&mut self.frequencies.contact_omega);
            let step = |w: &Option<NodeOmega>| w.map_or(f64::INFINITY, |w| 2.0 / w.bound);
            let least = match nodes {
                Some(list) if wr.len() == nb => {
                    for &v in list {
                        let b = self.surface.index_of[v as usize];
                        if b != crate::NONE {
                            wr[b as usize] = self.contact_node_frequency(contact, b as usize);
                        }
                    }
                    pool.install(|| {
                        wr.par_iter().with_min_len(crate::CHUNK).map(step).reduce(|| f64::INFINITY, f64::min)
                    })
                }
                _ => {
                    wr.resize(nb, None);
                    pool.install(|| {
                        wr.par_iter_mut()
                            .enumerate()
                            .with_min_len(crate::CHUNK)
                            .map(|(b, out)| {
                                *out = self.contact_node_frequency(contact, b);
                                step(out)
                            })
                            .reduce(|| f64::INFINITY, f64::min)
                    })
                }
            };
            self.frequencies.contact_omega = wr;
            crit = crit.min(least);
        }
        // the boundary nodes' ω² as just evaluated, where they are for the
        // current surface (they are whenever there is contact)
        let nb = self.surface.nodes.len();
        let known = (self.frequencies.contact_omega.len() == nb).then_some(&self.frequencies.contact_omega[..]);
        pool.install(|| {
            if let Some(fr) = &self.fracture {
                // a bond adds k ℓ (1/m_a + 1/m_b) to the frequency² of its
                // nodes, on top of their elements and contact springs
                let k_c = self.contact.as_ref().map_or(0.0, |c| c.max_stiffness);
                // parallel, like the contact nodes' minimum above
                let least = fr
                    .bonds
                    .par_iter()
                    .with_min_len(crate::CHUNK)
                    .filter_map(|bond| {
                        let [a, b] = bond.nodes.map(|v| v as usize);
                        let (ma, mb) = (self.nodes.mass[a], self.nodes.mass[b]);
                        if ma <= 0.0 || mb <= 0.0 {
                            return None;
                        }
                        // the same expressions as `contact_node_frequency`'s
                        // (so the same bits whether read or worked out)
                        let node_w2 = |v: usize, m: f64| {
                            let bi = self.surface.index_of[v];
                            if let Some(w) = known.filter(|_| bi != crate::NONE).and_then(|k| k[bi as usize]) {
                                return w.squared;
                            }
                            let we = self.node_frequency(v);
                            let wc2 = if bi == crate::NONE {
                                0.0
                            } else {
                                4.0 * k_c * self.surface.tributary_max(bi as usize) / m
                            };
                            we * we + wc2
                        };
                        let wb2 = bond.stiffness * bond.length * (1.0 / ma + 1.0 / mb);
                        let w = (node_w2(a, ma).max(node_w2(b, mb)) + wb2).sqrt();
                        Some(2.0 / w)
                    })
                    .reduce(|| f64::INFINITY, f64::min);
                crit = crit.min(least);
            }
            crit
        })
    }

    /// The highest frequency among node `v`'s elements (rad/s).
    fn node_frequency(&self, v: usize) -> f64 {
        self.node_elems.row(v).iter().map(|&i| self.frequencies.omega[(i / 3) as usize]).fold(0.0, f64::max)
    }

    /// Boundary node `b`'s frequency with its contact springs
    /// ([`contact_bound`]); its critical step is `2 / ω`. `None` for a node
    /// without mass. The contact dashpot does not shorten it: the node pass
    /// applies it as the backward-Euler step of each pair on the predicted
    /// velocities, where an explicit dashpot of damping ratio ξ cost the
    /// factor `√(1 + ξ²) − ξ` (docs/contact.md).
    pub(crate) fn contact_node_frequency(&self, contact: &ContactModel, b: usize) -> Option<NodeOmega> {
        let node = self.surface.nodes[b] as usize;
        let m = self.nodes.mass[node];
        if m <= 0.0 {
            return None;
        }
        let we = self.node_frequency(node);
        // a node's contact spring is k ℓ (ℓ its tributary length); two-pass
        // contact doubles it and a free partner node doubles the relative
        // frequency²: 2kℓ (1/m1 + 1/m2) ≤ 4kℓ/m at the lighter node, so
        // 4kℓ/m at each node covers all pairs
        let wc2 = 4.0 * contact.max_stiffness * self.surface.tributary_max(b) / m;
        Some(NodeOmega { bound: contact_bound(we, wc2, contact.may_rattle()), squared: we * we + wc2 })
    }

    /// Selective mass scaling (docs/mass_scaling.md): raises the density
    /// factor of every element whose own frequency, or whose node's
    /// frequency with its contact springs, would need a step shorter than
    /// `target` (s, before the safety factor), by the factor that makes it
    /// meet `target` exactly. An element needs `ω_e ≤ W` with `W = 2 /
    /// √(T² + 2Tβ)` (the stiffness-damping-reduced bound solved for ω); a
    /// contact node's frequency scales as `1/√s` when all its elements'
    /// masses grow by `s`, so it needs the factor `(ω T / 2)²` on them.
    /// Factors only grow. Once the run has started, a node whose mass
    /// grows keeps its momentum (its whole-step velocity drops by
    /// `m_old / m_new`), the reported work terms stay continuous, and the
    /// kinetic energy that this inelastic accretion takes is booked as
    /// `mass_scaling` in the energy account. Before the first step the
    /// given velocities stay. Returns the elements changed, ascending.
    pub(crate) fn scale_masses(&mut self, target: f64) -> Vec<u32> {
        let beta = self.settings.stiffness_damping;
        let w_max = 2.0 / (target * target + 2.0 * target * beta).sqrt();
        // the elements that need more mass, in parallel (collected in
        // order; the list is sorted below anyway)
        let pool = Arc::clone(&self.pool);
        let mut need: Vec<(u32, f64)> = pool.install(|| {
            let (omega, active) = (&self.frequencies.omega, &self.elems.active);
            let mut need: Vec<(u32, f64)> = (0..omega.len())
                .into_par_iter()
                .with_min_len(crate::CHUNK)
                .filter(|&e| active[e] && omega[e] > w_max)
                .map(|e| (e as u32, (omega[e] / w_max) * (omega[e] / w_max)))
                .collect();
            if self.contact.is_some() {
                // the frequencies the step was just found from
                // (`update_time_step_for` calls this right after
                // `critical_step`)
                debug_assert_eq!(self.frequencies.contact_omega.len(), self.surface.nodes.len());
                let nodes: Vec<(usize, f64)> = self
                    .frequencies
                    .contact_omega
                    .par_iter()
                    .enumerate()
                    .with_min_len(crate::CHUNK)
                    .filter_map(|(b, &w)| {
                        let s = (w?.bound * target / 2.0).powi(2);
                        (s > 1.0).then_some((b, s))
                    })
                    .collect();
                for (b, s) in nodes {
                    let node = self.surface.nodes[b] as usize;
                    need.extend(self.node_elems.row(node).iter().map(|&i| (i / 3, s)));
                }
            }
            need
        });
        if need.is_empty() {
            return Vec::new();
        }
        need.sort_unstable_by(|a, b| a.0.cmp(&b.0).then(b.1.total_cmp(&a.1)));
        need.dedup_by_key(|p| p.0); // keeps the largest factor of each element
        let started = self.clock.started();
        for &(e, s) in &need {
            self.elems.mass_scale[e as usize] *= s;
        }
        let mut nodes: Vec<u32> = need.iter().flat_map(|&(e, _)| self.elems.conn[e as usize]).collect();
        nodes.sort_unstable();
        nodes.dedup();
        // only these nodes' masses change: their share of the account
        // before and after is the change of the whole account
        let terms = |sim: &Self| {
            let mut sum = [0.0; 6];
            for &v in &nodes {
                let t = sim.node_energy_terms(v as usize);
                (0..6).for_each(|k| sum[k] += t[k]);
            }
            sum
        };
        let before = if started { terms(self) } else { [0.0; 6] };
        let old: Vec<(f64, Vec2)> =
            nodes.iter().map(|&v| (self.nodes.mass[v as usize], self.whole_step_velocity(v as usize))).collect();
        for &v in &nodes {
            let m = crate::topology::node_mass(&self.node_elems, v as usize, |e| self.nodal_mass_of(e));
            self.nodes.mass[v as usize] = m;
        }
        if started {
            for (&v, &(m_old, vn)) in nodes.iter().zip(&old) {
                let k = m_old / self.nodes.mass[v as usize];
                self.set_whole_step_velocity(v as usize, [vn[0] * k, vn[1] * k]);
            }
            let after = terms(self);
            let acc = &mut self.ledger.account;
            acc.external_work += before[1] - after[1];
            acc.support_work += before[2] - after[2];
            acc.mass_damping += before[3] - after[3];
            acc.contact_work += before[4] - after[4];
            acc.contact_damping += before[5] - after[5];
            acc.mass_scaling += before[0] - after[0];
        }
        need.into_iter().map(|(e, _)| e).collect()
    }
}

/// The frequency (rad/s) that sets the stable step `s · 2/ω` of a boundary
/// node with element frequency `we` and contact frequency² `wc2`
/// (`4kℓ/m`, [`Simulation::contact_node_frequency`]): `ω = √(ω_e² + ω_c²)`,
/// i.e. `Δt ≤ s · 2/√(ω_e² + ω_c²)` for stability of the node with its
/// springs (DESIGN §4.2), and, where a contact may `rattle` (an interface
/// law with a dashpot weaker than [`RATTLE_DAMPING`](crate::contact::RATTLE_DAMPING)),
/// `ω = max(√(ω_e² + ω_c²), 2 ω_c)`: also `ω_c Δt ≤ s` for the accuracy of
/// contact onsets.
///
/// Why the second bound: a contact is switched on at the first step that
/// finds the node inside, a fraction `τ/Δt` of a step after it crossed the
/// facet, and the central-difference scheme's conserved energy then jumps
/// by `−½ k v² τ (Δt − τ)`: up to `(ω_c Δt)²/4` of the node's kinetic
/// energy at every onset, and back by a different amount when it leaves.
/// A spring much stiffer than the node's elements is resolved in one or
/// two steps at the stability bound, the pressed face nodes rattle, and the
/// onsets of every bounce add up: two bars meeting at 1 m/s with a node
/// spring of 20 E (`penalty_factor` 20), undamped, left with 3.2 times the
/// energy they brought at `ω_c Δt = 1.6`; at 1.0 with 0.9% more, at 0.8
/// with 0.06% (`test_undamped_impact_keeps_its_energy_at_the_default_step`).
/// A dashpot of `ξ ≥ 0.05` stops the rattle (the same bars lost 0.0–0.2%
/// at `ω_c Δt = 1.6`), so damped contacts keep the longer step: where the
/// elements are as stiff as the contact (the default penalty `E/h̄`) the
/// second bound costs a factor up to `√2` in step (1.48 times the steps of
/// the paper-scale caving run, whose laws all have `ξ = 0.5`).
#[inline]
pub(crate) fn contact_bound(we: f64, wc2: f64, rattle: bool) -> f64 {
    let stable = (we * we + wc2).sqrt();
    if rattle {
        stable.max(2.0 * wc2.sqrt())
    } else {
        stable
    }
}
