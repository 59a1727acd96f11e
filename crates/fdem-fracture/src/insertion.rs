//! Rotating-crack insertion through nodes (paper 2.4, Fig. 2; DESIGN §4.4).
//!
//! At a node `p` whose averaged failure factor has reached the insertion
//! factor (1 in the paper; see `docs/fracture.md`), a crack is opened along
//! the plane normal to σ1: the line through `p` in the
//! directions `±c`, `c ⟂ θ̄_p`. For each direction that goes into material
//! and is not already cracked:
//!
//! * **inter-element** (Fig. 2c): an existing edge at `p` within the
//!   tolerance angle of `c` is opened;
//! * **intra-element** (Fig. 2b): otherwise the element crossed by the ray
//!   is split by a new node `m` where the ray meets its opposite edge, and
//!   the neighbour across that edge is split too, so the mesh stays
//!   conforming. If any of the four children would fall below the minimum
//!   quality or size, the crack snaps to the nearer edge instead.
//!
//! Then `p` is duplicated: one copy per sector of its star (elements
//! connected across uncut edges); the sector with the smallest element id
//! keeps `p`. An interior node needs both directions cut to separate; a
//! boundary node or a crack tip one; a node where a crack has run into the
//! boundary or into another crack none. A new node `m` is the crack's tip.
//!
//! Cracks interact: a node next to another crack (reached by an interior
//! edge) does not start a new one, and a crack tip there links up with it
//! through that edge (within 60° of its direction) instead of running
//! alongside; otherwise a band would be cut into slivers.
//!
//! Every insertion is planned on the mesh as it was when the check began.
//! An insertion claims the elements it reads or changes; a later candidate
//! whose star meets a claimed element waits for the next check. So
//! insertions of one check never conflict, and the result depends only on
//! the order of the candidates (decreasing `F̄`, then node id).

use fdem_mesh::Csr;
use rayon::prelude::*;
use smallvec::SmallVec;

use crate::Vec2;

/// Parameters of crack insertion.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FractureParams {
    /// An existing edge within this angle (rad) of the crack direction is
    /// opened instead of splitting an element.
    pub edge_tolerance: f64,
    /// A crack face or boundary edge at the node within this angle (rad)
    /// means the direction is already cracked.
    pub crack_tolerance: f64,
    /// Smallest quality `4√3 A / Σ l²` (1 for an equilateral triangle) a new
    /// triangle may have.
    pub min_quality: f64,
    /// Smallest altitude `2A / l_max` (m) a new triangle may have; 0 for no
    /// limit. Quality alone does not stop repeated splits from shrinking
    /// elements (and the stable time step, which scales with the smallest
    /// altitude) without bound.
    pub min_altitude: f64,
}

impl Default for FractureParams {
    fn default() -> Self {
        Self {
            edge_tolerance: 15f64.to_radians(),
            crack_tolerance: 30f64.to_radians(),
            min_quality: 0.2,
            min_altitude: 0.0,
        }
    }
}

/// A node created by an insertion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NewNode {
    /// A copy of node `of` (the other side of the crack).
    Copy {
        /// The node copied.
        of: u32,
    },
    /// A node on edge `(a, b)` at `a + t (b − a)` (a crack tip).
    OnEdge {
        /// Start of the edge.
        a: u32,
        /// End of the edge.
        b: u32,
        /// Position along it, in `(0, 1)`.
        t: f64,
    },
}

/// The topology edits of one check.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Edits {
    /// Nodes to append, in order (ids `n_nodes`, `n_nodes + 1`, …).
    pub new_nodes: Vec<NewNode>,
    /// Existing elements that get new connectivity.
    pub changed: Vec<(u32, [u32; 3])>,
    /// Elements to append, in order, with the element they come from.
    pub added: Vec<(u32, [u32; 3])>,
    /// New crack faces, as node pairs in ids before duplication (both
    /// sides of each face share the pair).
    pub crack_faces: Vec<[u32; 2]>,
    /// Edges `(a, b)` split by a new node `m`: facets `(a, m)` and `(m, b)`
    /// inherit whatever `(a, b)` was.
    pub split_edges: Vec<([u32; 2], u32)>,
    /// Nodes at which a crack was inserted.
    pub inserted_at: Vec<u32>,
    /// Candidates that wait for the next check because an insertion of this
    /// check claimed part of their star, in candidate order. They are still
    /// due: the caller must keep them candidates at the next check.
    pub waiting: Vec<u32>,
}

#[inline]
fn sub(a: Vec2, b: Vec2) -> Vec2 {
    [a[0] - b[0], a[1] - b[1]]
}

#[inline]
fn cross(a: Vec2, b: Vec2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Angle (rad) between direction `d` (unit) and vector `v`.
#[inline]
fn angle(d: Vec2, v: Vec2) -> f64 {
    cross(d, v).atan2(d[0] * v[0] + d[1] * v[1]).abs()
}

/// Quality `4√3 A / Σ l²` of a triangle (negative if clockwise).
pub fn quality(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let area = 0.5 * cross(sub(b, a), sub(c, a));
    let l2 = |u: Vec2, v: Vec2| (u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2);
    4.0 * 3f64.sqrt() * area / (l2(a, b) + l2(b, c) + l2(c, a))
}

/// Smallest altitude `2A / l_max` of a triangle (m; negative if clockwise).
pub fn altitude(a: Vec2, b: Vec2, c: Vec2) -> f64 {
    let area2 = cross(sub(b, a), sub(c, a));
    let l2 = |u: Vec2, v: Vec2| (u[0] - v[0]).powi(2) + (u[1] - v[1]).powi(2);
    area2 / l2(a, b).max(l2(b, c)).max(l2(c, a)).sqrt()
}

impl FractureParams {
    /// Whether a new triangle `(a, b, c)` meets the minimum quality and size.
    pub fn acceptable(&self, a: Vec2, b: Vec2, c: Vec2) -> bool {
        quality(a, b, c) >= self.min_quality && altitude(a, b, c) >= self.min_altitude
    }
}

/// A crack tip links up with another crack through an edge within this
/// angle (rad) of its direction.
const LINK_CONE: f64 = std::f64::consts::FRAC_PI_3;

/// What one direction of the crack at a node resolves to.
#[derive(Clone, Copy, Debug)]
enum Cut {
    /// Open the existing edge `(p, w)`.
    Edge(u32),
    /// Split element `e` (and its neighbour `n`, if any) at `t` along
    /// `(q, r)`.
    Split { e: u32, n: Option<u32>, q: u32, r: u32, t: f64 },
}

/// Per-node inputs of [`plan`].
#[derive(Clone, Copy, Debug)]
pub struct NodeFailure<'a> {
    /// Direction of σ1 (rad from x): the crack runs along `(−sin θ, cos θ)`.
    /// Read for the candidates only.
    pub normal: &'a [f64],
    /// The node lies on an existing crack (may be shorter than the node
    /// count: missing entries are `false`).
    pub cracked: &'a [bool],
}

/// Plans the insertions of one check.
///
/// `candidates` are the nodes that have reached the insertion factor, in
/// priority order. `conn`, `active`, `node_elems` and `x` (current
/// positions) describe the mesh at the check; new ids start after the last
/// node and element. A crack does not start afresh at a node next to an
/// existing crack (the open crack has relieved it; the crack grows from its
/// tip instead, and the band beside it is not cut into slivers), and a
/// crack tip next to another crack links up with it. `scratch` holds the
/// buffers kept from check to check ([`PlanScratch`]), so that a check
/// that inserts nothing allocates nothing.
///
/// Each candidate's insertion is planned in parallel on the mesh as it was
/// at the check, as if nothing were claimed; then, in candidate order, a
/// candidate whose star an earlier insertion claimed waits, one whose plan
/// read the claim of a split neighbour that an earlier insertion claimed
/// is planned again with the claims as they stand, and the others are
/// committed with their new ids counted on. The result is the same as
/// planning the candidates one by one in order ([`plan_in_order`]), on any
/// thread count. (One by one, planning was 0.6% of a fragmenting impact's
/// run at one thread, all of it serial.)
#[allow(clippy::too_many_arguments)]
pub fn plan(
    scratch: &mut PlanScratch,
    conn: &[[u32; 3]],
    active: &[bool],
    node_elems: &Csr,
    x: &[Vec2],
    candidates: &[u32],
    nodes: &NodeFailure<'_>,
    params: &FractureParams,
) -> Edits {
    let check = Check { conn, active, node_elems, x, nodes: *nodes, params };
    let PlanScratch { proposals, claimed } = scratch;
    candidates.par_iter().with_min_len(8).map(|&p| plan_one(&check, p, |_| false)).collect_into_vec(proposals);
    let mut edits = Edits::default();
    claimed.clear();
    claimed.resize(conn.len(), false);
    for (&p, proposal) in candidates.iter().zip(proposals.drain(..)) {
        let Some(mut proposal) = proposal else { continue };
        if proposal.star.iter().any(|&e| claimed[e as usize]) {
            edits.waiting.push(p);
            continue;
        }
        if proposal.read.iter().any(|&n| claimed[n as usize]) {
            proposal = plan_one(&check, p, |n| claimed[n as usize]).expect("the star is the same");
        }
        if let Some(insertion) = proposal.insertion {
            insertion.commit(p, &mut edits, claimed, x.len() as u32);
        }
    }
    edits
}

/// The buffers [`plan`] keeps from check to check: a check that inserts
/// nothing (its candidates all wait, or none can separate) then allocates
/// nothing, as the time loop must not (a fragmented impact's checks
/// re-plan a couple of hundred such candidates each).
#[derive(Default)]
pub struct PlanScratch {
    proposals: Vec<Option<Proposal>>,
    claimed: Vec<bool>,
}

/// [`plan`] one candidate at a time, in order, each planned with the claims
/// of the insertions before it: the definition [`plan`] keeps to (the
/// tests compare the two).
#[allow(clippy::too_many_arguments)]
pub fn plan_in_order(
    conn: &[[u32; 3]],
    active: &[bool],
    node_elems: &Csr,
    x: &[Vec2],
    candidates: &[u32],
    nodes: &NodeFailure<'_>,
    params: &FractureParams,
) -> Edits {
    let check = Check { conn, active, node_elems, x, nodes: *nodes, params };
    let mut edits = Edits::default();
    let mut claimed = vec![false; conn.len()];
    for &p in candidates {
        let Some(proposal) = plan_one(&check, p, |n| claimed[n as usize]) else { continue };
        if proposal.star.iter().any(|&e| claimed[e as usize]) {
            edits.waiting.push(p);
        } else if let Some(insertion) = proposal.insertion {
            insertion.commit(p, &mut edits, &mut claimed, x.len() as u32);
        }
    }
    edits
}

/// The mesh at the check and the other inputs of [`plan`].
#[derive(Clone, Copy)]
struct Check<'a> {
    conn: &'a [[u32; 3]],
    active: &'a [bool],
    node_elems: &'a Csr,
    x: &'a [Vec2],
    nodes: NodeFailure<'a>,
    params: &'a FractureParams,
}

impl Check<'_> {
    /// The active elements around `p` as `(element, q, r)`, `(p, q, r)`
    /// counter-clockwise.
    fn star_of(&self, p: u32) -> SmallVec<[(u32, u32, u32); STAR]> {
        self.node_elems
            .row(p as usize)
            .iter()
            .filter(|&&item| self.active[(item / 3) as usize])
            .map(|&item| {
                let (e, k) = (item / 3, (item % 3) as usize);
                let t = self.conn[e as usize];
                (e, t[(k + 1) % 3], t[(k + 2) % 3])
            })
            .collect()
    }

    /// The active element other than `e` across edge `(q, r)`.
    fn neighbour(&self, e: u32, q: u32, r: u32) -> Option<u32> {
        self.node_elems
            .row(q as usize)
            .iter()
            .map(|&i| i / 3)
            .find(|&f| f != e && self.active[f as usize] && self.conn[f as usize].contains(&r))
    }
}

/// The elements round a node that a plan keeps without allocating: a
/// node of a triangulation has about six, a fragmented one rarely more
/// than twelve (more spill to the heap, as a `Vec` would).
const STAR: usize = 16;

/// One candidate as planned on the mesh at the check.
struct Proposal {
    /// The elements of its star: it waits if an earlier insertion claimed one.
    star: SmallVec<[u32; STAR]>,
    /// The split neighbours whose claims the plan read: planned again if an
    /// earlier insertion claimed one (one per direction).
    read: SmallVec<[u32; 2]>,
    /// The insertion, if the node separates.
    insertion: Option<Insertion>,
}

/// One insertion, its new nodes numbered from the node count at the check
/// (as if it were the check's first).
struct Insertion {
    /// The elements it claims: its star and the split neighbours.
    claims: Vec<u32>,
    /// [`Edits`]' lists of this insertion alone, in their order.
    new_nodes: Vec<NewNode>,
    split_edges: Vec<([u32; 2], u32)>,
    changed: Vec<(u32, [u32; 3])>,
    added: Vec<(u32, [u32; 3])>,
    crack_faces: Vec<[u32; 2]>,
}

impl Insertion {
    /// Appends this insertion at node `p` to `edits` (its new node ids
    /// shifted past those already planned; `n_nodes` nodes at the check)
    /// and claims its elements.
    fn commit(self, p: u32, edits: &mut Edits, claimed: &mut [bool], n_nodes: u32) {
        for &e in &self.claims {
            claimed[e as usize] = true;
        }
        let base = edits.new_nodes.len() as u32;
        let id = |v: u32| if v >= n_nodes { v + base } else { v };
        edits.new_nodes.extend(self.new_nodes);
        edits.split_edges.extend(self.split_edges.into_iter().map(|(edge, m)| (edge, id(m))));
        edits.changed.extend(self.changed.into_iter().map(|(e, t)| (e, t.map(id))));
        edits.added.extend(self.added.into_iter().map(|(e, t)| (e, t.map(id))));
        edits.crack_faces.extend(self.crack_faces.into_iter().map(|f| f.map(id)));
        edits.inserted_at.push(p);
    }
}

/// Plans candidate `p` on the mesh at the check, reading a split
/// neighbour's claim through `claimed`; `None` if `p` has no active element.
fn plan_one(check: &Check<'_>, p: u32, claimed: impl Fn(u32) -> bool) -> Option<Proposal> {
    let m = check;
    let Check { conn, x, params, .. } = *check;
    let NodeFailure { normal, cracked } = check.nodes;
    let (n_nodes, n_elements) = (x.len() as u32, conn.len() as u32);
    let star = m.star_of(p);
    if star.is_empty() {
        return None;
    }
    let mut proposal =
        Proposal { star: star.iter().map(|&(e, ..)| e).collect(), read: SmallVec::new(), insertion: None };
    let xp = x[p as usize];
    // edges at p and how many star elements hold each (1: a face)
    let mut edges: SmallVec<[(u32, u32); 2 * STAR]> = SmallVec::new();
    for &(_, q, r) in &star {
        for w in [q, r] {
            match edges.iter_mut().find(|(v, _)| *v == w) {
                Some(entry) => entry.1 += 1,
                None => edges.push((w, 1)),
            }
        }
    }
    // another crack next to p: a node on a crack reached by an interior
    // edge of p's star (no face joins it to p). A fresh crack does not
    // start there (the open crack has relieved it); a crack tip links up
    // with it instead of running alongside and cutting a sliver.
    let on_crack = |v: u32| cracked.get(v as usize).copied().unwrap_or(false);
    let foreign = |w: u32, k: u32| k == 2 && on_crack(w);
    if !on_crack(p) && edges.iter().any(|&(w, k)| foreign(w, k)) {
        return Some(proposal);
    }
    let th = normal[p as usize];
    let c = [-th.sin(), th.cos()];
    let mut cuts: SmallVec<[Cut; 2]> = SmallVec::new();
    // the split neighbours whose claims were read
    let mut read = SmallVec::new();
    for d in [c, [-c[0], -c[1]]] {
        // already cracked (or the boundary) in this direction?
        if edges.iter().any(|&(w, k)| k == 1 && angle(d, sub(x[w as usize], xp)) < params.crack_tolerance) {
            continue;
        }
        if on_crack(p) {
            let link = edges
                .iter()
                .filter(|&&(w, k)| foreign(w, k))
                .map(|&(w, _)| (angle(d, sub(x[w as usize], xp)), w))
                .filter(|&(a, _)| a < LINK_CONE)
                .min_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((_, w)) = link {
                cuts.push(Cut::Edge(w));
                continue;
            }
        }
        let Some(&(e, q, r)) = star
            .iter()
            .find(|&&(_, q, r)| cross(sub(x[q as usize], xp), d) >= 0.0 && cross(d, sub(x[r as usize], xp)) >= 0.0)
        else {
            continue; // the direction leaves the material
        };
        let interior = |w: u32| edges.iter().any(|&(v, k)| v == w && k == 2);
        let (aq, ar) = (angle(d, sub(x[q as usize], xp)), angle(d, sub(x[r as usize], xp)));
        let nearer = if aq <= ar { (q, aq) } else { (r, ar) };
        let snap = if interior(nearer.0) { Some(Cut::Edge(nearer.0)) } else { None };
        if nearer.1 < params.edge_tolerance {
            if let Some(s) = snap {
                cuts.push(s);
            }
            continue;
        }
        // the ray p + s d meets q + t (r − q) at t
        let (xq, xr) = (x[q as usize], x[r as usize]);
        let qr = sub(xr, xq);
        let denom = cross(d, qr);
        let t = if denom.abs() > 0.0 { cross(sub(xq, xp), d) / denom } else { -1.0 };
        let split = (t > 0.0 && t < 1.0).then(|| {
            let xm = [xq[0] + t * qr[0], xq[1] + t * qr[1]];
            let n = m.neighbour(e, q, r);
            let mut ok = params.acceptable(xp, xq, xm) && params.acceptable(xp, xm, xr);
            if let Some(n) = n {
                read.push(n);
                let s = conn[n as usize].iter().copied().find(|&v| v != q && v != r).unwrap_or(q);
                let xs = x[s as usize];
                ok &= !claimed(n)
                    && params.acceptable(xr, xm, xs)
                    && params.acceptable(xm, xq, xs)
                    && cuts.iter().all(|c| !matches!(c, Cut::Split { n: Some(m), .. } if *m == n));
            }
            (ok, n)
        });
        match split {
            Some((true, n)) => cuts.push(Cut::Split { e, n, q, r, t }),
            _ => {
                if let Some(s) = snap {
                    cuts.push(s);
                }
            }
        }
    }
    // no new cut may still separate: a crack that has run into a
    // boundary node or another crack has already split the star
    // the star after the planned splits: (provisional id, nodes)
    let mut next_node = n_nodes;
    let mut next_elem = n_elements;
    // (inline: a candidate that cannot separate allocates nothing)
    let mut local: SmallVec<[(u32, [u32; 3]); STAR + 2]> = star.iter().map(|&(e, q, r)| (e, [p, q, r])).collect();
    let mut outside: SmallVec<[(u32, [u32; 3]); 2]> = SmallVec::new(); // split neighbours' children (no p)
    let mut new_nodes: SmallVec<[NewNode; 4]> = SmallVec::new();
    let mut cut_to: SmallVec<[u32; 2]> = SmallVec::new();
    let mut added: SmallVec<[(u32, [u32; 3]); 4]> = SmallVec::new();
    let mut split_edges: SmallVec<[([u32; 2], u32); 2]> = SmallVec::new();
    for cut in &cuts {
        match *cut {
            Cut::Edge(w) => cut_to.push(w),
            Cut::Split { e, n, q, r, t } => {
                let mid = next_node;
                next_node += 1;
                new_nodes.push(NewNode::OnEdge { a: q, b: r, t });
                split_edges.push(([q, r], mid));
                if let Some(slot) = local.iter_mut().find(|(id, _)| *id == e) {
                    slot.1 = [p, q, mid];
                }
                local.push((next_elem, [p, mid, r]));
                added.push((e, [p, mid, r]));
                next_elem += 1;
                if let Some(n) = n {
                    let tn = conn[n as usize];
                    let k = (0..3).find(|&k| tn[k] == r && tn[(k + 1) % 3] == q).unwrap_or(0);
                    let s = tn[(k + 2) % 3];
                    outside.push((n, [r, mid, s]));
                    added.push((n, [mid, q, s]));
                    next_elem += 1;
                }
                cut_to.push(mid);
            }
        }
    }
    // sectors of p's star: joined across shared, uncut edges (p, w)
    let k = local.len();
    let mut parent: SmallVec<[usize; STAR + 2]> = (0..k).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..k {
        for j in i + 1..k {
            let shared = local[i].1[1..].iter().copied().find(|w| local[j].1[1..].contains(w));
            if let Some(w) = shared {
                if !cut_to.contains(&w) {
                    let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                    if a != b {
                        parent[a.max(b)] = a.min(b);
                    }
                }
            }
        }
    }
    let mut roots: SmallVec<[usize; 4]> = SmallVec::new();
    let mut order: SmallVec<[(u32, usize); STAR + 2]> = (0..k).map(|i| (local[i].0, i)).collect();
    order.sort_unstable();
    for &(_, i) in &order {
        let r = find(&mut parent, i);
        if !roots.contains(&r) {
            roots.push(r);
        }
    }
    proposal.read = read;
    if roots.len() < 2 {
        return Some(proposal); // nothing separates: leave the node for a later check
    }
    // the insertion: its claims, its splits, p duplicated per extra sector
    let mut claims = proposal.star.to_vec();
    claims.extend(cuts.iter().filter_map(|cut| match *cut {
        Cut::Split { n: Some(n), .. } => Some(n),
        _ => None,
    }));
    let copy_ids: Vec<u32> = (1..roots.len()).map(|s| next_node + s as u32 - 1).collect();
    new_nodes.extend((1..roots.len()).map(|_| NewNode::Copy { of: p }));
    let mut changed = Vec::with_capacity(k + outside.len());
    let copy_for = |i: usize, parent: &mut [usize]| -> u32 {
        let r = find(parent, i);
        let s = roots.iter().position(|&x| x == r).unwrap_or(0);
        if s == 0 {
            p
        } else {
            copy_ids[s - 1]
        }
    };
    for i in 0..k {
        let id = copy_for(i, &mut parent);
        let mut nodes = local[i].1;
        nodes[0] = id;
        // back to the element's own vertex order: rotate so the stored
        // order of an existing element is kept
        let (eid, tri) = (local[i].0, nodes);
        if eid < n_elements {
            let orig = conn[eid as usize];
            let kp = orig.iter().position(|&v| v == p).unwrap_or(0);
            let mut rotated = [0; 3];
            for j in 0..3 {
                rotated[(kp + j) % 3] = tri[j];
            }
            changed.push((eid, rotated));
        } else {
            added[(eid - n_elements) as usize].1 = tri;
        }
    }
    changed.extend(outside);
    let crack_faces = cut_to.iter().map(|&w| [p, w]).collect();
    proposal.insertion = Some(Insertion {
        claims,
        new_nodes: new_nodes.into_vec(),
        split_edges: split_edges.into_vec(),
        changed,
        added: added.into_vec(),
        crack_faces,
    });
    Some(proposal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fdem_mesh::node_elements;

    /// 3×3 cells of the unit square scaled by 3, alternating diagonals;
    /// node (i, j) has id 4j + i.
    fn grid() -> (Vec<Vec2>, Vec<[u32; 3]>) {
        let mut x = Vec::new();
        for j in 0..4 {
            for i in 0..4 {
                x.push([i as f64, j as f64]);
            }
        }
        let id = |i: u32, j: u32| 4 * j + i;
        let mut t = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if (i + j) % 2 == 0 {
                    t.push([a, b, c]);
                    t.push([a, c, d]);
                } else {
                    t.push([a, b, d]);
                    t.push([b, c, d]);
                }
            }
        }
        (x, t)
    }

    fn apply(x: &mut Vec<Vec2>, t: &mut Vec<[u32; 3]>, e: &Edits) {
        for nn in &e.new_nodes {
            let p = match *nn {
                NewNode::Copy { of } => x[of as usize],
                NewNode::OnEdge { a, b, t } => {
                    let (pa, pb) = (x[a as usize], x[b as usize]);
                    [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])]
                }
            };
            x.push(p);
        }
        for &(id, c) in &e.changed {
            t[id as usize] = c;
        }
        for &(_, c) in &e.added {
            t.push(c);
        }
    }

    fn nodes(normal: &[f64]) -> NodeFailure<'_> {
        NodeFailure { normal, cracked: &[] }
    }

    fn area(x: &[Vec2], t: &[[u32; 3]]) -> f64 {
        t.iter()
            .map(|e| 0.5 * cross(sub(x[e[1] as usize], x[e[0] as usize]), sub(x[e[2] as usize], x[e[0] as usize])))
            .sum()
    }

    #[test]
    fn vertical_crack_through_an_interior_node_along_edges() {
        let (mut x, mut t) = grid();
        let csr = node_elements(x.len(), &t);
        let active = vec![true; t.len()];
        let mut normal = vec![0.0; x.len()];
        normal[5] = 0.0; // σ1 along x: the crack runs vertically through (1, 1)
        let e =
            plan(&mut PlanScratch::default(), &t, &active, &csr, &x, &[5], &nodes(&normal), &FractureParams::default());
        assert_eq!(e.inserted_at, vec![5]);
        assert!(e.added.is_empty(), "vertical edges exist: no split");
        assert_eq!(e.new_nodes, vec![NewNode::Copy { of: 5 }]);
        let mut faces = e.crack_faces.clone();
        faces.sort();
        assert_eq!(faces, vec![[5, 1], [5, 9]]);
        let before = area(&x, &t);
        apply(&mut x, &mut t, &e);
        assert!((area(&x, &t) - before).abs() < 1e-12);
        // every element has positive area and the new node is used
        assert!(t
            .iter()
            .all(|e| cross(sub(x[e[1] as usize], x[e[0] as usize]), sub(x[e[2] as usize], x[e[0] as usize])) > 0.0));
        assert!(t.iter().any(|e| e.contains(&16)));
    }

    #[test]
    fn inclined_crack_splits_elements() {
        let (mut x, mut t) = grid();
        let csr = node_elements(x.len(), &t);
        let active = vec![true; t.len()];
        let mut normal = vec![0.0; x.len()];
        normal[5] = 20f64.to_radians(); // crack at 110°: no edge within 15°
        let e =
            plan(&mut PlanScratch::default(), &t, &active, &csr, &x, &[5], &nodes(&normal), &FractureParams::default());
        assert_eq!(e.inserted_at, vec![5]);
        assert!(!e.added.is_empty());
        let before = area(&x, &t);
        apply(&mut x, &mut t, &e);
        assert!((area(&x, &t) - before).abs() < 1e-12);
        for tri in &t {
            let [a, b, c] = tri.map(|v| x[v as usize]);
            assert!(quality(a, b, c) >= 0.2, "{tri:?}");
        }
    }

    #[test]
    fn candidates_sharing_elements_wait() {
        let (x, t) = grid();
        let csr = node_elements(x.len(), &t);
        let active = vec![true; t.len()];
        let normal = vec![0.0; x.len()];
        // nodes 5 and 6 are neighbours: only the first inserts this check,
        // and the second is reported as waiting (still due)
        let e = plan(
            &mut PlanScratch::default(),
            &t,
            &active,
            &csr,
            &x,
            &[5, 6],
            &nodes(&normal),
            &FractureParams::default(),
        );
        assert_eq!(e.inserted_at, vec![5]);
        assert_eq!(e.waiting, vec![6]);
    }

    #[test]
    fn boundary_node_cracks_inward_once() {
        let (x, t) = grid();
        let csr = node_elements(x.len(), &t);
        let active = vec![true; t.len()];
        let normal = vec![0.0; x.len()];
        // node 1 = (1, 0) on the bottom: the vertical crack goes up only
        let e =
            plan(&mut PlanScratch::default(), &t, &active, &csr, &x, &[1], &nodes(&normal), &FractureParams::default());
        assert_eq!(e.crack_faces, vec![[1, 5]]);
        assert_eq!(e.new_nodes, vec![NewNode::Copy { of: 1 }]);
    }
}
