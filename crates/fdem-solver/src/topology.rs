//! What is derived from the connectivity and rebuilt whenever it changes
//! (crack insertion, excavation): node→element lists, the free surfaces,
//! and the pressure facets resolved on them.

use std::collections::BTreeMap;

use fdem_contact::Surface;
use fdem_element::Vec2;
use rayon::prelude::*;

use crate::loads::PressureLoad;
use crate::passes::PressureFacet;
use crate::NONE;

/// The free surfaces of the active elements, with the law of each facet
/// from `law_of`. A facet `(a, b)` of element `e` is free when no other
/// active element holds both `a` and `b` (looked up in `node_elems`, the
/// node→element lists of the active elements): linear in the element count
/// and parallel, as crack insertion rebuilds it often. Facets come in
/// element order, each element's edges `k = 0, 1, 2` (vertex `k` to
/// `k + 1`), body on the left, keyed `3 e + k` (stable: elements keep their
/// ids and vertex order through topology changes).
///
/// With `dirty` (ascending element ids) and an `old` surface of the mesh
/// before a change that touched only the elements around the nodes of
/// `dirty`'s elements, only the elements in `dirty` are tested again; the
/// others' free edges are read off the old surface's keys. An edge's state
/// depends only on which active elements hold its two nodes, so an element
/// none of whose nodes gained or lost an element keeps its free edges
/// ([`dirty_elements`] lists the rest). The test of every edge took about
/// 3 ms of each insertion check at the paper's scale on 2 threads.
pub(crate) fn build_surface(
    conn: &[[u32; 3]],
    active: &[bool],
    node_elems: &fdem_mesh::Csr,
    x_ref: &[Vec2],
    old: Option<&Surface>,
    dirty: Option<&[u32]>,
    law_of: impl Fn(u32, u32) -> u16 + Sync,
) -> Surface {
    let free_edges = |e: usize| -> u8 {
        if !active[e] {
            return 0;
        }
        let t = conn[e];
        let mut bits = 0u8;
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let shared = node_elems.row(a as usize).iter().any(|&item| {
                let f = (item / 3) as usize;
                f != e && active[f] && conn[f].contains(&b)
            });
            if !shared {
                bits |= 1 << k;
            }
        }
        bits
    };
    let free: Vec<u8> = match (old, dirty) {
        (Some(old), Some(dirty)) => {
            // the old surface's free edges, in parallel over fixed chunks
            // of elements: the old facets ascend by key (`3 e + k`), so
            // each chunk's are one run, found by a binary search (one
            // serial pass over them was 0.12% of the 10⁴ fragmenting
            // impact at one thread, at every insertion check)
            let mut free = vec![0u8; conn.len()];
            free.par_chunks_mut(crate::CHUNK).enumerate().for_each(|(c, part)| {
                let first = c * crate::CHUNK;
                let (lo, hi) = (3 * first as u64, 3 * (first + part.len()) as u64);
                let start = old.facets.partition_point(|f| u64::from(f.key) < lo);
                for f in old.facets[start..].iter().take_while(|f| u64::from(f.key) < hi) {
                    part[(f.key / 3) as usize - first] |= 1 << (f.key % 3);
                }
            });
            for &e in dirty {
                free[e as usize] = free_edges(e as usize);
            }
            free
        }
        _ => (0..conn.len()).into_par_iter().with_min_len(crate::CHUNK).map(free_edges).collect(),
    };
    // a facet that was on the old surface (same key, same nodes) keeps its
    // law; only new ones are looked up (a map lookup per facet took 8–10 ms
    // of every insertion check at the paper's scale). Both lists ascend by
    // key, so one walk per chunk of elements finds them; the chunks in
    // parallel (serial, this walk was 0.4% of a fragmenting impact's run),
    // joined in element order.
    let old_facets = old.map_or(&[][..], |s| &s.facets[..]);
    type Facets = (Vec<([u32; 2], u16)>, Vec<Vec2>, Vec<u32>);
    let chunks: Vec<Facets> = free
        .par_chunks(crate::CHUNK)
        .enumerate()
        .map(|(c, bits)| {
            let (mut list, mut apex, mut keys) = (Vec::new(), Vec::new(), Vec::new());
            let first = (3 * c * crate::CHUNK) as u32;
            let mut j = old_facets.partition_point(|f| f.key < first);
            for (i, &bits) in bits.iter().enumerate() {
                let e = c * crate::CHUNK + i;
                for k in 0..3 {
                    if bits & (1 << k) != 0 {
                        let t = conn[e];
                        let nodes = [t[k], t[(k + 1) % 3]];
                        let key = (3 * e + k) as u32;
                        while j < old_facets.len() && old_facets[j].key < key {
                            j += 1;
                        }
                        let law = match old_facets.get(j) {
                            Some(f) if f.key == key && f.nodes == nodes => f.law,
                            _ => law_of(nodes[0], nodes[1]),
                        };
                        list.push((nodes, law));
                        apex.push(x_ref[t[(k + 2) % 3] as usize]);
                        keys.push(key);
                    }
                }
            }
            (list, apex, keys)
        })
        .collect();
    let total = chunks.iter().map(|c| c.0.len()).sum();
    let (mut list, mut apex, mut keys) =
        (Vec::with_capacity(total), Vec::with_capacity(total), Vec::with_capacity(total));
    for (l, a, k) in chunks {
        list.extend_from_slice(&l);
        apex.extend_from_slice(&a);
        keys.extend_from_slice(&k);
    }
    let mut surface = Surface::with_keys(x_ref.len(), &list, x_ref, &apex, &keys);
    set_apexes(&mut surface, conn);
    surface
}

/// Sets the surface's facets' apexes ([`fdem_contact::SurfaceFacet::apex`])
/// from their keys, `3 e + k` for edge `k` of element `e`, whose third node
/// is `conn[e][(k + 2) % 3]`: after building or restoring a surface.
pub(crate) fn set_apexes(surface: &mut Surface, conn: &[[u32; 3]]) {
    surface.set_apexes(|key| conn[(key / 3) as usize][((key % 3 + 2) % 3) as usize]);
}

/// A set of nodes as one bit per node: membership in O(1) where a node
/// list is tested once per bond, facet or boundary node (binary searches
/// or scans there were serial hot spots of an insertion check).
pub(crate) struct NodeBits(Vec<u64>);

impl NodeBits {
    /// The set of `nodes` (each below `n`) on a mesh of `n` nodes.
    pub(crate) fn of(n: usize, nodes: impl IntoIterator<Item = u32>) -> Self {
        let mut bits = vec![0u64; n.div_ceil(64)];
        for v in nodes {
            bits[v as usize / 64] |= 1 << (v % 64);
        }
        Self(bits)
    }

    /// Whether node `v` is in the set (a node beyond the mesh is not).
    #[inline]
    pub(crate) fn has(&self, v: u32) -> bool {
        self.0.get(v as usize / 64).is_some_and(|w| (w >> (v % 64)) & 1 == 1)
    }
}

/// The sorted pair of two nodes' ancestors: the key under which a facet's
/// law and loads are remembered through node splits.
#[inline]
pub(crate) fn ancestor_pair(ancestor: &[u32], a: u32, b: u32) -> (u32, u32) {
    let (x, y) = (ancestor[a as usize], ancestor[b as usize]);
    (x.min(y), x.max(y))
}

/// Resolves pressure loads (given by ancestor node pairs) on the surface:
/// each must be a boundary facet (either orientation); it gets the
/// surface's orientation (body on the left). Both faces of a facet that a
/// crack has split keep the load if both are on the boundary. With
/// `strict`, a load off the boundary is an error (at set-up); otherwise it
/// is dropped (its facet was excavated).
pub(crate) fn resolve_pressures(
    surface: &Surface,
    loads: &[PressureLoad],
    ancestor: &[u32],
    strict: bool,
) -> Result<Vec<PressureFacet>, String> {
    // only the loaded pairs are looked for: a few hundred loads against
    // the whole surface (every joint and crack face), at every insertion
    let key = |[a, b]: [u32; 2]| (a.min(b), a.max(b));
    let mut by_pair: BTreeMap<(u32, u32), Vec<[u32; 2]>> = loads.iter().map(|p| (key(p.nodes), Vec::new())).collect();
    // the loaded nodes as bits: most facets have an end that no load
    // names, and are passed over without a look in the map (1 ms of every
    // insertion at the paper's scale)
    let top = loads.iter().flat_map(|p| p.nodes).max().map_or(0, |v| v as usize + 1);
    let loaded = NodeBits::of(top, loads.iter().flat_map(|p| p.nodes));
    for f in &surface.facets {
        let (a, b) = ancestor_pair(ancestor, f.nodes[0], f.nodes[1]);
        if !(loaded.has(a) && loaded.has(b)) {
            continue;
        }
        if let Some(list) = by_pair.get_mut(&(a, b)) {
            list.push(f.nodes);
        }
    }
    let mut out = Vec::with_capacity(loads.len());
    for p in loads {
        let [a, b] = p.nodes;
        match by_pair.get(&key(p.nodes)) {
            Some(list) if !list.is_empty() => {
                for &nodes in list {
                    let bnodes = nodes.map(|n| surface.index_of[n as usize]);
                    debug_assert!(bnodes.iter().all(|&b| b != NONE));
                    out.push(PressureFacet { nodes, bnodes, pressure: p.pressure, amplitude: p.amplitude });
                }
            }
            _ if strict => {
                return Err(format!("pressure facet ({a}, {b}) is not an edge on the boundary of the mesh"));
            }
            _ => {}
        }
    }
    Ok(out)
}

/// Node→element incidence of the active elements (items `3e + k`).
pub(crate) fn active_node_elements(n_nodes: usize, conn: &[[u32; 3]], active: &[bool]) -> fdem_mesh::Csr {
    fdem_mesh::Csr::from_pairs(
        n_nodes,
        conn.iter()
            .enumerate()
            .filter(|(e, _)| active[*e])
            .flat_map(|(e, t)| (0..3).map(move |k| (t[k] as usize, (e * 3 + k) as u32))),
    )
}

/// The elements whose free edges a topology change may have changed: every
/// active element around a node in `nodes` (ascending, deduplicated), with
/// `nodes` every node of the changed elements' old and new connectivity
/// and of the added elements ([`build_surface`]).
pub(crate) fn dirty_elements(node_elems: &fdem_mesh::Csr, nodes: &[u32]) -> Vec<u32> {
    let mut dirty: Vec<u32> =
        nodes.iter().flat_map(|&v| node_elems.row(v as usize).iter().map(|&item| item / 3)).collect();
    dirty.sort_unstable();
    dirty.dedup();
    dirty
}

/// Node `v`'s lumped mass (kg per unit thickness): the shares `share(e)`
/// of its elements added in the order of its node→element list
/// (ascending element), the one order every mass is summed in, so that a
/// mass worked out again for a few nodes has the bits of a rebuild's.
#[inline]
pub(crate) fn node_mass(node_elems: &fdem_mesh::Csr, v: usize, share: impl Fn(usize) -> f64) -> f64 {
    node_elems.row(v).iter().fold(0.0, |m, &item| m + share((item / 3) as usize))
}

impl crate::simulation::Simulation {
    /// The lumped mass element `e` gives each of its nodes (kg per unit
    /// thickness): its density times its mass-scaling factor, over its
    /// reference area, a third each.
    pub(crate) fn nodal_mass_of(&self, e: usize) -> f64 {
        let t = self.elems.conn[e];
        let x = [self.nodes.x0[t[0] as usize], self.nodes.x0[t[1] as usize], self.nodes.x0[t[2] as usize]];
        fdem_element::lumped_mass(
            self.materials[self.elems.material[e] as usize].density * self.elems.mass_scale[e],
            fdem_element::signed_area(&x),
        )
    }

    /// The node→element lists after a topology change that altered the
    /// `elements` listed (changed or added, ascending) and with them the
    /// `nodes` listed (ascending, new nodes included), from the lists
    /// before it (`self.node_elems`): only the touched nodes' rows are
    /// worked out again (the items of untouched elements they held, and
    /// those of the listed elements that hold them, ascending), the rest
    /// copied. The same lists as [`active_node_elements`] from scratch (a
    /// debug build checks it), without its pass over every element's three
    /// corners at each insertion check.
    fn node_elements_after(&self, nodes: &[u32], elements: &[u32]) -> fdem_mesh::Csr {
        let (conn, active) = (&self.elems.conn, &self.elems.active);
        let mut held: Vec<(u32, u32)> = elements
            .iter()
            .filter(|&&e| active[e as usize])
            .flat_map(|&e| (0..3u32).map(move |k| (conn[e as usize][k as usize], 3 * e + k)))
            .collect();
        held.sort_unstable();
        let old = &self.node_elems;
        let mut next = 0;
        let lists = old.with_rows_replaced(self.nodes.x.len(), nodes, |v, out| {
            let start = out.len();
            if (v as usize) < old.rows() {
                out.extend(old.row(v as usize).iter().filter(|&&item| elements.binary_search(&(item / 3)).is_err()));
            }
            while next < held.len() && held[next].0 == v {
                out.push(held[next].1);
                next += 1;
            }
            out[start..].sort_unstable();
        });
        debug_assert_eq!(next, held.len(), "a changed element holds a node not listed as touched");
        lists
    }

    /// Rebuilds everything derived from the connectivity after a topology
    /// change except forces and the stable step: node→element lists, lumped
    /// masses, the free surfaces (facet laws by ancestor pairs), pressure
    /// facets, contact buffers and friction memory, per-chunk buffers.
    /// `origins` lists the nodes this change created, ascending, each with
    /// the old node it came from: their contacts carry on. `touched`, when
    /// given, lists (each ascending, deduplicated) every node whose
    /// elements the change altered (the nodes of the changed elements' old
    /// and new connectivity and of the added elements, new nodes included)
    /// and those elements (changed and added). Only these nodes' element
    /// lists ([`Self::node_elements_after`]) and the free edges of the
    /// elements around them ([`build_surface`]) are worked out again.
    /// `None` (excavation) builds the lists from scratch and tests every
    /// edge.
    pub(crate) fn rebuild_structure(&mut self, origins: &[(u32, u32)], touched: Option<(&[u32], &[u32])>) {
        let n = self.nodes.x.len();
        let m = self.elems.conn.len();
        self.node_elems = match touched {
            Some((nodes, elements)) => self.node_elements_after(nodes, elements),
            None => active_node_elements(n, &self.elems.conn, &self.elems.active),
        };
        #[cfg(debug_assertions)]
        {
            let fresh = active_node_elements(n, &self.elems.conn, &self.elems.active);
            assert!(self.node_elems == fresh, "node→element lists differ from a build from scratch");
        }
        let touched = touched.map(|(nodes, _)| nodes);
        // the masses from scratch, per node in ascending element order (the
        // lists' order), the sums the serial element loop of setup makes:
        // after a renumbering the stored sums are in the old order, and a
        // node's mass must not depend on when the mesh was last renumbered
        // (the old ones kept to find the contact frequencies that stay)
        std::mem::swap(&mut self.nodes.mass, &mut self.frequencies.omega_carry.old_mass);
        let mut mass = std::mem::take(&mut self.nodes.mass);
        mass.clear();
        mass.resize(n, 0.0);
        let this = &*self;
        // each element's share once (a topology change may allocate)
        let mut share = vec![0.0; m];
        share.par_iter_mut().enumerate().with_min_len(crate::CHUNK).for_each(|(e, s)| {
            if this.elems.active[e] {
                *s = this.nodal_mass_of(e);
            }
        });
        mass.par_iter_mut().enumerate().with_min_len(crate::CHUNK).for_each(|(v, mv)| {
            *mv = node_mass(&this.node_elems, v, |e| share[e]);
        });
        self.nodes.mass = mass;
        let dirty = touched.map(|nodes| dirty_elements(&self.node_elems, nodes));
        let ancestor = &self.ancestor;
        let contact = &self.contact;
        let old = Some(&self.surface);
        let surface = build_surface(
            &self.elems.conn,
            &self.elems.active,
            &self.node_elems,
            &self.nodes.x0,
            old,
            dirty.as_deref(),
            |a, b| contact.as_ref().map_or(0, |c| c.law_of(ancestor_pair(ancestor, a, b))),
        );
        self.loads.pressure = if self.loads.pressure_loads.is_empty() {
            Vec::new()
        } else {
            resolve_pressures(&surface, &self.loads.pressure_loads, &self.ancestor, false).unwrap_or_default()
        };
        self.carry_contact_omega(&surface, touched);
        let nb = surface.nodes.len();
        self.loads.pressure_force.clear();
        self.loads.pressure_force.resize(nb, [0.0; 2]);
        if let Some(c) = &mut self.contact {
            c.adopt(Some(&self.surface), &surface, &self.nodes.x, origins, touched);
            self.node_forces.contact_force.clear();
            self.node_forces.contact_force.resize(nb, [0.0; 2]);
            self.node_forces.contact_damping_force.clear();
            self.node_forces.contact_damping_force.resize(nb, [0.0; 2]);
            self.node_forces.contact_damped.clear();
            self.node_forces.contact_damped.resize(nb, 0);
        }
        self.surface = surface;
        if let Some(fr) = &mut self.fracture {
            // by boundary node: the numbering changed
            fr.bond_gather.invalidate();
        }
        self.ledger.size_partials(n, m);
        self.frequencies.omega.resize(m, 0.0);
        self.elems.force.resize(3 * m, [0.0; 2]);
    }

    /// Carries the boundary nodes' contact frequencies
    /// ([`Self::contact_omega`], by boundary index of the current surface)
    /// over to `new`, the surface after a topology change whose `touched`
    /// nodes are those [`Self::rebuild_structure`] lists, and lists in
    /// [`crate::simulation::OmegaCarry::stale`] the nodes whose frequency
    /// must be worked out again: the touched ones, those new to the
    /// boundary, and those whose mass changed in any bit (the masses are
    /// summed again in the current element order). Any other node's
    /// frequency is exactly what it was: its elements (and so their
    /// frequencies), its mass and its facets are the same. The stable step
    /// of an insertion took 3.4 ms at the paper's scale on 2 threads with
    /// every boundary node worked out again, 2.7 ms with the carry-over
    /// (docs/caving.md, "The check interval is a delay in time").
    /// Without `touched` (excavation), or when the frequencies are not for
    /// the current surface (after a restore or a renumbering), nothing is
    /// carried and the next evaluation works out every node.
    fn carry_contact_omega(&mut self, new: &Surface, touched: Option<&[u32]>) {
        let carry = &mut self.frequencies.omega_carry;
        carry.stale.clear();
        let old = &self.surface;
        let Some(touched) = touched.filter(|_| self.frequencies.contact_omega.len() == old.nodes.len()) else {
            self.frequencies.contact_omega.clear();
            return;
        };
        let (mass, old_mass) = (&self.nodes.mass, &carry.old_mass);
        // (a binary search in `touched` per boundary node was 0.4% of a
        // fragmenting impact's run, serial)
        let touched = NodeBits::of(mass.len(), touched.iter().copied());
        carry.spare.clear();
        for &v in &new.nodes {
            let i = v as usize;
            let ob = old.index_of.get(i).copied().unwrap_or(NONE);
            let same =
                ob != NONE && old_mass.get(i).is_some_and(|m| m.to_bits() == mass[i].to_bits()) && !touched.has(v);
            if same {
                carry.spare.push(self.frequencies.contact_omega[ob as usize]);
            } else {
                carry.stale.push(v);
                carry.spare.push(None);
            }
        }
        std::mem::swap(&mut self.frequencies.contact_omega, &mut carry.spare);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An `n × n` grid of unit cells, two triangles each, counter-clockwise.
    fn grid(n: usize) -> (Vec<Vec2>, Vec<[u32; 3]>) {
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let x = (0..=n).flat_map(|j| (0..=n).map(move |i| [i as f64, j as f64])).collect();
        let mut conn = Vec::new();
        for j in 0..n {
            for i in 0..n {
                conn.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                conn.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (x, conn)
    }

    /// Cuts the mesh at node after node, the way crack insertion does
    /// (the elements on one side of a line through the node get a copy of
    /// it), and after every cut compares the surface rebuilt with `dirty`
    /// (only the elements around the touched nodes tested again) with one
    /// built from scratch: the same facets, nodes and derived data.
    #[test]
    fn a_surface_rebuilt_around_the_touched_nodes_is_the_surface_built_from_scratch() {
        // 1 152 elements: more than one chunk of elements, so that the old
        // surface's free edges are marked by several chunks
        let (mut x, mut conn) = grid(24);
        assert!(conn.len() > crate::CHUNK);
        let mut active = vec![true; conn.len()];
        active[7] = false; // a hole, so that some stars are open
        let law = |_: u32, _: u32| 0u16;
        let incidence = |x: &[Vec2], conn: &[[u32; 3]], active: &[bool]| active_node_elements(x.len(), conn, active);
        let mut surface = build_surface(&conn, &active, &incidence(&x, &conn, &active), &x, None, None, law);
        let mut cuts = 0;
        for (step, p) in (8u32..41).step_by(3).chain((300..620).step_by(29)).enumerate() {
            let angle = 0.7 * step as f64;
            let (c, s) = (angle.cos(), angle.sin());
            let at = x[p as usize];
            let side = |t: &[u32; 3]| {
                let m = t.iter().fold([0.0; 2], |m, &v| [m[0] + x[v as usize][0] / 3.0, m[1] + x[v as usize][1] / 3.0]);
                (m[0] - at[0]) * s - (m[1] - at[1]) * c > 0.0
            };
            let q = x.len() as u32;
            let moved: Vec<usize> =
                (0..conn.len()).filter(|&e| active[e] && conn[e].contains(&p) && side(&conn[e])).collect();
            if moved.is_empty() {
                continue;
            }
            x.push(at);
            let mut touched = vec![q];
            for &e in &moved {
                touched.extend(conn[e]);
                conn[e] = conn[e].map(|v| if v == p { q } else { v });
                touched.extend(conn[e]);
            }
            touched.sort_unstable();
            touched.dedup();
            let node_elems = incidence(&x, &conn, &active);
            let dirty = dirty_elements(&node_elems, &touched);
            let incremental = build_surface(&conn, &active, &node_elems, &x, Some(&surface), Some(&dirty), law);
            let full = build_surface(&conn, &active, &node_elems, &x, None, None, law);
            assert_eq!(incremental, full, "after cutting node {p}");
            surface = incremental;
            cuts += 1;
        }
        assert!(cuts >= 16, "only {cuts} cuts made");
        // the cuts opened the mesh: far more free facets than the grid's
        // outline (96) and the hole (3)
        assert!(surface.facets.len() > 130, "{} facets", surface.facets.len());
    }
}
