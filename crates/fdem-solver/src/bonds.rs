//! Cohesive bonds across young cracks, seen from the solver (DESIGN §4.4
//! as amended in docs/fracture.md; the law itself is
//! `fdem_contact::cohesive`): what a new crack's bonds owe
//! ([`Simulation::remaining_softening`]), along which normal and over
//! which length they act ([`Simulation::shared_crack`]), the force they
//! take over at insertion ([`Simulation::preload_bonds`]), and their forces
//! and energies in each step ([`Simulation::bond_forces`]). Split from
//! `fracture.rs` (the check and the topology edits), which calls it.

use fdem_element::Vec2;
use fdem_material::Softening;
use rayon::prelude::*;

use crate::fracture::FractureModel;
use crate::simulation::Simulation;

/// Adds a bond's force `f` on its node `b` (and `−f` on `a`) to the contact
/// forces (by boundary node) of `nodes = [a, b]`, when both are on the
/// surface.
#[inline]
pub(crate) fn add_bond_force(force: &mut [Vec2], index_of: &[u32], [a, b]: [u32; 2], f: Vec2) {
    let (ia, ib) = (index_of[a as usize], index_of[b as usize]);
    if ia != crate::NONE && ib != crate::NONE {
        let fa = &mut force[ia as usize];
        fa[0] -= f[0];
        fa[1] -= f[1];
        let fb = &mut force[ib as usize];
        fb[0] += f[0];
        fb[1] += f[1];
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
        for (k, bond) in fr.bonds.iter().enumerate() {
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
    /// (each reads only its two nodes); their forces and energies are then
    /// added up in bond order, so the sums do not depend on the thread
    /// count.
    pub(crate) fn bond_forces(&mut self) {
        let Some(fr) = &mut self.fracture else { return };
        if fr.bonds.is_empty() {
            self.ledger.account.cohesive_elastic = 0.0;
            return;
        }
        let (x, index_of) = (&self.nodes.x, &self.surface.index_of);
        // grows only when the bonds do (at insertions)
        let responses = &mut fr.bond_responses;
        responses.resize(fr.bonds.len(), fdem_contact::BondResponse::default());
        fr.bonds.par_iter_mut().zip(responses.par_iter_mut()).with_min_len(crate::CHUNK).for_each(|(bond, r)| {
            let [a, b] = bond.nodes;
            *r = bond.update(x[a as usize], x[b as usize]);
        });
        let (mut dissipated, mut elastic) = (0.0, 0.0);
        let force = &mut self.node_forces.contact_force;
        let mut broken = false;
        for (bond, r) in fr.bonds.iter().zip(responses.iter()) {
            dissipated += r.dissipated;
            elastic += r.elastic;
            add_bond_force(force, index_of, bond.nodes, r.force);
            broken |= r.broken;
        }
        if broken {
            let mut k = 0;
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
    /// the contact forces of their nodes, in the same order: what a rebuild
    /// of the contact forces from the contact records outside a step
    /// (restore, renumbering) must add to give the forces the step left.
    pub(crate) fn add_bond_forces(&mut self) {
        let Some(fr) = &self.fracture else { return };
        let (x, index_of) = (&self.nodes.x, &self.surface.index_of);
        for bond in &fr.bonds {
            let [a, b] = bond.nodes;
            add_bond_force(
                &mut self.node_forces.contact_force,
                index_of,
                bond.nodes,
                bond.force(x[a as usize], x[b as usize]),
            );
        }
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
