//! Contact in the time loop: the glue between the solver's state and the
//! `fdem-contact` crate (DESIGN §4.5).

use std::collections::BTreeMap;

use fdem_contact::narrow::{self, ContactPartial, Contacts, FacetFrame, NarrowInputs};
use fdem_contact::{BroadPhase, ContactState, InterfaceLaw, NodeContact, Surface};
use fdem_element::Vec2;
use rayon::prelude::*;

use crate::error::SetupError;
use crate::model::ContactSpec;
use crate::NONE;

/// The forces the node pass takes from contact and bonds, per boundary
/// node, and its dashpot scratch (docs/contact.md, "Dashpots on the
/// predicted velocities").
#[derive(Default)]
pub(crate) struct NodeForces {
    /// Contact forces per boundary node at `xⁿ` (N); empty without contact.
    pub contact_force: Vec<Vec2>,
    /// Their contact-dashpot parts (N), whose work is the contact damping.
    pub contact_damping_force: Vec<Vec2>,
    /// Per boundary node: how many contact dashpots act on it (set by the
    /// contact assembly; derived, not saved).
    pub contact_damped: Vec<u16>,
    /// Scratch of the node pass with dashpots: the dashpot forces per
    /// boundary node (N), and per node the predicted velocity (m/s) and
    /// net force without the dashpots (N).
    pub dashpot_force: Vec<Vec2>,
    pub pred_v: Vec<Vec2>,
    pub pred_f: Vec<Vec2>,
}

/// Damping ratio of an interface's dashpot from which a penalty contact
/// no longer rattles at the stability bound. Two bars meeting at 1 m/s
/// with a node spring of 20 E or 100 E, at twice the default step
/// (`ω_c Δt = 1.6`): undamped they gained 55–155% of their energy, with
/// `ξ` 0.005–0.02 up to 143% in some runs and nothing in others; with
/// `ξ` from 0.05 to 0.5 every run lost 0.0–0.2% (docs/contact.md).
pub const RATTLE_DAMPING: f64 = 0.1;
/// Where [`ContactModel::assemble`] writes, per boundary node: the contact
/// forces (N), their dashpot parts (N), and how many dashpots act on the
/// node.
pub(crate) struct AssemblyOut<'a> {
    pub forces: &'a mut [Vec2],
    pub damping: &'a mut [Vec2],
    pub damped: &'a mut [u16],
}

/// Contact state and settings owned by the simulation.
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct ContactModel {
    pub laws: Vec<InterfaceLaw>,
    /// Laws other than 0 by facet (sorted pair of the nodes' ancestors).
    pub facet_laws: BTreeMap<(u32, u32), u16>,
    /// Law of crack faces.
    pub crack_law: u16,
    pub broad: BroadPhase,
    /// Per boundary node: friction memory.
    pub states: Vec<ContactState>,
    /// Per boundary node: this step's contact.
    pub out: Vec<NodeContact>,
    /// Per boundary node: the second contact's memory (corner nodes, see
    /// [`Surface::faces`]; saved in checkpoint format 3).
    #[serde(skip)]
    pub corner_states: Vec<ContactState>,
    /// Per boundary node: this step's second contact (corner nodes).
    #[serde(skip)]
    pub corner_out: Vec<NodeContact>,
    /// Per boundary node: which memories are not empty (derived, see
    /// `narrow::Contacts::busy`; set with [`ContactModel::mark_busy`]).
    #[serde(skip)]
    busy: Vec<u8>,
    /// The memory and contacts of the surface before the last topology
    /// change, kept as buffers for the next one (scratch).
    #[serde(skip)]
    spare_states: [Vec<ContactState>; 2],
    #[serde(skip)]
    spare_out: [Vec<NodeContact>; 2],
    #[serde(skip)]
    pub partials: Vec<ContactPartial>,
    /// Per facet: its frame at the current evaluation (scratch).
    #[serde(skip)]
    frames: Vec<FacetFrame>,
    /// The nodes of the facets before the last topology change (scratch,
    /// [`NarrowInputs::resumed`]).
    #[serde(skip)]
    resumed: Vec<[u32; 2]>,
    /// The contacts with a dashpot (`2b + k`) in the assembly's order, and
    /// their dashpots as the node pass applies them (scratch, set by
    /// [`ContactModel::assemble`] and [`ContactModel::dashpots`]).
    #[serde(skip)]
    dashpot_ids: Vec<u32>,
    #[serde(skip)]
    dashpot_links: Vec<narrow::DashpotLink>,
    /// Scratch of the chunked assemblies (contacts and dashpots).
    #[serde(skip)]
    scatter: narrow::Scatter,
    /// Set by a topology change that named the nodes it touched
    /// ([`ContactModel::adopt`]) for the evaluation that follows it: per
    /// boundary node whether its contacts were carried over as they were,
    /// and per facet whether an end of it was touched
    /// ([`narrow::evaluate_after_change`]). Empty otherwise (scratch).
    #[serde(skip)]
    kept: Vec<u8>,
    #[serde(skip)]
    changed: Vec<u8>,
    /// Candidate pairs evaluated so far.
    pub pairs_evaluated: u64,
    /// Largest stiffness over all laws (Pa/m), for the stable step.
    pub max_stiffness: f64,
    /// Largest damping ratio over all laws. Kept in the saved state; the
    /// stable step no longer needs it since the node pass applies the
    /// dashpots on the predicted velocities (checkpoint format 6).
    pub max_damping: f64,
    /// Margin given by the user, if any.
    margin: Option<f64>,
}

impl ContactModel {
    /// Normal stiffness of the crack law (Pa/m): the penalty of cohesive
    /// bonds across cracks.
    pub fn crack_stiffness(&self) -> f64 {
        self.laws[self.crack_law as usize].normal_stiffness
    }

    /// Sizes the scratch buffers (per-chunk partial sums, facet frames)
    /// for `surface`: at a topology change, never in the time loop.
    pub fn size_scratch(&mut self, surface: &Surface) {
        // resized in place: a fresh allocation at every crack insertion
        // cost its page faults (2–9 ms at the paper's scale)
        self.partials.clear();
        self.partials.resize(surface.nodes.len().div_ceil(fdem_contact::CHUNK), ContactPartial::default());
        // not cleared: every evaluation writes every frame before reading
        // any, so only new entries need a value (the clear refilled 24 MB
        // at every insertion at the paper's scale)
        self.frames.resize(surface.facets.len(), FacetFrame::default());
        // at most two contacts a node: filled by every assembly without
        // growing
        let most = 2 * surface.nodes.len();
        self.dashpot_ids.reserve(most.saturating_sub(self.dashpot_ids.len()));
        self.dashpot_links.reserve(most.saturating_sub(self.dashpot_links.len()));
        self.scatter.reserve(surface.nodes.len());
    }

    /// Derives the busy flags from the memories (after they were set other
    /// than by an evaluation: a topology change, a restore).
    pub fn mark_busy(&mut self) {
        self.busy.clear();
        self.busy.resize(self.states.len(), 0);
        narrow::mark_busy(&self.states, &self.corner_states, &mut self.busy);
    }

    /// Follows a relabelling of the surface ([`Surface::relabel`]):
    /// `surface` is the relabelled one, `facet_map` and `b_map` give each
    /// old facet's and boundary node's new index. Memories and this step's
    /// contacts move with their nodes and point at the same facets; the
    /// broad phase is rebuilt at its next update.
    pub fn relabel(&mut self, surface: &Surface, facet_map: &[u32], b_map: &[u32]) {
        use crate::renumber::scatter;
        let facet = |f: u32| if f == NONE { NONE } else { facet_map[f as usize] };
        // a resumed mark indexes the facets before the last topology change;
        // the evaluation after every change clears it, and renumbering
        // comes after one
        debug_assert!(self.states.iter().chain(&self.corner_states).all(|s| s.resumed == NONE));
        // likewise the flags of the evaluation after a change, by the
        // boundary index of before
        debug_assert!(self.kept.is_empty() && self.changed.is_empty());
        for states in [&mut self.states, &mut self.corner_states] {
            states.iter_mut().for_each(|s| s.facet = facet(s.facet));
            scatter(states, b_map);
        }
        for out in [&mut self.out, &mut self.corner_out] {
            for c in out.iter_mut() {
                c.facet = facet(c.facet);
                c.locate(surface);
            }
            scatter(out, b_map);
        }
        self.mark_busy();
        self.size_scratch(surface);
        self.broad.reset();
    }

    /// Checks and builds the contact model.
    pub fn new(spec: &ContactSpec, n_nodes: usize) -> Result<Self, SetupError> {
        if spec.laws.is_empty() {
            return Err(SetupError::Invalid("contact needs at least one interface law".into()));
        }
        let mut laws = Vec::with_capacity(spec.laws.len());
        for (k, l) in spec.laws.iter().enumerate() {
            laws.push(
                InterfaceLaw::new(l.normal_stiffness, l.shear_stiffness, l.friction, l.cohesion, l.damping_ratio)
                    .map_err(|e| SetupError::Invalid(format!("interface law {k}: {e}")))?,
            );
        }
        let mut facet_laws = BTreeMap::new();
        for &([a, b], law) in &spec.facet_laws {
            if a as usize >= n_nodes || b as usize >= n_nodes {
                return Err(SetupError::Invalid(format!("interface facet ({a}, {b}) refers to a missing node")));
            }
            if law as usize >= laws.len() {
                return Err(SetupError::Invalid(format!(
                    "interface facet ({a}, {b}) uses law {law}, but only {} are defined",
                    laws.len()
                )));
            }
            facet_laws.insert((a.min(b), a.max(b)), law);
        }
        if spec.crack_law as usize >= laws.len() {
            return Err(SetupError::Invalid(format!("crack law {} is not defined", spec.crack_law)));
        }
        if let Some(m) = spec.margin {
            if !(m > 0.0 && m.is_finite()) {
                return Err(SetupError::Invalid(format!("contact margin = {m} must be positive")));
            }
        }
        let max_stiffness = laws.iter().map(|l| l.normal_stiffness.max(l.shear_stiffness)).fold(0.0, f64::max);
        let max_damping = laws.iter().map(|l| l.damping_ratio).fold(0.0, f64::max);
        Ok(Self {
            laws,
            facet_laws,
            crack_law: spec.crack_law,
            broad: BroadPhase::new(spec.margin.unwrap_or(1.0)),
            states: Vec::new(),
            out: Vec::new(),
            corner_states: Vec::new(),
            corner_out: Vec::new(),
            busy: Vec::new(),
            spare_states: Default::default(),
            spare_out: Default::default(),
            partials: Vec::new(),
            frames: Vec::new(),
            resumed: Vec::new(),
            dashpot_ids: Vec::new(),
            dashpot_links: Vec::new(),
            scatter: Default::default(),
            kept: Vec::new(),
            changed: Vec::new(),
            pairs_evaluated: 0,
            max_stiffness,
            max_damping,
            margin: spec.margin,
        })
    }

    /// Whether some interface law's dashpot is too weak to damp a rattling
    /// contact (damping ratio below [`RATTLE_DAMPING`]): then the stable
    /// step must also keep contact onsets accurate
    /// ([`contact_bound`](crate::stable_step::contact_bound)).
    pub fn may_rattle(&self) -> bool {
        self.laws.iter().any(|l| l.damping_ratio < RATTLE_DAMPING)
    }

    /// The law of the facet whose nodes have the (sorted) ancestor pair
    /// `pair`.
    pub fn law_of(&self, pair: (u32, u32)) -> u16 {
        self.facet_laws.get(&pair).copied().unwrap_or(0)
    }

    /// Adapts to a new surface (after a topology change): friction memory
    /// follows the nodes and facets that still exist. Each contact of a
    /// node (one, or two at a corner) takes over the old contact of the
    /// same node whose bearing face is the same facet, else the one whose
    /// face points most nearly the same way (and not away from it); a node
    /// created in this change (`origins`: new node → the old node it came
    /// from) takes over its origin's. A contact whose facet has changed, or
    /// that a new node inherits, resumes at the next evaluation with the
    /// penetration it has (see [`ContactState::resumed`]); `x` are the
    /// current positions. `touched` (ascending), when the change names the
    /// nodes it touched (a crack insertion, see
    /// [`Simulation::rebuild_structure`](crate::simulation::Simulation)),
    /// lets the evaluation that follows keep the contacts of the nodes away
    /// from it ([`narrow::evaluate_after_change`]).
    pub fn adopt(
        &mut self,
        old: Option<&Surface>,
        new: &Surface,
        x: &[Vec2],
        origins: &[(u32, u32)],
        touched: Option<&[u32]>,
    ) {
        // The default margin follows the mean facet length, with
        // hysteresis: every crack insertion changes that mean a little, and
        // a margin that grew forced the broad phase to rebuild instead of
        // carrying its lists over (every other insertion check at the
        // paper's scale, 10–12 ms each). The lists, and so the results, do
        // not depend on the margin.
        let margin = self.margin.unwrap_or_else(|| {
            let target = 0.2 * new.facets.iter().map(|f| f.length).sum::<f64>() / new.facets.len().max(1) as f64;
            let current = self.broad.margin;
            if old.is_some() && (0.8 * current..=1.25 * current).contains(&target) {
                current
            } else {
                target
            }
        });
        // The broad phase's carry-over and the memory's are independent
        // (disjoint data) and each mostly serial: side by side they share
        // the workers (about 3 and 6 ms of an insertion at the paper's
        // scale late in the run on 2 threads, one after the other).
        let mut broad = std::mem::replace(&mut self.broad, BroadPhase::new(margin));
        rayon::join(
            || match old {
                Some(old) => broad.carry_over(old, new, x, margin),
                None => {
                    broad.margin = margin;
                    broad.invalidate();
                }
            },
            || self.adopt_memory(old, new, x, origins, touched),
        );
        self.broad = broad;
    }

    /// The memory part of [`ContactModel::adopt`]: the contact memories
    /// carried over to `new`, the contact records emptied, the busy flags
    /// and scratch buffers sized. With `touched` (the nodes the change
    /// touched, ascending), also the flags of the evaluation that follows
    /// ([`ContactModel::kept`]): a node keeps its contacts, records
    /// included, when it was on the old surface, neither it nor an end of
    /// its own facets was touched, and each of its contacts stays on the
    /// same facet in the same slot.
    fn adopt_memory(
        &mut self,
        old: Option<&Surface>,
        new: &Surface,
        x: &[Vec2],
        origins: &[(u32, u32)],
        touched: Option<&[u32]>,
    ) {
        let nb = new.nodes.len();
        // the new memory and records go into the spare buffers (no fresh
        // allocation, whose page faults cost as much as filling them).
        // With an old surface the pass over the nodes below writes every
        // entry, so they are only sized here (filling them first cost
        // 1.4 ms of an insertion on one thread late in the paper-scale run,
        // 17 MB written twice); without one they are filled, in parallel.
        let empty = NodeContact { facet: NONE, ..Default::default() };
        let mut states = [std::mem::take(&mut self.spare_states[0]), std::mem::take(&mut self.spare_states[1])];
        let mut outs = [std::mem::take(&mut self.spare_out[0]), std::mem::take(&mut self.spare_out[1])];
        for (s, o) in states.iter_mut().zip(&mut outs) {
            if old.is_some() {
                s.resize(nb, ContactState::default());
                o.resize(nb, empty);
            } else {
                s.clear();
                s.par_extend(rayon::iter::repeat_n(ContactState::default(), nb));
                o.clear();
                o.par_extend(rayon::iter::repeat_n(empty, nb));
            }
        }
        self.kept.clear();
        self.changed.clear();
        if let Some(old) = old {
            self.resumed.clear();
            self.resumed.par_extend(old.facets.par_iter().map(|f| f.nodes));
            // a facet keeps its key through a rebuild; a contact stays on it
            // if it still joins the same two nodes
            let max_key = new.facets.last().map_or(0, |f| f.key as usize + 1);
            let mut facet_of_key = Vec::new();
            fdem_contact::surface::index_by_key(&new.facets, max_key, &mut facet_of_key);
            // A node split by this change and its copies are one node cut in
            // pieces, and which piece keeps the id (and the facets ending
            // there) depends on how the mesh is numbered
            // (docs/renumbering.md): so all of them resume their contacts,
            // and a facet joins the same two nodes as before when each end
            // is the old one or a copy of it. (With the piece that kept the
            // id continuing its contacts, and the facets that kept it too,
            // a renumbered run went on differently after an insertion that
            // split a node in contact.)
            let mut split: Vec<u32> = origins.iter().map(|&(_, o)| o).collect();
            split.sort_unstable();
            split.dedup();
            let origin_of = |v: u32| origins.binary_search_by_key(&v, |&(n, _)| n).ok().map(|i| origins[i].1);
            let same_ends =
                |now: [u32; 2], then: [u32; 2]| (0..2).all(|i| now[i] == then[i] || origin_of(now[i]) == Some(then[i]));
            // the touched nodes as bits, and the facets with a touched end:
            // a facet none of whose ends was touched is the same facet, with
            // the same neighbours, as before (its two nodes kept their
            // elements)
            // (without `touched` none are flagged, and `changed` stays
            // empty: then no node is untouched, below)
            let hit = crate::topology::NodeBits::of(
                if touched.is_some() { x.len() } else { 0 },
                touched.unwrap_or_default().iter().copied(),
            );
            if touched.is_some() {
                self.changed
                    .par_extend(new.facets.par_iter().map(|f| u8::from(hit.has(f.nodes[0]) || hit.has(f.nodes[1]))));
            }
            let changed = &self.changed;
            let old_states = [&self.states, &self.corner_states];
            let old_out = [&self.out, &self.corner_out];
            // the old node's active contacts: (state, depth, old boundary
            // index, bearing face or NONE); the depth is the memory's, which
            // every evaluation sets to the contact's `−gap` (so the 80-byte
            // contact records of every node need not be read here)
            type Old = Option<(ContactState, f64, usize, u32)>;
            let old_contacts = |node: u32| -> [Old; 2] {
                let ob = old.index_of.get(node as usize).copied().unwrap_or(NONE) as usize;
                if ob >= self.states.len() {
                    return [None; 2];
                }
                let faces = old.faces.get(ob).copied().unwrap_or([NONE; 2]);
                std::array::from_fn(|k| {
                    let s = *old_states[k].get(ob)?;
                    if s.facet == NONE {
                        return None;
                    }
                    Some((s, s.depth.max(0.0), ob, faces[k]))
                })
            };
            // the outward normal at `x` of an old contact's bearing face
            let old_normal = |&(_, _, ob, face): &(ContactState, f64, usize, u32)| match face {
                NONE => old.mean_normal(x, ob),
                f => old.facet_normal(x, f),
            };
            // a contact whose facet is gone resumes along the old facet's
            // direction, read by the next evaluation from the old facets'
            // nodes (kept in `resumed`) at the same positions
            let resumed = |s: ContactState, depth: f64| ContactState {
                facet: NONE,
                resumed: s.facet,
                elastic_gap: s.elastic_gap,
                depth,
                offset: s.offset,
            };
            // whether the node `node` (boundary index `b`) and its own
            // facets are untouched (never without `touched`)
            let untouched = |b: usize, node: u32| {
                !changed.is_empty()
                    && !hit.has(node)
                    && new.node_facets.row(b).iter().all(|&k| changed[k as usize] == 0)
            };
            // every node's memory by itself (parallel: each writes its own
            // entries; 5 ms a change at the paper's scale when serial)
            // (sized in any case; dropped below without `touched`)
            let mut kept = std::mem::take(&mut self.kept);
            kept.resize(nb, 0);
            let [first, second] = &mut states;
            let [out0, out1] = &mut outs;
            let rows =
                (first.par_iter_mut().zip(second.par_iter_mut())).zip(out0.par_iter_mut().zip(out1.par_iter_mut()));
            new.nodes.par_iter().zip(rows).zip(kept.par_iter_mut()).enumerate().with_min_len(crate::CHUNK).for_each(
                |(b, ((&node, (slots, records)), keep))| {
                    // every entry written (the buffers were only sized)
                    (*slots.0, *slots.1) = (ContactState::default(), ContactState::default());
                    (*records.0, *records.1) = (empty, empty);
                    *keep = 0;
                    let mut from = old_contacts(node);
                    let on_old = old.index_of.get(node as usize).is_some_and(|&i| i != NONE);
                    // a node created by this change inherits its origin's contacts
                    let created = from == [None; 2] && !on_old;
                    if created {
                        match origins.binary_search_by_key(&node, |&(n, _)| n) {
                            Ok(i) => from = old_contacts(origins[i].1),
                            Err(_) => return,
                        }
                    }
                    let stays = !created && on_old && untouched(b, node);
                    if from == [None; 2] {
                        *keep = u8::from(stays);
                        return;
                    }
                    let faces = new.faces[b];
                    let single = faces[0] == NONE;
                    let (slot0, slot1) = slots;
                    if stays {
                        // Neither the node nor its facets changed, so its
                        // faces are the same facets, with the same normals
                        // to the bit: each contact goes on in its own slot,
                        // which is what the rule below picks (but for a
                        // node whose facets' normals cancel exactly, which
                        // it would leave without contact), on its facet
                        // where that is still there, without working out
                        // any normal (most of an insertion's contact memory
                        // when it did, 3 ms on one thread late in the
                        // paper-scale run). Kept whole when every contact's
                        // facet is untouched too.
                        let mut whole = true;
                        let mut carried = [None; 2];
                        for (k, slot) in [slot0, slot1].into_iter().enumerate() {
                            let Some((s, depth, ob, _)) = from[k] else { continue };
                            let of = &old.facets[s.facet as usize];
                            let f = facet_of_key.get(of.key as usize).copied().unwrap_or(NONE);
                            if f != NONE && same_ends(new.facets[f as usize].nodes, of.nodes) {
                                *slot = ContactState {
                                    facet: f,
                                    resumed: NONE,
                                    elastic_gap: s.elastic_gap,
                                    depth,
                                    offset: s.offset,
                                };
                                whole &= changed[f as usize] == 0;
                                carried[k] = Some((f, ob));
                            } else {
                                *slot = resumed(s, depth);
                                whole = false;
                            }
                        }
                        if whole {
                            // kept: the step's contacts go on, on the
                            // facets' new indices
                            *keep = 1;
                            let (record0, record1) = records;
                            for (k, record) in [record0, record1].into_iter().enumerate() {
                                if let Some((f, ob)) = carried[k] {
                                    let c = &old_out[k][ob];
                                    debug_assert_eq!(c.facet, from[k].map_or(NONE, |o| o.0.facet));
                                    *record = NodeContact { facet: f, ends: new.facets[f as usize].ends, ..*c };
                                }
                            }
                        }
                        return;
                    }
                    // which old contact each slot takes up: at a corner the
                    // one on the same face, or whose face points most nearly
                    // the same way; on a smooth stretch the first the one
                    // whose face points most nearly the node's way, the
                    // second the other one (on a second body,
                    // `Search::run`), if the first took one
                    let pieces = created || split.binary_search(&node).is_ok();
                    let mut first_taken = None;
                    for (k, slot) in [slot0, slot1].into_iter().enumerate() {
                        let pick = if single && k == 1 {
                            // (not one on the first's facet or next to it: the
                            // two faces of a corner on one body)
                            first_taken.map(|i: usize| 1 - i).filter(|&j| {
                                let facet = |i: usize| from[i].map_or(NONE, |o| o.0.facet);
                                let (f, g) = (facet(1 - j), facet(j));
                                g != NONE && f != g && !old.adjacent(f, g)
                            })
                        } else {
                            let key = if single { NONE } else { new.facets[faces[k] as usize].key };
                            let same_face = |o: &Old| {
                                o.is_some_and(|(_, _, _, face)| face != NONE && old.facets[face as usize].key == key)
                            };
                            (0..2).find(|&i| same_face(&from[i])).or_else(|| {
                                // the old contact whose face points most nearly the same way
                                let n = if single { new.mean_normal(x, b) } else { new.facet_normal(x, faces[k]) };
                                let dot = |i: &usize| {
                                    from[*i].as_ref().map_or(f64::NEG_INFINITY, |o| {
                                        let m = old_normal(o);
                                        m[0] * n[0] + m[1] * n[1]
                                    })
                                };
                                (0..2).filter(|i| dot(i) > 0.0).max_by(|p, q| dot(p).total_cmp(&dot(q)))
                            })
                        };
                        if k == 0 {
                            first_taken = pick;
                        }
                        let Some((s, depth, ..)) = pick.and_then(|i| from[i]) else { continue };
                        let of = &old.facets[s.facet as usize];
                        let f = facet_of_key.get(of.key as usize).copied().unwrap_or(NONE);
                        *slot = if !pieces && f != NONE && same_ends(new.facets[f as usize].nodes, of.nodes) {
                            ContactState {
                                facet: f,
                                resumed: NONE,
                                elastic_gap: s.elastic_gap,
                                depth,
                                offset: s.offset,
                            }
                        } else {
                            resumed(s, depth)
                        };
                    }
                },
            );
            if touched.is_none() {
                kept.clear();
            }
            self.kept = kept;
        }
        let [first, second] = states;
        self.spare_states =
            [std::mem::replace(&mut self.states, first), std::mem::replace(&mut self.corner_states, second)];
        let [out0, out1] = outs;
        self.spare_out = [std::mem::replace(&mut self.out, out0), std::mem::replace(&mut self.corner_out, out1)];
        self.mark_busy();
        self.size_scratch(new);
    }

    /// The narrow phase of one contact evaluation at positions `x`
    /// (reference positions `x_ref`, which tell the two faces of a crack or
    /// joint), velocities `v` (parallel; the broad phase must be up to
    /// date): every boundary node's contacts and their forces, not yet
    /// assembled.
    pub fn search(&mut self, surface: &Surface, x: &[Vec2], x_ref: &[Vec2], v: &[Vec2], mass: &[f64], dt: f64) {
        narrow::facet_frames(surface, x, &mut self.frames);
        debug_assert_eq!(x_ref.len(), x.len());
        let inp = NarrowInputs {
            x,
            x_ref,
            v,
            mass,
            surface,
            frames: &self.frames,
            candidates: &self.broad.candidates,
            laws: &self.laws,
            resumed: &self.resumed,
            dt,
        };
        let c = Contacts {
            states: &mut self.states,
            corner_states: &mut self.corner_states,
            out: &mut self.out,
            corner_out: &mut self.corner_out,
            busy: &mut self.busy,
        };
        if self.kept.is_empty() {
            narrow::evaluate(&inp, c, &mut self.partials);
        } else {
            narrow::evaluate_after_change(&inp, c, &mut self.partials, &self.kept, &self.changed);
            // for the evaluation right after the change only
            self.kept.clear();
            self.changed.clear();
        }
    }

    /// The assembly (in parallel over chunks of boundary nodes, in a fixed
    /// order: [`narrow::Scatter`]) after
    /// [`ContactModel::search`]: the forces into `forces` (per boundary
    /// node), their dashpot parts into `damping`, and how many dashpots act
    /// on each boundary node into `damped` ([`narrow::assemble`]); returns
    /// the summed partials.
    pub fn assemble(&mut self, out: AssemblyOut<'_>) -> ContactPartial {
        self.reassemble(out);
        let mut sum = ContactPartial::default();
        for p in &self.partials {
            sum.pairs += p.pairs;
            sum.contacts += p.contacts;
            sum.friction += p.friction;
            sum.stored += p.stored;
        }
        self.pairs_evaluated += sum.pairs;
        sum
    }

    /// [`ContactModel::assemble`] without counting the pairs: after a
    /// restore or a renumbering, for the dashpots (the forces come out as
    /// saved, up to the order of the sums).
    pub fn reassemble(&mut self, out: AssemblyOut<'_>) {
        let AssemblyOut { forces, damping, damped } = out;
        let contacts = [&self.out[..], &self.corner_out[..]];
        narrow::assemble(contacts, &self.busy, forces, damping, damped, &mut self.dashpot_ids, &mut self.scatter);
    }

    /// Whether the last assembly found a contact with a dashpot.
    pub fn has_dashpots(&self) -> bool {
        !self.dashpot_ids.is_empty()
    }

    /// The dashpot forces of the node pass ([`narrow::Dashpot`]): each
    /// contact's from the predicted velocities `v` and the masses `mass`
    /// (by node; `nodes` maps boundary index to node, `damped` counts the
    /// dashpots per boundary node) with the velocity step `h` (s), in
    /// parallel, then added up per boundary node into `out` (N), in the
    /// assembly's order.
    pub fn dashpots(&mut self, nodes: &[u32], damped: &[u16], mass: &[f64], v: &[Vec2], h: f64, out: &mut [Vec2]) {
        let contacts = [&self.out[..], &self.corner_out[..]];
        let links = &mut self.dashpot_links;
        links.resize(self.dashpot_ids.len(), Default::default());
        narrow::dashpot_forces(contacts, &self.dashpot_ids, nodes, damped, mass, v, h, links);
        narrow::assemble_dashpots(links, out, &mut self.scatter);
    }
}
