//! Cohesive bonds across young cracks, seen from the solver (DESIGN §4.4
//! as amended in docs/fracture.md; the law itself is
//! `fdem_contact::cohesive`): what a new crack's bonds owe
//! ([`Simulation::remaining_softening`]), along which normal and over
//! which length they act ([`Simulation::shared_crack`]), the force they
//! take over at insertion ([`Simulation::preload_bonds`]), and their forces
//! and energies in each step ([`Simulation::bond_forces`]). Split from
//! `fracture.rs` (the check and the topology edits), which calls it.

use fdem_contact::{Bond, BondResponse};
use fdem_element::Vec2;
use fdem_material::Softening;
use rayon::prelude::*;

use crate::fracture::FractureModel;
use crate::simulation::Simulation;

/// Which bond ends act on each boundary node, kept per chunk of
/// [`CHUNK`](crate::CHUNK) boundary nodes, so that the bonds' forces are
/// added to the contact forces in parallel over those chunks, in an order
/// that does not depend on the thread count
/// ([`Simulation::bond_forces`], [`Simulation::add_bond_forces`]).
///
/// Each chunk lists its nodes' bond ends in bond order, so every boundary
/// node gets its bonds' forces in bond order, after the contact forces:
/// the order of the serial loop over the bonds this replaced, so the sums
/// are the same to the bit. (The contact assembly's
/// [`Scatter`](fdem_contact::narrow::Scatter) fits contacts, which are
/// stored by boundary node and so already belong to a chunk; bonds are
/// stored in insertion order and would need the same grouping by chunk,
/// and its order, a chunk's own contributions first, then the other
/// chunks' in chunk order, would have changed the bits.) The lists
/// depend on the bonds' nodes and on the surface's numbering of boundary
/// nodes: they are built again at the first sum after either changed
/// ([`Self::invalidate`]; insertions, excavation, renumbering, restore),
/// and bonds that break are struck out in place
/// ([`Self::drop_broken`]). The lists keep their capacity, so the step
/// allocates only when the bonds grow.
#[derive(Debug, Default)]
pub(crate) struct BondGather {
    /// Per chunk of boundary nodes: `[j, 2k + s]` for each end of a bond on
    /// one of its nodes, in bond order: node `j` of the chunk is end `s` of
    /// bond `k` (`s` = 0: node `a`, which feels `−f`; 1: node `b`, `+f`).
    /// Only bonds with both nodes on the surface are listed.
    chunks: Vec<Vec<[u32; 2]>>,
    /// The number of bonds the lists are for.
    bonds: usize,
    /// The lists are for the current bonds and surface; cleared by
    /// [`Self::invalidate`].
    valid: bool,
    /// Scratch of [`Self::drop_broken`]: each bond's index after the
    /// broken ones are removed, or [`NONE`](crate::NONE).
    remap: Vec<u32>,
}

impl BondGather {
    /// Marks the lists stale: to be called whenever the bonds' nodes, the
    /// bond list (other than through [`Self::drop_broken`]) or the surface's
    /// boundary-node numbering change. The next sum builds them again.
    pub(crate) fn invalidate(&mut self) {
        self.valid = false;
    }

    /// Builds the lists for `bonds` on a surface with `index_of` (mesh node
    /// → boundary node) and `boundary_nodes` boundary nodes, unless they
    /// are already for them.
    fn ensure(&mut self, bonds: &[Bond], index_of: &[u32], boundary_nodes: usize) {
        let chunks = boundary_nodes.div_ceil(crate::CHUNK);
        if self.valid && self.bonds == bonds.len() && self.chunks.len() == chunks {
            #[cfg(debug_assertions)]
            {
                let mut fresh = BondGather::default();
                fresh.build(bonds, index_of, chunks);
                assert!(fresh.chunks == self.chunks, "the bond gather is stale: a change did not invalidate it");
            }
            return;
        }
        self.build(bonds, index_of, chunks);
    }

    /// Builds the lists afresh for `chunks` chunks of boundary nodes, in
    /// parallel: each fixed part of [`CHUNK`](crate::CHUNK) bonds groups
    /// its ends by chunk of boundary nodes (a counting sort, in bond order
    /// within each group), then each chunk's list joins its groups from
    /// the parts in part order. The lists are those of one pass over the
    /// bonds in bond order (built serially, this pass was 0.27% of the 10⁴
    /// fragmenting impact at one thread, at every insertion check).
    /// Allocates the parts' groups: it runs after topology changes only.
    fn build(&mut self, bonds: &[Bond], index_of: &[u32], chunks: usize) {
        use crate::CHUNK;
        // per part: where each chunk's group starts (`chunks + 1` offsets)
        // and the groups one after the other
        let parts: Vec<(Vec<u32>, Vec<[u32; 2]>)> = bonds
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(q, part)| {
                let ends = |bond: &Bond| {
                    let [ia, ib] = bond.nodes.map(|v| index_of[v as usize]);
                    (ia != crate::NONE && ib != crate::NONE).then_some([ia, ib])
                };
                let mut start = vec![0u32; chunks + 1];
                for i in part.iter().filter_map(ends).flatten() {
                    start[i as usize / CHUNK + 1] += 1;
                }
                for c in 0..chunks {
                    start[c + 1] += start[c];
                }
                let mut at = start.clone();
                let mut grouped = vec![[0u32; 2]; start[chunks] as usize];
                for (i, bond) in part.iter().enumerate() {
                    let Some(nodes) = ends(bond) else { continue };
                    let k = q * CHUNK + i;
                    for (s, b) in nodes.into_iter().enumerate() {
                        let c = b as usize / CHUNK;
                        grouped[at[c] as usize] = [(b as usize % CHUNK) as u32, 2 * k as u32 + s as u32];
                        at[c] += 1;
                    }
                }
                (start, grouped)
            })
            .collect();
        self.chunks.resize_with(chunks, Vec::new);
        self.chunks.par_iter_mut().enumerate().for_each(|(c, list)| {
            list.clear();
            for (start, grouped) in &parts {
                list.extend_from_slice(&grouped[start[c] as usize..start[c + 1] as usize]);
            }
        });
        // room for [`Self::drop_broken`]'s numbering: breaks allocate nothing
        self.remap.clear();
        self.remap.reserve(bonds.len());
        self.bonds = bonds.len();
        self.valid = true;
    }

    /// Adds each listed bond's force `force_of(k)` (on its node `b`; `a`
    /// gets its negative) to `force` (per boundary node), in parallel over
    /// the chunks, each node's bonds in bond order.
    fn add(&self, force: &mut [Vec2], force_of: impl Fn(usize) -> Vec2 + Sync) {
        assert_eq!(force.len().div_ceil(crate::CHUNK), self.chunks.len(), "bond lists for another surface");
        force.par_chunks_mut(crate::CHUNK).zip(self.chunks.par_iter()).for_each(|(fc, list)| {
            for &[j, code] in list {
                let f = force_of((code / 2) as usize);
                let t = &mut fc[j as usize];
                if code % 2 == 0 {
                    t[0] -= f[0];
                    t[1] -= f[1];
                } else {
                    t[0] += f[0];
                    t[1] += f[1];
                }
            }
        });
    }

    /// Strikes the bonds that broke (`responses[k].broken`) out of the
    /// lists and numbers the others as the bond list will after the same
    /// removal (`Vec::retain`), in parallel over the chunks: the lists stay
    /// in bond order.
    fn drop_broken(&mut self, responses: &[BondResponse]) {
        let mut kept = 0u32;
        self.remap.clear();
        self.remap.extend(responses.iter().map(|r| {
            if r.broken {
                crate::NONE
            } else {
                kept += 1;
                kept - 1
            }
        }));
        let remap = &self.remap;
        self.chunks.par_iter_mut().for_each(|list| {
            list.retain_mut(|e| {
                let k = remap[(e[1] / 2) as usize];
                if k == crate::NONE {
                    return false;
                }
                e[1] = 2 * k + e[1] % 2;
                true
            })
        });
        self.bonds = kept as usize;
    }
}

/// The law of the bonds across a crack inserted at one node
/// ([`Simulation::remaining_softening`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BondSeed {
    /// Tensile strength `t₀` (Pa).
    pub(crate) strength: f64,
    /// `2 G_I / t₀` (m), with `G_I` the mode-I energy left: the opening at
    /// which the tensile traction reaches zero on a straight envelope.
    pub(crate) final_opening: f64,
    /// Shear strength at zero normal stress (Pa).
    pub(crate) cohesion: f64,
    /// `tan φ` (−).
    pub(crate) friction: f64,
    /// Mode-II fracture energy (J/m²).
    pub(crate) shear_energy: f64,
    /// The kink of the rest of a bilinear curve; `None`: straight.
    pub(crate) kink: Option<fdem_contact::Kink>,
}

impl Simulation {
    /// Gives the new bonds of each split node (`which`: their indices in
    /// the bond list, and the node's copies) the openings at which, at the
    /// positions of the insertion, they carry the force the elements
    /// carried through the node: time continuity of the traction across a
    /// crack inserted early (Papoulia, Sam & Vavasis 2003). Without it a
    /// bond starts slack, every insertion drops a node's share of
    /// `f_t (1 − F̄)` at once, and the stress wave that follows swung the
    /// reaction of a notched beam by ±20% of its load (docs/fracture.md).
    ///
    /// Each copy `c` feels `g_c`: its elements' forces and those of the
    /// bonds it already has. The new bonds' forces `F_j` (on `v_j`, minus
    /// that on `u_j`) are the least-norm ones that cancel them: with `B`
    /// the bonds' incidence matrix, `F = B φ` where `Bᵀ B φ = −(g − ḡ)`,
    /// `ḡ` the mean over the copies a bond chain joins (so the bonds' forces
    /// are equal and opposite and momentum is kept; for a node cut in two,
    /// `F = (g_u − g_v)/2`). A bond that would push its copies together
    /// gets none (contact carries that), and none gets more than its
    /// strength: its offset stays within the elastic range, so no damage
    /// starts at insertion. The elastic energy the bonds hold then is
    /// booked with the rest of the insertion's change of held energy
    /// (`resurfacing`).
    pub(crate) fn preload_bonds(&mut self, which: &[(std::ops::Range<usize>, Vec<u32>)]) {
        let Some(fr) = &mut self.fracture else { return };
        let (x, conn, force, node_elems) = (&self.nodes.x, &self.elems.conn, &self.elems.force, &self.node_elems);
        // the elements' force on a node, and the centroid of its elements
        let pull = |p: u32| {
            let (mut g, mut c, mut n) = ([0.0; 2], [0.0; 2], 0.0_f64);
            for &item in node_elems.row(p as usize) {
                let fe = force[item as usize];
                g = [g[0] - fe[0], g[1] - fe[1]];
                for &q in &conn[(item / 3) as usize] {
                    c = [c[0] + x[q as usize][0], c[1] + x[q as usize][1]];
                    n += 1.0;
                }
            }
            (g, [c[0] / n.max(1.0), c[1] / n.max(1.0)])
        };
        if which.is_empty() {
            return;
        }
        // each copy of a split node: the elements' pull on it, then, in
        // one pass over the bonds in their order, that of the bonds it
        // already has (copy → pull, centroid of its elements)
        let mut others: Vec<(u32, Vec2, Vec2)> =
            which.iter().flat_map(|(_, c)| c.iter().map(|&v| (v, pull(v)))).map(|(v, (g, c))| (v, g, c)).collect();
        others.sort_unstable_by_key(|e| e.0);
        let new_bond = |k: usize| which.iter().any(|(r, _)| r.contains(&k));
        // the copies as bits: most bonds touch none, and are passed over
        // without a search (two binary searches per bond were 0.7% of a
        // fragmenting impact's run, serial); the few that do are found in
        // parallel, in bond order (a serial scan of every bond was 0.14%)
        let copies = crate::topology::NodeBits::of(x.len(), others.iter().map(|e| e.0));
        let touching: Vec<usize> = fr
            .bonds
            .par_iter()
            .enumerate()
            .with_min_len(crate::CHUNK)
            .filter(|(_, bond)| copies.has(bond.nodes[0]) || copies.has(bond.nodes[1]))
            .map(|(k, _)| k)
            .collect();
        for k in touching {
            let bond = &fr.bonds[k];
            let [a, b] = bond.nodes;
            let (ia, ib) = (others.binary_search_by_key(&a, |e| e.0), others.binary_search_by_key(&b, |e| e.0));
            if (ia.is_err() && ib.is_err()) || new_bond(k) {
                continue;
            }
            let f = bond.force(x[a as usize], x[b as usize]);
            if let Ok(i) = ib {
                others[i].1 = [others[i].1[0] + f[0], others[i].1[1] + f[1]];
            }
            if let Ok(i) = ia {
                others[i].1 = [others[i].1[0] - f[0], others[i].1[1] - f[1]];
            }
        }
        for (range, copies) in which {
            let m = copies.len();
            let at = |p: u32| copies.iter().position(|&c| c == p);
            let (g, centre): (Vec<Vec2>, Vec<Vec2>) = copies
                .iter()
                .map(|&c| {
                    let e = others[others.binary_search_by_key(&c, |e| e.0).expect("a copy")];
                    (e.1, e.2)
                })
                .unzip();
            // the family's bonds join its copies (they were made between them)
            let edges: Option<Vec<(usize, usize)>> =
                fr.bonds[range.clone()].iter().map(|b| Some((at(b.nodes[0])?, at(b.nodes[1])?))).collect();
            let Some(edges) = edges else { continue };
            let Some(phi) = laplacian_potential(m, &edges, &g) else { continue };
            for (bond, &(u, v)) in fr.bonds[range.clone()].iter_mut().zip(&edges) {
                let kl = bond.stiffness * bond.length;
                if kl.is_nan() || kl <= 0.0 {
                    continue;
                }
                let f = [phi[v][0] - phi[u][0], phi[v][1] - phi[u][1]];
                let o = [-f[0] / kl, -f[1] / kl];
                // from u's side of the crack to v's: the copies are pulled apart
                let across = [centre[v][0] - centre[u][0], centre[v][1] - centre[u][1]];
                if o[0] * across[0] + o[1] * across[1] <= 0.0 {
                    continue;
                }
                let cap = bond.elastic_scale(o);
                bond.offset = [o[0] * cap, o[1] * cap];
            }
        }
    }

    /// Half the reference length of the crack faces at `u` that face crack
    /// faces at `v` (the same segment seen from its two sides: far ends of
    /// the same ancestor) (m): the tributary length of a bond `(u, v)`.
    pub(crate) fn shared_crack_length(&self, u: u32, v: u32) -> f64 {
        self.shared_crack(u, v).0
    }

    /// [`Self::shared_crack_length`] and those faces' direction now, as the
    /// length-weighted sum of their doubled-angle unit vectors (so that the
    /// two faces of a straight crack through `u`, which leave it in
    /// opposite directions, add up).
    pub(crate) fn shared_crack(&self, u: u32, v: u32) -> (f64, Vec2) {
        let Some(crack_law) = self.contact.as_ref().map(|c| c.crack_law) else { return (0.0, [0.0; 2]) };
        let s = &self.surface;
        let faces = |node: u32| {
            let bi = s.index_of[node as usize];
            let row: &[u32] = if bi == crate::NONE { &[] } else { s.node_facets.row(bi as usize) };
            row.iter().map(|&k| &s.facets[k as usize]).filter(|f| f.law == crack_law).map(move |f| {
                let far = if f.nodes[0] == node { f.nodes[1] } else { f.nodes[0] };
                (far, f.length)
            })
        };
        let x = &self.nodes.x;
        let (mut length, mut doubled) = (0.0, [0.0; 2]);
        for (far, l) in
            faces(u).filter(|&(far, _)| faces(v).any(|(g, _)| self.ancestor[g as usize] == self.ancestor[far as usize]))
        {
            length += 0.5 * l;
            let t = [x[far as usize][0] - x[u as usize][0], x[far as usize][1] - x[u as usize][1]];
            let s = t[0] * t[0] + t[1] * t[1];
            if s > 0.0 {
                // (cos 2θ, sin 2θ) of t, weighted by the face's length
                doubled[0] += l * (t[0] * t[0] - t[1] * t[1]) / s;
                doubled[1] += l * 2.0 * t[0] * t[1] / s;
            }
        }
        (length, doubled)
    }

    /// The unit normal of the crack between copies `u` and `v` of a split
    /// node, from `u`'s side to `v`'s: normal to the faces' mean direction
    /// (`doubled`, from [`Self::shared_crack`]), turned towards the
    /// centroid of `v`'s elements from that of `u`'s. The mixed-mode bond
    /// between them measures opening along it and slip across it.
    pub(crate) fn crack_normal(&self, u: u32, v: u32, doubled: Vec2) -> Vec2 {
        let half = 0.5 * doubled[1].atan2(doubled[0]);
        let mut n = [-half.sin(), half.cos()];
        let (cu, cv) = (self.star_centre(u), self.star_centre(v));
        if n[0] * (cv[0] - cu[0]) + n[1] * (cv[1] - cu[1]) < 0.0 {
            n = [-n[0], -n[1]];
        }
        n
    }

    /// The mean of the vertices of the active elements around node `p`
    /// (m): which side of a crack its piece lies on.
    pub(crate) fn star_centre(&self, p: u32) -> Vec2 {
        let (x, conn) = (&self.nodes.x, &self.elems.conn);
        let (mut c, mut k) = ([0.0; 2], 0.0_f64);
        for &item in self.node_elems.row(p as usize) {
            for &q in &conn[(item / 3) as usize] {
                c = [c[0] + x[q as usize][0], c[1] + x[q as usize][1]];
                k += 1.0;
            }
        }
        [c[0] / k.max(1.0), c[1] / k.max(1.0)]
    }

    /// Adds the forces of the intact bonds at `xⁿ` to the contact forces of
    /// their (boundary) nodes, books their dissipation as fracture energy,
    /// and drops the bonds that broke. The bonds are updated in parallel
    /// over fixed chunks of [`crate::CHUNK`] bonds (each bond reads only its
    /// two nodes), each chunk summing its bonds' energies in bond order as
    /// it goes, and the chunks' sums are added in chunk order; their forces
    /// are then added in parallel over chunks of boundary nodes, each
    /// node's in bond order ([`BondGather`]). Nothing depends on the thread
    /// count. (The energies were summed over all the bonds in one serial
    /// pass beside the forces' sum: 1% of the 10⁴ fragmenting impact at one
    /// thread, and the longer side of that join at many threads.)
    pub(crate) fn bond_forces(&mut self) {
        let Some(fr) = &mut self.fracture else { return };
        if fr.bonds.is_empty() {
            self.ledger.account.cohesive_elastic = 0.0;
            return;
        }
        let (x, surface) = (&self.nodes.x, &self.surface);
        // both grow only when the bonds do (at insertions)
        let responses = &mut fr.bond_responses;
        responses.resize(fr.bonds.len(), BondResponse::default());
        fr.bond_chunk_sums.resize(fr.bonds.len().div_ceil(crate::CHUNK), (0.0, 0.0, false));
        fr.bonds
            .par_chunks_mut(crate::CHUNK)
            .zip(responses.par_chunks_mut(crate::CHUNK))
            .zip(fr.bond_chunk_sums.par_iter_mut())
            .for_each(|((bonds, rs), sums)| {
                let (mut d, mut e, mut broken) = (0.0, 0.0, false);
                for (bond, r) in bonds.iter_mut().zip(rs) {
                    let [a, b] = bond.nodes;
                    *r = bond.update(x[a as usize], x[b as usize]);
                    d += r.dissipated;
                    e += r.elastic;
                    broken |= r.broken;
                }
                *sums = (d, e, broken);
            });
        let (dissipated, elastic, broken) =
            fr.bond_chunk_sums.iter().fold((0.0, 0.0, false), |(d, e, b), &(cd, ce, cb)| (d + cd, e + ce, b | cb));
        fr.bond_gather.ensure(&fr.bonds, &surface.index_of, surface.nodes.len());
        let (gather, responses) = (&fr.bond_gather, &fr.bond_responses);
        gather.add(&mut self.node_forces.contact_force, |k| responses[k].force);
        if broken {
            fr.bond_gather.drop_broken(&fr.bond_responses);
            let mut k = 0;
            let responses = &fr.bond_responses;
            fr.bonds.retain(|_| {
                k += 1;
                !responses[k - 1].broken
            });
        }
        self.ledger.account.fracture += dissipated;
        self.ledger.account.cohesive_elastic = elastic;
    }

    /// Adds the forces of the intact bonds, as the last [`Self::bond_forces`]
    /// left them (at the same positions, without updating the bonds), to
    /// the contact forces of their nodes, in the same order (the same
    /// [`BondGather`]): what a rebuild of the contact forces from the
    /// contact records outside a step (restore, renumbering) must add to
    /// give the forces the step left.
    pub(crate) fn add_bond_forces(&mut self) {
        let Some(fr) = &mut self.fracture else { return };
        let (x, surface) = (&self.nodes.x, &self.surface);
        fr.bond_gather.ensure(&fr.bonds, &surface.index_of, surface.nodes.len());
        let bonds = &fr.bonds;
        fr.bond_gather.add(&mut self.node_forces.contact_force, |k| {
            let [a, b] = bonds[k].nodes;
            bonds[k].force(x[a as usize], x[b as usize])
        });
    }

    /// The law of a bond across a crack inserted at node `p`: strength
    /// `t₀ = f_t (1 − F)` (Pa) and final opening `δ_c = 2 G_f (1 − F) / f_t`
    /// (m) in tension, shear strength `c (1 − F)` and `tan φ`, and
    /// mode-II energy `G_II (1 − F)²` for linear softening; for a bilinear
    /// curve `s`, `t₀ = f_t s(F)`, `c s(F)`, the energies `G_f` and `G_II`
    /// times the fraction `r(F)` of the curve's area left, `δ_c = 2 G_f
    /// r(F) / t₀` and the curve's kink if `F` is before it; with `F` and
    /// the parameters those of
    /// the most softened element around `p`: the bond continues that
    /// element's softening curve, so band and bond together dissipate `G_f`
    /// per unit crack length, and it is no stronger than any element beside
    /// it, so the crack, not the band, takes up the opening
    /// (docs/fracture.md). `None` once that element has fully softened (the
    /// paper's traction-free crack).
    pub(crate) fn remaining_softening(&self, fr: &FractureModel, p: u32) -> Option<BondSeed> {
        let mut most: Option<(f64, usize)> = None;
        for &item in self.node_elems.row(p as usize) {
            let e = (item / 3) as usize;
            let f = fr.element_factor[e];
            if self.elems.active[e] && f > 0.0 && most.is_none_or(|(g, _)| f > g) {
                most = Some((f, e));
            }
        }
        let (f, e) = most?;
        if f >= 1.0 {
            return None;
        }
        let material = &self.materials[self.elems.material[e] as usize];
        let law = material.plastic.as_ref()?;
        let (ft, gf) = (law.tensile_strength, law.fracture_energy);
        if law.softening == Softening::Linear {
            let r = 1.0 - f;
            return Some(BondSeed {
                strength: ft * r,
                final_opening: 2.0 * gf * r / ft,
                cohesion: law.cohesion * r,
                friction: law.friction.tan(),
                shear_energy: material.shear_fracture_energy * r * r,
                kink: None,
            });
        }
        let (s, left) = (law.softening.stress(f), law.softening.remaining(f));
        Some(BondSeed {
            strength: ft * s,
            final_opening: 2.0 * gf * left / (ft * s),
            cohesion: law.cohesion * s,
            friction: law.friction.tan(),
            shear_energy: material.shear_fracture_energy * left,
            kink: law.softening.kink_after(f).map(|(at, traction)| fdem_contact::Kink { at, traction }),
        })
    }
}

/// The least-norm potentials `φ` (one 2-vector per node of a small graph
/// of `m` nodes and `edges` `(u, v)`) with `Bᵀ B φ = −(g − ḡ)`, `B` the
/// edges' incidence matrix (`+1` at `v`, `−1` at `u`) and `ḡ` the mean of
/// `g` over each connected part: the edge forces `φ_v − φ_u` then cancel
/// `g` as far as forces within each part can. `None` if an edge names a
/// node beyond `m`. Dense Gaussian elimination: the graphs are the copies
/// of one split node (two to a handful).
pub(crate) fn laplacian_potential(m: usize, edges: &[(usize, usize)], g: &[Vec2]) -> Option<Vec<Vec2>> {
    if edges.iter().any(|&(u, v)| u >= m || v >= m || u == v) {
        return None;
    }
    // connected parts (the graphs are tiny: relabel until stable)
    let mut part: Vec<usize> = (0..m).collect();
    loop {
        let mut changed = false;
        for &(u, v) in edges {
            let low = part[u].min(part[v]);
            for w in [u, v] {
                if part[w] != low {
                    part[w] = low;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    // right-hand side with each part's mean taken out
    let mut rhs = vec![[0.0; 2]; m];
    for p in 0..m {
        let members: Vec<usize> = (0..m).filter(|&i| part[i] == part[p]).collect();
        let n = members.len() as f64;
        let mean = members.iter().fold([0.0; 2], |a, &i| [a[0] + g[i][0] / n, a[1] + g[i][1] / n]);
        rhs[p] = [-(g[p][0] - mean[0]), -(g[p][1] - mean[1])];
    }
    // the Laplacian, each part's first node pinned (φ = 0 there)
    let mut a = vec![vec![0.0_f64; m]; m];
    for &(u, v) in edges {
        a[u][u] += 1.0;
        a[v][v] += 1.0;
        a[u][v] -= 1.0;
        a[v][u] -= 1.0;
    }
    for p in 0..m {
        if part[p] == p {
            a[p].iter_mut().for_each(|e| *e = 0.0);
            for row in a.iter_mut() {
                row[p] = 0.0;
            }
            a[p][p] = 1.0;
            rhs[p] = [0.0; 2];
        }
    }
    // symmetric positive definite: elimination without pivoting
    for c in 0..m {
        let pivot = a[c][c];
        if pivot.abs() < 1e-300 {
            return None;
        }
        for r in c + 1..m {
            let f = a[r][c] / pivot;
            if f != 0.0 {
                for k in c..m {
                    a[r][k] -= f * a[c][k];
                }
                rhs[r] = [rhs[r][0] - f * rhs[c][0], rhs[r][1] - f * rhs[c][1]];
            }
        }
    }
    let mut phi = vec![[0.0; 2]; m];
    for r in (0..m).rev() {
        let mut s = rhs[r];
        for k in r + 1..m {
            s = [s[0] - a[r][k] * phi[k][0], s[1] - a[r][k] * phi[k][1]];
        }
        phi[r] = [s[0] / a[r][r], s[1] / a[r][r]];
    }
    Some(phi)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{CHUNK, NONE};

    /// The bonds' forces added through [`BondGather`] are those of the
    /// serial loop over the bonds it replaced (each node's bond forces in
    /// bond order, after what the node held), bit for bit, on 1, 2 and 3
    /// threads, over several chunks of boundary nodes, with bonds that
    /// cross chunks and bonds with a node off the surface (left out); and
    /// after bonds break, the lists struck in place are those built afresh
    /// for the bonds that are left.
    #[test]
    fn the_gathered_bond_forces_are_the_serial_loops_on_any_thread_count() {
        let (n, nb) = (4 * CHUNK, 2 * CHUNK + CHUNK / 3);
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        // every third mesh node is off the surface
        let mut index_of = vec![NONE; n];
        let mut b = 0;
        for (v, i) in index_of.iter_mut().enumerate() {
            if v % 3 != 2 && b < nb {
                *i = b as u32;
                b += 1;
            }
        }
        assert_eq!(b, nb);
        let bond = |a: u32, b: u32| Bond {
            nodes: [a, b],
            length: 1.0,
            stiffness: 1.0,
            strength: 1.0,
            final_opening: 1.0,
            max_opening: 0.0,
            offset: [0.0; 2],
            mode: None,
        };
        // pairs of near nodes mostly (copies of one split node), far now and
        // then; many nodes with several bonds
        let mut bonds: Vec<Bond> = (0..3000)
            .map(|_| {
                let a = (next() % n as u64) as u32;
                let b = if next() % 8 == 0 { next() % n as u64 } else { (u64::from(a) + 1 + next() % 5) % n as u64 };
                bond(a, if b as u32 == a { (a + 1) % n as u32 } else { b as u32 })
            })
            .collect();
        let mut responses: Vec<BondResponse> = (0..bonds.len())
            .map(|k| BondResponse {
                force: [(next() % 2001) as f64 * 0.37 - 370.0, 1e-3 * (next() % 997) as f64 - 0.5],
                broken: next() % 7 == 0 && k % 2 == 0,
                ..BondResponse::default()
            })
            .collect();
        let start: Vec<Vec2> = (0..nb).map(|i| [0.1 * i as f64, 3.3 - 1e-2 * i as f64]).collect();
        let serial = |bonds: &[Bond], responses: &[BondResponse]| {
            let mut force = start.clone();
            for (bond, r) in bonds.iter().zip(responses) {
                let (ia, ib) = (index_of[bond.nodes[0] as usize], index_of[bond.nodes[1] as usize]);
                if ia != NONE && ib != NONE {
                    let fa = &mut force[ia as usize];
                    fa[0] -= r.force[0];
                    fa[1] -= r.force[1];
                    let fb = &mut force[ib as usize];
                    fb[0] += r.force[0];
                    fb[1] += r.force[1];
                }
            }
            force
        };
        let want = serial(&bonds, &responses);
        // the lists of one pass over the bonds in bond order
        let mut lists = vec![Vec::new(); nb.div_ceil(CHUNK)];
        for (k, bond) in bonds.iter().enumerate() {
            let [ia, ib] = bond.nodes.map(|v| index_of[v as usize]);
            if ia != NONE && ib != NONE {
                for (s, i) in [ia, ib].into_iter().enumerate() {
                    lists[i as usize / CHUNK].push([(i as usize % CHUNK) as u32, 2 * k as u32 + s as u32]);
                }
            }
        }
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut gather = BondGather::default();
            let mut force = start.clone();
            pool.install(|| {
                gather.ensure(&bonds, &index_of, nb);
                gather.add(&mut force, |k| responses[k].force);
            });
            assert!(gather.chunks == lists, "{threads} threads: the lists");
            assert!(force == want, "{threads} threads");
            assert!(gather.chunks.iter().all(|list| !list.is_empty()), "every chunk has bonds");
        }
        // some bonds break: struck out in place, the rest renumbered
        let mut gather = BondGather::default();
        gather.ensure(&bonds, &index_of, nb);
        gather.drop_broken(&responses);
        let mut k = 0;
        bonds.retain(|_| {
            k += 1;
            !responses[k - 1].broken
        });
        responses.retain(|r| !r.broken);
        assert!(bonds.len() < 2900);
        let mut fresh = BondGather::default();
        fresh.build(&bonds, &index_of, nb.div_ceil(CHUNK));
        assert!(gather.chunks == fresh.chunks && gather.bonds == bonds.len());
        let mut force = start.clone();
        gather.ensure(&bonds, &index_of, nb);
        gather.add(&mut force, |k| responses[k].force);
        assert!(force == serial(&bonds, &responses));
    }
}
