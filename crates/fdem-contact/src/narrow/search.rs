//! The candidate search of one boundary node: which of its candidate
//! facets each of its contacts takes up. A contact keeps the facet it
//! touched last step while that still qualifies, slides on to the next
//! facet along a smooth surface, resumes after a topology change, or
//! starts on a facet it entered through the facet's line within this step
//! ([`rank`]); only facets that face the node's bearing face count; at a
//! corner a facet along the face comes before one that meets it only at
//! its end ([`lies_along`]); and among equal ranks the shallower
//! penetration wins.
//!
//! Over 800 lines with its unit tests, which build small contact scenes
//! (three bodies at a point, a sharp wedge, a corner on two faces) round
//! one rule each; the code itself is about 470.

use super::projection::{bears_past_sharp_end, corner_gap, most_opposed, node_normal, projects_inside, XI_SLACK};
use super::{ContactPartial, ContactState, NarrowInputs};
use crate::surface::MANY;
use crate::{Vec2, NONE, SMOOTH_COS};

/// Relative slack on the depth a contact that moves to another facet (or
/// resumes after a topology change) may have: its spring energy may grow by
/// at most about `2 × DEPTH_SLACK` of its value.
pub(super) const DEPTH_SLACK: f64 = 1e-3;

/// A node only touches a facet whose outward normal opposes the node's own
/// surface normal by more than this cosine (surfaces in contact face each
/// other): `n_node · n_facet < −FACING_COS`, i.e. within about 75° of
/// head-on. This keeps a node of a flat surface lying under a corner of the
/// other body from catching that body's side face.
const FACING_COS: f64 = 0.25;

/// One candidate facet of a node that passed the geometric tests.
struct Candidate {
    /// The facet.
    f: u32,
    /// Projection parameter (unclamped) and gap (m, negative inside).
    xi: f64,
    gap: f64,
    /// The facet's outward normal.
    n: Vec2,
    /// Its length (m).
    len: f64,
}

/// How a contact with memory `state` would take up candidate `c`: rank 0
/// the facet touched last step, 1 a facet next to it (sliding on along the
/// surface) or one parallel to a resumed contact's, 2 a new contact,
/// [`FOUND_INSIDE`] a facet the node already lies in deeper than entry or
/// continuity allow (taken up with its spring offset by that depth:
/// [`ContactState::offset`]; the twin of the node's bearing `face`, or of
/// any of its facets on a smooth stretch (`face` [`NONE`]), qualifies
/// whatever side is nearer). Keeping the same facet stops
/// a node near a corner of the other body from flipping between two
/// normals. A new contact must have been entered through the facet's line
/// within this step (its penetration no deeper than its normal approach): a
/// node that slides onto the end of a facet from the side would otherwise
/// start with a finite penetration, and the penalty energy ½α g² would
/// appear without work (an energy pump at every corner).
#[inline]
fn rank(inp: &NarrowInputs<'_>, node: usize, state: &ContactState, c: &Candidate, face: u32) -> Option<u8> {
    let (f, n, gap) = (c.f, c.n, c.gap);
    if f == state.facet {
        // its spring grows no faster than the node's motion allows
        // (`respond`)
        return Some(0);
    }
    // how far the node moved towards the facet this step
    let approach = || {
        let w = c.xi.clamp(0.0, 1.0);
        let [ia, ib] = inp.surface.facets[c.f as usize].nodes;
        let (v, [va, vb]) = (inp.v, [inp.v[ia as usize], inp.v[ib as usize]]);
        ((v[node][0] - (1.0 - w) * va[0] - w * vb[0]) * n[0] + (v[node][1] - (1.0 - w) * va[1] - w * vb[1]) * n[1])
            .abs()
            * inp.dt
    };
    // no deeper than the contact was, plus this step's approach and a
    // relative slack: velocities are re-interpolated at a crack insertion,
    // so the approach of the step after one is not exactly the gap's change
    // (measured: 2×10⁻⁷ m on a 0.53 mm penetration, which dropped a joint
    // contact worth 10⁴ J)
    let no_deeper = |depth: f64| gap >= -(depth * (1.0 + DEPTH_SLACK) + 2.0 * approach() + 1e-12 * c.len);
    // in every other case the node lies in the facet already: hold it
    // where it is (its spring offset by the depth), lowest in rank, if
    // this facet is where it lies inside the body: inside the facet's
    // element (the depth rectangle behind a facet reaches past the
    // triangle's sides into whatever lies beside it), nearer this facet's
    // line than the element's other sides where those are surface too (a
    // node just inside a surface side lies in that side, not metres behind
    // this facet; an interior side has rock on both sides, and near a
    // vertex the node is nearest one whichever facet it went in through),
    // and no deeper than `FOUND_INSIDE_DEPTH` of the facet's length (item
    // 7 of docs/contact.md)
    let inside = || {
        let facet = &inp.surface.facets[f as usize];
        if facet.apex == NONE || -gap > FOUND_INSIDE_DEPTH * c.len {
            return false;
        }
        let s = inp.x[node];
        let [ia, ib, ic] = [facet.nodes[0], facet.nodes[1], facet.apex];
        let [a, b, c] = [ia, ib, ic].map(|v| inp.x[v as usize]);
        // the distance of the node from the line p → q, positive on its left
        let left = |p: Vec2, q: Vec2| {
            let e = [q[0] - p[0], q[1] - p[1]];
            (e[0] * (s[1] - p[1]) - e[1] * (s[0] - p[0])) / (e[0] * e[0] + e[1] * e[1]).sqrt()
        };
        let (ab, bc, ca) = (left(a, b), left(b, c), left(c, a));
        if ab <= 0.0 || bc <= 0.0 || ca <= 0.0 {
            return false;
        }
        // whether the element's side p–q is surface: it is then the facet
        // that follows this one along the surface (from b) or precedes it
        // (into a); none or several there (`NONE`, `MANY`) count as surface
        let surface_side = |link: u32, p: u32, q: u32| match link {
            NONE | MANY => true,
            g => {
                let n = inp.surface.facets[g as usize].nodes;
                n == [p, q] || n == [q, p]
            }
        };
        // the twin of a face of the node (the other face of the same crack
        // or joint: the same reference points in reverse) is where the node
        // lies whichever side is nearer: two copies of a node at a crack's
        // mouth each lie at the other's corner, nearer its other face
        let twin = || {
            let own = if face == NONE {
                inp.surface.node_facets.row(inp.surface.index_of[node] as usize)
            } else {
                std::slice::from_ref(&face)
            };
            !inp.x_ref.is_empty()
                && own.iter().any(|&g| {
                    let [p, q] = inp.surface.facets[g as usize].nodes;
                    let r = |v: u32| inp.x_ref[v as usize];
                    r(p) == r(ib) && r(q) == r(ia)
                })
        };
        let [prev, next] = inp.surface.links[f as usize];
        ((ab <= bc || !surface_side(next, ib, ic)) && (ab <= ca || !surface_side(prev, ic, ia))) || twin()
    };
    if state.facet != NONE && inp.surface.adjacent(state.facet, f) && no_deeper(state.depth) && {
        // continuing along the surface, not turning a corner of it
        let prev = &inp.surface.facets[state.facet as usize];
        let (pa, pb) = (inp.x[prev.nodes[0] as usize], inp.x[prev.nodes[1] as usize]);
        let d = [pb[0] - pa[0], pb[1] - pa[1]];
        (d[1] * n[0] - d[0] * n[1]) >= SMOOTH_COS * (d[0] * d[0] + d[1] * d[1]).sqrt()
    } {
        Some(1)
    } else if state.resumed != NONE {
        let d = resumed_direction(inp, state.resumed);
        // a resumed contact: no deeper than it was before the topology
        // change, preferably on a facet parallel to its old one
        if !no_deeper(state.depth) {
            return inside().then_some(FOUND_INSIDE);
        }
        let [ia, ib] = inp.surface.facets[c.f as usize].nodes;
        let (a, b) = (inp.x[ia as usize], inp.x[ib as usize]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let parallel = (d[0] * e[0] + d[1] * e[1]).abs() >= SMOOTH_COS * (d[0] * d[0] + d[1] * d[1]).sqrt() * c.len;
        Some(if parallel { 1 } else { 2 })
    } else if no_deeper(0.0) {
        Some(2)
    } else {
        inside().then_some(FOUND_INSIDE)
    }
}

/// The rank of a facet a node is found in without having entered it
/// through its line nor slid onto it ([`rank`]), the node lying inside the
/// facet's element: taken up only when no other facet qualifies, with the
/// spring offset by the depth beyond the spring the node had
/// ([`ContactState::offset`]). Without it such a node was never taken up
/// and passed through the other body freely: 80 nodes of the demo lay
/// deeper than 3 cm inside other pieces at 0.8 s (docs/contact.md, item 7).
pub(super) const FOUND_INSIDE: u8 = 3;

/// The deepest a node may lie inside a facet, as a share of the facet's
/// length, to be taken up there as [`FOUND_INSIDE`]. The nodes this rank
/// is for come to lie inside by microns to millimetres (a crack's cut, a
/// contact handed on at an insertion); deeper than this the facet is not
/// where the node entered, and holding it there would also make the
/// result depend on the broad phase's margin (0.2 of the mean facet
/// length), beyond which a rebuild drops the pair.
pub(super) const FOUND_INSIDE_DEPTH: f64 = 0.01;

/// The direction `x_b − x_a` (m) of the facet `[a, b]` that was number
/// `old` before the last topology change ([`ContactState::resumed`]).
#[inline]
pub(super) fn resumed_direction(inp: &NarrowInputs<'_>, old: u32) -> Vec2 {
    let [a, b] = inp.resumed[old as usize];
    let (pa, pb) = (inp.x[a as usize], inp.x[b as usize]);
    [pb[0] - pa[0], pb[1] - pa[1]]
}

/// Per contact: (rank, facet, ξ, gap, facing, along) of the best candidate
/// so far; `along` is [`lies_along`].
pub(super) type Best = Option<(u8, u32, f64, f64, f64, bool)>;

/// Whether candidate `c` lies along a face of a corner node that runs from
/// the node in the unit direction `t` ([`face_direction`]), rather than
/// meeting the face only at the candidate's end, where the other body has a
/// corner (the candidate runs away from the face beyond the node's
/// projection, within the slack `XI_SLACK`, and its surface turns by 30° or
/// more there or stops). At a junction of joints four blocks meet at a
/// point: a corner's face is opposed along its whole length by the block
/// across the joint, and at its end only by the corner of the block
/// diagonally across. The diagonal block's facet is often the shallower
/// penetration, and a face that took it left the block across the joint
/// unopposed: two blocks of the demo passed 7.6 cm into each other that
/// way (docs/contact.md, "Which facet a node touches", item 8).
#[inline]
fn lies_along(inp: &NarrowInputs<'_>, t: Vec2, c: &Candidate) -> bool {
    let d = inp.frames[c.f as usize].t;
    // which end of the candidate the face runs towards, and the share of
    // the candidate between the node's projection and that end
    let at_end = d[0] * t[0] + d[1] * t[1] >= 0.0;
    let beyond = if at_end { 1.0 - c.xi } else { c.xi };
    if beyond > XI_SLACK {
        return true;
    }
    // the other body's surface past that end: along the face if it goes on
    // smoothly
    match inp.surface.links[c.f as usize][usize::from(at_end)] {
        NONE | MANY => false,
        k => {
            let e = inp.frames[k as usize].t;
            d[0] * e[0] + d[1] * e[1] >= SMOOTH_COS
        }
    }
}

/// The direction in which corner face `k` of a node runs away from it:
/// `faces` is `[into, from]` ([`Surface::faces`]), so the node ends the
/// first face and starts the second.
///
/// [`Surface::faces`]: crate::surface::Surface::faces
#[inline]
fn face_direction(inp: &NarrowInputs<'_>, faces: [u32; 2], k: usize) -> Vec2 {
    let t = inp.frames[faces[k] as usize].t;
    if k == 0 {
        [-t[0], -t[1]]
    } else {
        t
    }
}

/// The candidate search of one boundary node: what every candidate test
/// reads, and the search's running state.
pub(super) struct Search<'i, 'a> {
    inp: &'i NarrowInputs<'a>,
    /// Boundary index and mesh id of the node, and its position.
    b: usize,
    pub(super) node: usize,
    s: Vec2,
    /// The node's two faces at a corner ([`Surface::faces`]).
    ///
    /// [`Surface::faces`]: crate::surface::Surface::faces
    pub(super) faces: [u32; 2],
    /// Faces the node bears with: 1 on a smooth stretch (whose second
    /// contact is on a second body, [`Search::run`]), 2 at a corner.
    pub(super) slots: usize,
    pub(super) best: [Best; 2],
    /// Each contact's bearing normal, computed on first use.
    own: [Option<Vec2>; 2],
    /// Whether the node is on more than two facets (its body touches
    /// itself there): past a facet's end any face of its own that lies
    /// along the facet then slides on ([`most_opposed`]), worked out on
    /// first use.
    pinch: Option<bool>,
    /// Per contact, a facet it may take neither nor a neighbour of
    /// ([`NONE`]: none): at a smooth node each contact keeps away from the
    /// other's facet, so that the two bear on different bodies.
    apart: [u32; 2],
    /// At a smooth node without a second contact's memory: the first
    /// contact's gap (m), which a new second must be deeper than (infinite
    /// otherwise).
    deeper_than: f64,
}

impl<'i, 'a> Search<'i, 'a> {
    /// A search for boundary node `b`, nothing found yet.
    #[inline]
    pub(super) fn new(inp: &'i NarrowInputs<'a>, b: usize) -> Self {
        let node = inp.surface.nodes[b] as usize;
        let faces = inp.surface.faces[b];
        let slots = if faces[0] == NONE { 1 } else { 2 };
        Self {
            inp,
            b,
            node,
            s: inp.x[node],
            faces,
            slots,
            best: [None; 2],
            own: [None; 2],
            pinch: None,
            apart: [NONE; 2],
            deeper_than: f64::INFINITY,
        }
    }

    /// Finds each contact's best candidate. The facet a contact touched
    /// last step ranks 0 ([`rank`]) and so beats every other candidate
    /// whenever it still qualifies: it is tested first, and the others only
    /// for a contact that it no longer holds. Most contacts keep their facet
    /// step after step (a closed joint, a resting block), so most nodes in
    /// contact test one candidate instead of all of them; what is found is
    /// the same as testing all of them.
    ///
    /// A corner node's two contacts search side by side, one per face. A
    /// node on a smooth stretch bears with its whole surface: its first
    /// contact as a corner's, and a second one on another body where it
    /// lies deeper in that body than in the first contact's facet (a facet
    /// neither the first's nor next to it). Where three bodies meet, a
    /// node that held only the shallower of two went on into the other:
    /// five nodes of the demo lay 3–8 cm inside other pieces at 0.8 s that
    /// way (docs/contact.md, "Which facet a node touches", item 9). Each
    /// contact keeps away from the other's facet, so they stay on two
    /// bodies; a second contact, once made, keeps its facet like any
    /// other.
    #[inline]
    pub(super) fn run(&mut self, states: &[&mut ContactState; 2], acc: &mut ContactPartial) {
        self.run_as::<false>(states, acc);
    }

    /// [`Search::run`]; with `ALL`, testing every candidate for each
    /// contact searched (what the faster order must find; tests only).
    #[inline]
    fn run_as<const ALL: bool>(&mut self, states: &[&mut ContactState; 2], acc: &mut ContactPartial) {
        if self.slots == 2 {
            self.search::<ALL>(states, acc, [true, true]);
            return;
        }
        // (a second contact resumed after a topology change has no facet
        // yet, but a memory)
        let has_second = *states[1] != ContactState::default();
        self.apart = [states[1].facet, NONE];
        self.search::<ALL>(states, acc, [true, false]);
        match self.best[0] {
            Some((_, first, _, gap, ..)) => {
                self.apart = [NONE, first];
                if !has_second {
                    self.deeper_than = gap;
                }
            }
            // nothing the first could take: nor could a new second
            None if !has_second => return,
            None => self.apart = [NONE; 2],
        }
        self.search::<ALL>(states, acc, [false, true]);
    }

    /// The search of [`Search::run`] for the contacts flagged in `want`.
    #[inline]
    fn search<const ALL: bool>(&mut self, states: &[&mut ContactState; 2], acc: &mut ContactPartial, want: [bool; 2]) {
        let row = self.inp.candidates.row(self.b);
        if ALL {
            for &f in row {
                self.consider(f, want, states, acc);
            }
            return;
        }
        let mut open = [false; 2];
        for k in (0..2).filter(|&k| want[k]) {
            let f = states[k].facet;
            if f != NONE && row.binary_search(&f).is_ok() {
                self.consider(f, [k == 0, k == 1], states, acc);
            }
            // (a corner's facet that meets its face only at the facet's
            // end may yield to one along the face: `lies_along`)
            open[k] = !matches!(self.best[k], Some((0, .., true)));
        }
        if open.iter().any(|&o| o) {
            if row.len() > 64 {
                for &f in row {
                    self.consider(f, open, states, acc);
                }
                return;
            }
            // the projection test of every candidate first, without a
            // branch per candidate (in fractured rock which candidates pass
            // is unpredictable, and most do not), then the rest of the test
            // for those that pass, in row order: the same as testing them
            // one by one
            let frames = self.inp.frames;
            let mut passed = 0u64;
            for (i, &f) in row.iter().enumerate() {
                let frame = &frames[f as usize];
                let (xi, gap) = frame.project(self.s, frame.a);
                passed |= u64::from(projects_inside(xi, gap, frame.depth)) << i;
            }
            acc.pairs += row.len() as u64;
            while passed != 0 {
                let i = passed.trailing_zeros() as usize;
                passed &= passed - 1;
                // projected again (a few flops on a cached record) rather
                // than kept from above: a buffer per node to keep them in
                // would cost more to fill than the few that pass
                let f = row[i];
                let frame = &frames[f as usize];
                let (xi, gap) = frame.project(self.s, frame.a);
                self.consider_projected(f, xi, gap, open, states);
            }
        }
    }

    /// Tests candidate facet `f` for the contacts flagged in `open`, each
    /// against its memory in `states`, and keeps it where it is the best so
    /// far.
    #[inline]
    fn consider(&mut self, f: u32, open: [bool; 2], states: &[&mut ContactState; 2], acc: &mut ContactPartial) {
        acc.pairs += 1;
        let frame = &self.inp.frames[f as usize];
        let (xi, gap) = frame.project(self.s, frame.a);
        if !projects_inside(xi, gap, frame.depth) {
            return;
        }
        self.consider_projected(f, xi, gap, open, states);
    }

    /// The rest of [`Search::consider`], for a candidate that passed the
    /// projection test (`ξ` within the slack, `−depth ≤ gap < 0`).
    #[inline]
    fn consider_projected(&mut self, f: u32, xi: f64, gap: f64, open: [bool; 2], states: &[&mut ContactState; 2]) {
        let inp = self.inp;
        let frame = &inp.frames[f as usize];
        // Past an end of the facet (the slack that lets a node slide over a
        // vertex), at a convex corner of the other body, the facet's line
        // runs outside that body: the depth is the lesser of the two
        // facets' (the body is locally the intersection of their half
        // planes), and a node outside the next facet's line is not in
        // contact at all. Measured against the line alone, a node that has
        // just left the next facet would start with a deep penetration and
        // its spring energy would appear from nothing. Worked out only for
        // a candidate that some contact faces (most that get this far do
        // not: a facet of the node's own body across a concave corner).
        let on_facet = (0.0..=1.0).contains(&xi);
        let mut corner: Option<Option<f64>> = None;
        let mut c = Candidate { f, xi, gap, n: frame.normal(), len: frame.len };
        let (slots, b, faces) = (self.slots, self.b, self.faces);
        // a corner sharper than 2 × (90° − 75°) = 30° pressed head-on into
        // a facet: neither face opposes it within 75°, though the corner
        // does (its faces' mean normal); the face nearer to opposing it
        // bears then (item 10 of docs/contact.md: a 23° wedge's tip lost
        // its contact so and went 10 cm into the rock it pressed on)
        // (worked out only for a face that fails the usual test, once per
        // candidate)
        let n = c.n;
        let sharp_face = || {
            let [m0, m1] = [0, 1].map(|k| inp.frames[faces[k] as usize].normal());
            let (f0, f1) = (m0[0] * n[0] + m0[1] * n[1], m1[0] * n[0] + m1[1] * n[1]);
            let mean = [m0[0] + m1[0], m0[1] + m1[1]];
            let across = mean[0] * n[0] + mean[1] * n[1];
            (f0 > -FACING_COS
                && f1 > -FACING_COS
                && across < -FACING_COS * (mean[0] * mean[0] + mean[1] * mean[1]).sqrt())
            .then_some(usize::from(f1 < f0))
        };
        let mut sharp: Option<Option<usize>> = None;
        for k in (0..2).filter(|&k| open[k]) {
            let apart = self.apart[k];
            if apart != NONE && (f == apart || inp.surface.adjacent(f, apart)) {
                continue;
            }
            // the face that bears: the node's mean normal, or at a corner
            // the contact's own facet
            let m = *self.own[k].get_or_insert_with(|| {
                if slots == 1 {
                    node_normal(inp.surface, inp.frames, b)
                } else {
                    inp.frames[faces[k] as usize].normal()
                }
            });
            let facing = m[0] * c.n[0] + m[1] * c.n[1];
            // past an end of the facet (within the slack) only a face that
            // lies along it slides on: a face at an angle (the crack face at
            // a block's corner next to a separating piece's edge) would
            // touch a facet it has already passed. Where the body touches
            // itself (more than two facets) the mean points between its
            // wedges, at no face: there any face of its own that lies along
            // the facet slides on (item 11 of docs/contact.md; the facing
            // test above stays on the mean, since a crack face between the
            // wedges opposes almost any facet)
            let bears =
                facing <= -FACING_COS || (slots == 2 && on_facet && *sharp.get_or_insert_with(sharp_face) == Some(k));
            let along_past = on_facet
                || facing <= -SMOOTH_COS
                || (slots == 1
                    && *self.pinch.get_or_insert_with(|| inp.surface.node_facets.row(b).len() > 2)
                    && most_opposed(inp.surface, inp.frames, b, c.n) <= -SMOOTH_COS);
            if !bears || !along_past {
                continue;
            }
            if !on_facet {
                let g = *corner.get_or_insert_with(|| corner_gap(inp.surface, inp.frames, f, xi > 1.0, self.s));
                match g {
                    Some(g) if g >= 0.0 => return,
                    Some(g) => c.gap = gap.max(g),
                    // a sharp or inward corner (or the surface's end):
                    // the line extended bears only just past it
                    None if !bears_past_sharp_end(xi, gap, c.len) => return,
                    None => {}
                }
            }
            let gap = c.gap;
            // a smooth node's new second contact: only on a body it lies
            // deeper in than in the first's facet
            if k == 1 && slots == 1 && gap >= self.deeper_than {
                continue;
            }
            // the face the node bears with in this contact ([`NONE`] on a
            // smooth stretch)
            let Some(r) = rank(inp, self.node, &*states[k], &c, faces[k]) else { continue };
            // at a corner a facet along the face comes first, whatever its
            // rank (`lies_along`); then the lower rank; equal ranks: the
            // shallower penetration; an exact tie (a node at the vertex two
            // facets share) goes to the facet that faces the node's face
            // more squarely, so the choice is geometric, not by facet
            // index, and does not depend on the numbering
            let along = slots == 1 || lies_along(inp, face_direction(inp, faces, k), &c);
            let key = (!along, r);
            if self.best[k].is_none_or(|(rb, _, _, g, fb, ab)| {
                key < (!ab, rb) || (key == (!ab, rb) && (gap > g || (gap == g && facing < fb)))
            }) {
                self.best[k] = Some((r, f, xi, gap, facing, along));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::law::InterfaceLaw;
    use crate::narrow::evaluation::tests::{evaluate_in_place, evaluate_once};
    use crate::narrow::projection::XI_SLACK;
    use crate::narrow::{facet_frames, project, FacetFrame, NodeContact};
    use crate::surface::Surface;

    /// The corner cases' geometry: master triangle a(−1,0), b(0,0),
    /// c(1,0.3), counter-clockwise, convex at b; a slave triangle with its
    /// apex at `apex_s`. Returns positions, surface, broad phase, and the
    /// boundary index of the apex and the facets a→b and b→c.
    fn corner_case(apex_s: Vec2) -> (Vec<Vec2>, Surface, crate::BroadPhase, usize, u32, u32) {
        let x: Vec<Vec2> = vec![[-1.0, 0.0], [0.0, 0.0], [1.0, 0.3], [-0.5, -1.0], [0.5, -1.0], apex_s];
        let facets = [([0, 1], 0), ([1, 2], 0), ([2, 0], 0), ([3, 4], 0), ([4, 5], 0), ([5, 3], 0)];
        let apex = [x[2], x[0], x[1], x[5], x[3], x[4]];
        let surface = Surface::new(x.len(), &facets, &x, &apex);
        let mut broad = crate::BroadPhase::new(0.5);
        broad.build(&surface, &x);
        let node_s = surface.index_of[5] as usize;
        let facet = |nodes: [u32; 2]| surface.facets.iter().position(|f| f.nodes == nodes).unwrap() as u32;
        let (ab, bc) = (facet([0, 1]), facet([1, 2]));
        (x, surface, broad, node_s, ab, bc)
    }

    /// Runs `f` on the narrow phase's inputs for positions `x`, at rest
    /// but for node `moving` (node, velocity in m/s), unit masses, the one
    /// interface law `law` and a step of 1e-4 s.
    fn with_inputs<R>(
        x: &[Vec2],
        surface: &Surface,
        broad: &crate::BroadPhase,
        law: InterfaceLaw,
        moving: Option<(usize, Vec2)>,
        f: impl FnOnce(&NarrowInputs<'_>) -> R,
    ) -> R {
        let laws = [law];
        let (mut v, mass) = (vec![[0.0; 2]; x.len()], vec![1.0; x.len()]);
        if let Some((i, vi)) = moving {
            v[i] = vi;
        }
        let mut frames = vec![FacetFrame::default(); surface.facets.len()];
        facet_frames(surface, x, &mut frames);
        f(&NarrowInputs {
            x,
            x_ref: &[],
            v: &v,
            mass: &mass,
            surface,
            frames: &frames,
            candidates: &broad.candidates,
            laws: &laws,
            resumed: &[],
            dt: 1e-4,
        })
    }

    /// One evaluation of the corner case at `x` with the apex node last
    /// touching facet `last` 1 cm deep (deep enough that the "no deeper than
    /// before" rule lets it continue onto the neighbouring facet, so that
    /// only the corner rule can refuse): the contacts and the chunk
    /// partials. The apex is a corner node: both its contacts (one per
    /// face) are returned, each remembering `last`.
    fn evaluate_corner(
        x: &[Vec2],
        surface: &Surface,
        broad: &crate::BroadPhase,
        node_s: usize,
        last: u32,
    ) -> ([Vec<NodeContact>; 2], Vec<ContactPartial>) {
        with_inputs(x, surface, broad, InterfaceLaw::new(1e9, 1e9, 0.5, 0.0, 0.0).unwrap(), None, |inp| {
            let mut states = vec![ContactState::default(); surface.nodes.len()];
            states[node_s] = ContactState { facet: last, depth: 0.01, ..Default::default() };
            assert_ne!(surface.faces[node_s][0], NONE, "the apex is a corner");
            evaluate_once(inp, states.clone(), states)
        })
    }

    /// Two blocks pressed 1 cm into each other along the line y = 0: the
    /// lower one 4 m wide with four top facets, the upper one with its four
    /// bottom facets shifted `shift` m along x. Positions, surface and
    /// broad phase (built at these positions).
    fn pressed_blocks(shift: f64) -> (Vec<Vec2>, Surface, crate::BroadPhase) {
        let lower = [[0.0, -1.0], [4.0, -1.0], [4.0, 0.0], [3.0, 0.0], [2.0, 0.0], [1.0, 0.0], [0.0, 0.0]];
        let upper: Vec<Vec2> = [0.0, 1.0, 2.0, 3.0, 4.0]
            .iter()
            .map(|&x| [x + 0.25 + shift, -0.01])
            .chain([[4.25 + shift, 1.0], [0.25 + shift, 1.0]])
            .collect();
        blocks(&[&lower, &upper])
    }

    /// Blocks, each a counter-clockwise ring of positions (body on the
    /// left): the positions in ring order, the surface (the apex of every
    /// facet its block's centroid) and the broad phase built at them.
    fn blocks(rings: &[&[Vec2]]) -> (Vec<Vec2>, Surface, crate::BroadPhase) {
        let x: Vec<Vec2> = rings.iter().flat_map(|r| r.iter().copied()).collect();
        let mut facets = Vec::new();
        let mut apex = Vec::new();
        let mut first = 0u32;
        for ring in rings {
            let n = ring.len() as u32;
            let w = 1.0 / f64::from(n);
            let c = ring.iter().fold([0.0; 2], |c, p| [c[0] + p[0] * w, c[1] + p[1] * w]);
            for k in 0..n {
                facets.push(([first + k, first + (k + 1) % n], 0));
                apex.push(c);
            }
            first += n;
        }
        let surface = Surface::new(x.len(), &facets, &x, &apex);
        let mut broad = crate::BroadPhase::new(0.5);
        broad.build(&surface, &x);
        (x, surface, broad)
    }

    /// The search that tests a contact's last facet first finds what a
    /// test of every candidate finds, for contacts that keep their facet,
    /// that slide onto the next one and that lose theirs, at smooth and at
    /// corner nodes; and a node whose contacts all keep their facets tests
    /// one candidate per contact.
    #[test]
    fn last_facet_first_finds_what_testing_every_candidate_finds() {
        let laws = [InterfaceLaw::new(1e9, 1e9, 0.5, 0.0, 0.0).unwrap()];
        let (x0, surface, broad) = pressed_blocks(0.0);
        let nb = surface.nodes.len();
        // the upper block moving down fast enough to have entered the 1 cm
        // within one step (a new contact must come through the facet's line)
        let v: Vec<Vec2> = (0..x0.len()).map(|i| if i >= 7 { [0.0, -100.0] } else { [0.0; 2] }).collect();
        let mass = vec![1.0; x0.len()];
        let mut frames = vec![FacetFrame::default(); surface.facets.len()];
        fn inputs<'a>(
            x: &'a [Vec2],
            frames: &'a [FacetFrame],
            (v, mass, surface, broad, laws): (
                &'a [Vec2],
                &'a [f64],
                &'a Surface,
                &'a crate::BroadPhase,
                &'a [InterfaceLaw],
            ),
        ) -> NarrowInputs<'a> {
            NarrowInputs {
                x,
                x_ref: &[],
                v,
                mass,
                surface,
                frames,
                candidates: &broad.candidates,
                laws,
                resumed: &[],
                dt: 1e-4,
            }
        }
        let fixed = (&v[..], &mass[..], &surface, &broad, &laws[..]);
        // the memories of one evaluation at the start
        facet_frames(&surface, &x0, &mut frames);
        let (mut states, mut corner_states) = (vec![ContactState::default(); nb], vec![ContactState::default(); nb]);
        evaluate_in_place(&inputs(&x0, &frames, fixed), &mut states, &mut corner_states);
        let held = states.iter().chain(&corner_states).filter(|s| s.facet != NONE).count();
        assert!(held >= 8, "{held} contacts");
        let (mut kept, mut moved_on, mut lost) = (0, 0, 0);
        for shift in [0.0, -0.4, 0.4, 1.6] {
            // the upper block slid along x (the candidate lists still hold)
            let x: Vec<Vec2> =
                x0.iter().enumerate().map(|(i, p)| if i >= 7 { [p[0] + shift, p[1]] } else { *p }).collect();
            facet_frames(&surface, &x, &mut frames);
            let inp = inputs(&x, &frames, fixed);
            for b in 0..nb {
                let (mut s1, mut s2) = (states[b], corner_states[b]);
                let memories = [&mut s1, &mut s2];
                let mut acc = ContactPartial::default();
                let mut fast = Search::new(&inp, b);
                fast.run(&memories, &mut acc);
                let mut all = Search::new(&inp, b);
                all.run_as::<true>(&memories, &mut ContactPartial::default());
                assert_eq!(fast.best, all.best, "node {b}, shift {shift}");
                let rank0 = |k: usize| matches!(fast.best[k], Some((0, ..)));
                let smooth_second = memories[1].facet != NONE;
                if rank0(0) && (if fast.slots == 2 { rank0(1) } else { !smooth_second || rank0(1) }) {
                    // every contact kept its facet: one test each; a
                    // smooth node without a second contact tests every
                    // candidate for one
                    let tests = match (fast.slots, smooth_second) {
                        (2, _) | (1, true) => 2,
                        _ => 1 + inp.candidates.row(b).len(),
                    };
                    assert_eq!(acc.pairs, tests as u64, "node {b}, shift {shift}");
                    kept += 1;
                }
                for (k, m) in memories.iter().enumerate() {
                    match fast.best[k] {
                        Some((r, f, ..)) if m.facet != NONE && f != m.facet => moved_on += usize::from(r > 0),
                        None if m.facet != NONE => lost += 1,
                        _ => {}
                    }
                }
            }
        }
        assert!(kept > 0 && moved_on > 0 && lost > 0, "kept {kept}, moved on {moved_on}, lost {lost}");
    }

    /// A node that has just left a facet next to a convex corner of the
    /// other body lies inside the line of the facet before the corner
    /// (within the slack past its end) but outside the body: no contact,
    /// where the line alone would give it a 3 mm penetration out of nothing.
    #[test]
    fn no_contact_past_a_convex_corner() {
        // the slave apex s just below the facet b→c and 3 mm above the line
        // of a→b
        let (x, surface, broad, node_s, facet_ab, facet_bc) = corner_case([0.02, 0.003]);
        // the line of a→b alone says: inside, past its end
        let (xi, gap, ..) = project(x[5], x[0], x[1]);
        assert!(xi > 1.0 && xi < 1.0 + XI_SLACK && gap < -0.002, "xi {xi}, gap {gap}");
        assert!(broad.candidates.row(node_s).contains(&facet_ab));
        // it was touching b→c last step, so a→b would rank as its continuation
        let (out, _) = evaluate_corner(&x, &surface, &broad, node_s, facet_bc);
        for o in &out {
            assert_eq!(o[node_s].facet, NONE);
            assert_eq!(o[node_s].normal_force, 0.0);
        }
        // 1 cm higher it is inside both lines: the depth is the lesser one
        let mut x2 = x.clone();
        x2[5] = [0.02, 0.013];
        let (out, _) = evaluate_corner(&x2, &surface, &broad, node_s, facet_bc);
        let depth_bc = project(x2[5], x[1], x[2]).1;
        assert!(depth_bc < 0.0 && depth_bc > -0.013);
        // the face that looks at b→c bears on it; the other face, if it
        // bears on a→b past its end, is as deep as the lesser line too
        assert!(out.iter().any(|o| o[node_s].facet == facet_bc));
        for o in out.iter().filter(|o| o[node_s].facet != NONE) {
            assert!((o[node_s].gap - depth_bc).abs() < 1e-15, "{:?}", o[node_s]);
        }
    }

    /// The mirror case, before the start of a facet: a node that has just
    /// left facet a→b past the convex corner b lies inside the backward
    /// extension of b→c but outside the body. Measured on the block-caving
    /// case: such a node at a crack mouth was given 1.2 mm of penetration
    /// (2.8×10⁴ J of spring energy from nothing in one step).
    #[test]
    fn no_contact_before_a_convex_corner() {
        // the slave apex s is 3 mm below a→b, left of b, and inside the line
        // of b→c (which passes 6 mm lower)
        let (x, surface, broad, node_s, facet_ab, facet_bc) = corner_case([-0.02, -0.003]);
        let (xi, gap, ..) = project(x[5], x[1], x[2]);
        assert!(xi < 0.0 && xi > -XI_SLACK && gap < -0.002, "xi {xi}, gap {gap}");
        assert!(broad.candidates.row(node_s).contains(&facet_bc));
        let (out, partials) = evaluate_corner(&x, &surface, &broad, node_s, facet_ab);
        assert!(out.iter().all(|o| o[node_s].facet == NONE));
        assert_eq!(partials.iter().map(|p| p.stored).sum::<f64>(), 0.0);
    }

    /// Item 6 of docs/contact.md, past a sharp corner: block Q, the unit
    /// square under y = 0, has a 90° corner at the origin; block P's lower
    /// left corner N, 0.1 mm into Q's top line, bore on Q's top facet last
    /// step. Sheared a micron past Q's corner, N still bears there with
    /// the whole spring `k ℓ × 0.1 mm` (ℓ = 0.5 m, half of N's 1 m bottom
    /// face; closed form to 1e-9); 2 cm past it (more than
    /// `SHARP_PAST_LENGTH × 1 m + SHARP_PAST_DEPTH × 0.1 mm` = 1.2 mm) it
    /// lies over nothing of Q and bears on nothing: with the whole slack
    /// (5 cm here) it was held by Q's top line extended.
    #[test]
    fn a_corner_bears_on_a_facet_past_a_sharp_end_only_just_past_it() {
        use super::super::projection::{SHARP_PAST_DEPTH, SHARP_PAST_LENGTH};
        let (k, g) = (1e9, 1e-4);
        let run = |past: f64| {
            let q: [Vec2; 4] = [[0.0, -1.0], [1.0, -1.0], [1.0, 0.0], [0.0, 0.0]];
            let p: [Vec2; 4] = [[-past, -g], [1.0 - past, -g], [1.0 - past, 1.0 - g], [-past, 1.0 - g]];
            let (x, surface, broad) = blocks(&[&q, &p]);
            let n = surface.index_of[4] as usize;
            let top = surface.facets.iter().position(|f| f.nodes == [2, 3]).unwrap() as u32;
            let (xi, gap, ..) = project(x[4], x[2], x[3]);
            assert!(xi > 1.0 && xi < 1.0 + XI_SLACK && (gap + g).abs() < 1e-12, "xi {xi}, gap {gap}");
            assert!(broad.candidates.row(n).contains(&top));
            let law = InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap();
            let (out, _) = with_inputs(&x, &surface, &broad, law, None, |inp| {
                let mut states = vec![ContactState::default(); surface.nodes.len()];
                states[n] = ContactState { facet: top, depth: g, ..Default::default() };
                evaluate_once(inp, states.clone(), states)
            });
            (out[0][n], out[1][n], top)
        };
        let (a, b, top) = run(1e-6);
        let held = [a, b].into_iter().find(|c| c.facet == top).expect("a micron past: held");
        let expected = k * 0.5 * g;
        assert!((held.normal_force - expected).abs() < 1e-9 * expected, "{held:?}, expected {expected}");
        let limit = SHARP_PAST_LENGTH * 1.0 + SHARP_PAST_DEPTH * g;
        assert!(0.02 > limit && 0.02 < XI_SLACK);
        let (a, b, _) = run(0.02);
        assert!(a.facet == NONE && b.facet == NONE, "2 cm past: {a:?} {b:?}");
    }

    /// Body A, the triangle (0,0), (1,0), (0.5,1), and body B, a triangle
    /// whose apex `apex_s` points up at A's base from B's base, 0.4 m wide
    /// at y = −0.3 m under it: positions, surface (with apexes), broad phase, the
    /// boundary index of B's apex and the facet of A's base.
    fn apex_under_base(apex_s: Vec2) -> (Vec<Vec2>, Surface, crate::BroadPhase, usize, u32) {
        let [ax, ay] = apex_s;
        let x: Vec<Vec2> = vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0], [ax, ay], [ax - 0.2, -0.3], [ax + 0.2, -0.3]];
        let facets = [([0, 1], 0), ([1, 2], 0), ([2, 0], 0), ([3, 4], 0), ([4, 5], 0), ([5, 3], 0)];
        let apex = [x[2], x[0], x[1], x[5], x[3], x[4]];
        let mut surface = Surface::new(x.len(), &facets, &x, &apex);
        // each facet's third node: keys are positions in `facets`
        surface.set_apexes(|key| [2, 0, 1, 5, 3, 4][key as usize]);
        let mut broad = crate::BroadPhase::new(0.5);
        broad.build(&surface, &x);
        let s = surface.index_of[3] as usize;
        let base = surface.facets.iter().position(|f| f.nodes == [0, 1]).unwrap() as u32;
        (x, surface, broad, s, base)
    }

    /// One evaluation of the two bodies at positions `x`, at rest but for
    /// B's apex moving up at `speed` (m/s), with one law of stiffness `k`
    /// (N/m²): the apex's two contacts and the energy the springs hold.
    #[allow(clippy::too_many_arguments)]
    fn evaluate_apex(
        x: &[Vec2],
        speed: f64,
        surface: &Surface,
        broad: &crate::BroadPhase,
        k: f64,
        states: &mut [ContactState],
        corner_states: &mut [ContactState],
        s: usize,
    ) -> ([NodeContact; 2], f64) {
        with_inputs(
            x,
            surface,
            broad,
            InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap(),
            Some((3, [0.0, speed])),
            |inp| {
                let ([out, corner_out], partials) = evaluate_in_place(inp, states, corner_states);
                ([out[s], corner_out[s]], partials.iter().map(|p| p.stored).sum())
            },
        )
    }

    /// A node found 1 mm inside a facet without having entered it through
    /// its line (no memory, at rest) is taken up where it is: its spring
    /// is offset by that depth, so it starts with no force and no energy.
    /// Pressed 0.2 mm deeper it carries `k ℓ × 0.2 mm`; backed out to 0.5
    /// mm it carries nothing and the offset follows it (0.5 mm); pressed to
    /// 0.6 mm it carries `k ℓ × 0.1 mm`. `ℓ` is the tributary length of the
    /// node's two faces on the facet, each half face projected on it: 0.1
    /// m each (closed form; 1e-9 relative). Before, such a node was never
    /// taken up and went on through the other body without force.
    #[test]
    fn a_node_found_inside_is_held_where_it_is_without_energy_from_nothing() {
        let k = 1e9;
        // B's apex 1 mm up into A's base, then moved as the test says
        let (x0, surface, broad, s, base) = apex_under_base([0.5, 0.001]);
        let at = |depth: f64| -> Vec<Vec2> {
            let mut x = x0.clone();
            x[3] = [0.5, depth];
            x
        };
        let nb = surface.nodes.len();
        let (mut states, mut corner_states) = (vec![ContactState::default(); nb], vec![ContactState::default(); nb]);
        // moved from `last` to `depth` within the step (1e-4 s)
        let mut last = 0.001;
        let mut step = |depth: f64| {
            let speed = (depth - last) / 1e-4;
            last = depth;
            let (contacts, stored) =
                evaluate_apex(&at(depth), speed, &surface, &broad, k, &mut states, &mut corner_states, s);
            assert!(contacts.iter().all(|c| c.facet == base), "{contacts:?}");
            let force: f64 = contacts.iter().map(|c| c.normal_force).sum();
            (force, stored, [states[s].offset, corner_states[s].offset])
        };
        let (force, stored, offsets) = step(0.001);
        assert_eq!((force, stored), (0.0, 0.0));
        assert!(offsets.iter().all(|&d| (d - 0.001).abs() < 1e-15), "{offsets:?}");
        let length = |depth: f64| f64::hypot(0.2, 0.3 + depth);
        for (depth, offset) in [(0.0012, 0.001), (0.0005, 0.0005), (0.0006, 0.0005)] {
            let ell = 2.0 * 0.5 * length(0.001) * 0.2 / length(depth);
            let (force, stored, offsets) = step(depth);
            let loaded = depth - offset;
            assert!((force - k * ell * loaded).abs() <= 1e-9 * k * ell * 1e-4, "depth {depth}: {force}");
            assert!((stored - 0.5 * k * ell * loaded * loaded).abs() <= 1e-9 * 0.5 * k * ell * 1e-8, "{stored}");
            assert!(offsets.iter().all(|&d| (d - offset).abs() < 1e-15), "depth {depth}: {offsets:?}");
        }
    }

    /// A contact that is suddenly deeper in its facet than its motion this
    /// step allows keeps the spring it had, not the depth: B's apex, at
    /// rest, in contact 0.1 mm deep with A's base, is found 5 mm deep the
    /// next step (a jump no velocity explains, as when the rule for the
    /// gap past a facet's end switches). It carries `kℓ × 0.1 mm` (and the
    /// 0.1% relative slack a contact may deepen by), with ℓ
    /// its two half faces projected on the base (closed form, 1e-9), not
    /// `kℓ × 5 mm`: before, the facet it touched last step was kept
    /// whatever the depth, and 4.7 MJ appeared in one step of the
    /// paper-scale run that way.
    #[test]
    fn a_contact_does_not_jump_deeper_than_its_motion() {
        let k = 1e9;
        let (x0, surface, broad, s, base) = apex_under_base([0.5, 1e-4]);
        let nb = surface.nodes.len();
        let held = ContactState { facet: base, depth: 1e-4, ..Default::default() };
        let (mut states, mut corner_states) = (vec![ContactState::default(); nb], vec![ContactState::default(); nb]);
        (states[s], corner_states[s]) = (held, held);
        let mut x = x0.clone();
        x[3] = [0.5, 0.005];
        let (contacts, stored) = evaluate_apex(&x, 0.0, &surface, &broad, k, &mut states, &mut corner_states, s);
        assert!(contacts.iter().all(|c| c.facet == base), "{contacts:?}");
        let length = |depth: f64| f64::hypot(0.2, 0.3 + depth);
        let ell = 2.0 * 0.5 * length(1e-4) * 0.2 / length(0.005);
        // the spring it had and the relative slack a contact may deepen by
        let loaded = 1e-4 * (1.0 + DEPTH_SLACK) + 1e-12;
        let force: f64 = contacts.iter().map(|c| c.normal_force).sum();
        assert!((force - k * ell * loaded).abs() <= 1e-9 * k * ell * loaded, "{force} against {}", k * ell * loaded);
        assert!((stored - 0.5 * k * ell * loaded * loaded).abs() <= 1e-9 * 0.5 * k * ell * loaded * loaded, "{stored}");
    }

    /// Where a node found inside a facet is taken up there. Body A is the
    /// triangle (0,0), (1,0), (0.5,1); body B's apex, at rest and without
    /// memory, lies behind A's base facet (its depth limit is 0.5 m), 5 mm
    /// deep unless said: (0.5, 0.005), well inside A: held. (0.001, 0.005):
    /// projecting onto the base but 1.5 mm left of A's side (x = 0.0025 at
    /// that height), so not in A at all: not held (by the depth rectangle
    /// alone it was; in the quick caving case nodes were "found" up to 1.5 m
    /// behind 4 m facets that way). (0.004, 0.005): inside A, but 1.3 mm
    /// from its side and 5 mm from its base, so it lies in the side, not in
    /// the base: not held there (it had been, 1.4 m behind a 4 m facet, in
    /// the caving case). (0.5, 0.02): 2% of the base's length deep, beyond
    /// `FOUND_INSIDE_DEPTH`: not held.
    #[test]
    fn a_node_is_found_inside_a_facet_only_where_it_lies_in_its_body_through_it() {
        let held = |apex_s: Vec2| -> bool {
            let (x, surface, broad, s, base) = apex_under_base(apex_s);
            assert!(broad.candidates.row(s).contains(&base), "the base facet is a candidate");
            let nb = surface.nodes.len();
            let (mut states, mut corner_states) =
                (vec![ContactState::default(); nb], vec![ContactState::default(); nb]);
            let (contacts, _) = evaluate_apex(&x, 0.0, &surface, &broad, 1e9, &mut states, &mut corner_states, s);
            contacts.iter().any(|c| c.facet == base)
        };
        assert!(held([0.5, 0.005]), "well inside A, 5 mm behind its base");
        assert!(!held([0.001, 0.005]), "beside A's side");
        assert!(!held([0.004, 0.005]), "nearer A's side than its base");
        assert!(!held([0.5, 0.02]), "deeper than FOUND_INSIDE_DEPTH");
    }

    /// Item 7's take-up in a scene of triangles: bodies from `facets` at
    /// `x` (each facet's element's third node in `apex_nodes`), no memory,
    /// reference positions `x_ref`. The normal force (N/m) of mesh node
    /// `node`'s contact on the facet `[a, b]`, `None` without one.
    fn found_on(
        x: &[Vec2],
        facets: &[([u32; 2], u16)],
        apex_nodes: &[u32],
        x_ref: &[Vec2],
        node: u32,
        on: [u32; 2],
    ) -> Option<f64> {
        let apex: Vec<Vec2> = apex_nodes.iter().map(|&n| x[n as usize]).collect();
        let mut surface = Surface::new(x.len(), facets, x, &apex);
        surface.set_apexes(|key| apex_nodes[key as usize]);
        let mut broad = crate::BroadPhase::new(0.5);
        broad.build(&surface, x);
        let b = surface.index_of[node as usize] as usize;
        let facet = surface.facets.iter().position(|f| f.nodes == on).unwrap() as u32;
        let nb = surface.nodes.len();
        let law = InterfaceLaw::new(1e9, 1e9, 0.0, 0.0, 0.0).unwrap();
        let (out, _) = with_inputs(x, &surface, &broad, law, None, |inp| {
            let inp = NarrowInputs { x_ref, ..*inp };
            evaluate_once(&inp, vec![ContactState::default(); nb], vec![ContactState::default(); nb])
        });
        [out[0][b], out[1][b]].into_iter().find(|c| c.facet == facet).map(|c| c.normal_force)
    }

    /// Item 7 where the element's nearer side is interior: body A is the
    /// unit square split along its diagonal (0,0)–(1,1) into two elements,
    /// and B's apex lies 5 mm behind A's base, 8 mm from A's corner, in the
    /// element under the diagonal: 2.1 mm from the diagonal, nearer than the
    /// base. The diagonal is rock on both sides, so the apex is held on the
    /// base (no force where found, the spring offset by the 5 mm; closed
    /// form to 1e-12). The same apex 2 mm from A's right side instead (a
    /// surface side of the same element, nearer than the base) is not.
    #[test]
    fn a_node_found_inside_by_an_interior_side_is_held_on_the_facet_behind_it() {
        let held = |s: Vec2| {
            let x = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], s, [s[0] - 0.2, -0.3], [s[0] + 0.2, -0.3]];
            // A: base and right side in the element under the diagonal
            // (third node (1,1) and (0,0)), top and left side in the other
            // ((0,0) and (1,1)); B: one triangle
            let facets = [([0, 1], 0), ([1, 2], 0), ([2, 3], 0), ([3, 0], 0), ([4, 5], 0), ([5, 6], 0), ([6, 4], 0)];
            found_on(&x, &facets, &[2, 0, 0, 2, 6, 4, 5], &[], 4, [0, 1])
        };
        let force = held([0.008, 0.005]).expect("nearer the interior diagonal than the base: held on the base");
        assert!(force.abs() < 1e-12, "found inside: no force, {force}");
        // by the right side, 2 mm away: that side is where it lies, not 5 mm
        // behind the base
        assert!(held([0.998, 0.005]).is_none(), "nearer A's right side than its base");
    }

    /// Item 7 for the twin of a face: body A is the triangle V (0,0), P1
    /// (1,0), P2 (0,1), its sides at V both surface; body B's corner N lies
    /// inside A by V, 1.5 mm behind A's base and 1 mm from A's left side,
    /// its face Q1 → N along A's base and opposing it, its other face
    /// running down to the left (facing away from A's left side). N is
    /// nearer A's left side, which its faces do not oppose, so it is found
    /// in no facet of A; but where B's face Q1 → N and A's base V → P1 are
    /// the two faces of one crack (N and V, Q1 and P1 at the same reference
    /// points), N lies behind its twin: held on the base with no force
    /// (its spring offset by the 1.5 mm; closed form to 1e-12).
    #[test]
    fn a_node_found_inside_behind_the_twin_of_its_face_is_held_there() {
        let s: Vec2 = [0.001, 0.0015];
        let x = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [s[0] + 1.0, s[1]], s, [s[0] - 1.0, s[1] - 1.0]];
        let facets = [([0, 1], 0), ([1, 2], 0), ([2, 0], 0), ([3, 4], 0), ([4, 5], 0), ([5, 3], 0)];
        let held = |x_ref: &[Vec2]| found_on(&x, &facets, &[2, 0, 1, 5, 3, 4], x_ref, 4, [0, 1]);
        let (a, p1, p2) = ([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]);
        let twins = [a, p1, p2, p1, a, [-1.0, -1.0]];
        let force = held(&twins).expect("behind the twin of its face: held on it");
        assert!(force.abs() < 1e-12, "found inside: no force, {force}");
        // two faces that were never one: not held
        let apart = [a, p1, p2, [1.0, 0.5], [0.0, 0.5], [-1.0, -0.5]];
        assert!(held(&apart).is_none(), "not a twin, nearer A's left side");
        assert!(held(&[]).is_none(), "no reference positions");
    }

    /// Item 9 of docs/contact.md: a node on a smooth stretch that lies in
    /// two bodies bears on both. Body C's bottom is two collinear facets
    /// meeting at node N (a smooth node) at x = 0; under N, block A (x ≤
    /// 0.001) and block B (x ≥ −0.001) overlap by 2 mm, B's top 1 mm
    /// higher than A's. N, moving down at 20 m/s (a step of 1e-4 s), has entered A by 0.5
    /// mm and B by 1.5 mm within the step (both through the facets'
    /// lines). Last step N held a contact on A's top (rank 0), so the
    /// first contact stays there; the second goes to B's top, the
    /// deeper, with the full spring `k ℓ × 1.5 mm` (ℓ = 0.5 m, half of
    /// each of N's two 0.5 m facets; closed form to 1e-9). Before, N held
    /// A alone and went on into B. A node pressed into A alone (B lower)
    /// has one contact.
    #[test]
    fn a_smooth_node_in_two_bodies_bears_on_both() {
        let k = 1e9;
        let run = |b_top: f64| {
            let body_c: [Vec2; 4] = [[-0.5, -0.0005], [0.0, -0.0005], [0.5, -0.0005], [0.0, 1.0]];
            let block_a: [Vec2; 4] = [[-1.0, -1.0], [0.001, -1.0], [0.001, 0.0], [-1.0, 0.0]];
            let block_b: [Vec2; 4] = [[-0.001, -1.0], [1.0, -1.0], [1.0, b_top], [-0.001, b_top]];
            let (x, surface, broad) = blocks(&[&body_c, &block_a, &block_b]);
            let node = 1; // N
            let b = surface.index_of[node] as usize;
            assert_eq!(surface.faces[b][0], NONE, "N is a smooth node");
            let facet = |p: Vec2, q: Vec2| {
                let at = |v: Vec2| x.iter().position(|&w| w == v).unwrap() as u32;
                surface.facets.iter().position(|f| f.nodes == [at(p), at(q)]).unwrap() as u32
            };
            let (top_a, top_b) = (facet([0.001, 0.0], [-1.0, 0.0]), facet([1.0, b_top], [-0.001, b_top]));
            // N moving down at 20 m/s (the facets' ends at rest)
            let law = InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap();
            let (out, _) = with_inputs(&x, &surface, &broad, law, Some((node, [0.0, -20.0])), |inp| {
                let nb = surface.nodes.len();
                let mut states = vec![ContactState::default(); nb];
                states[b] = ContactState { facet: top_a, depth: 0.0001, ..Default::default() };
                evaluate_once(inp, states, vec![ContactState::default(); nb])
            });
            (out[0][b], out[1][b], top_a, top_b)
        };
        let (first, second, top_a, top_b) = run(0.001);
        assert_eq!(first.facet, top_a, "{first:?}");
        assert_eq!(second.facet, top_b, "{second:?}");
        let expected = k * 0.5 * 0.0015;
        assert!((second.gap + 0.0015).abs() < 1e-12, "{second:?}");
        assert!((second.normal_force - expected).abs() < 1e-9 * expected, "{second:?}, expected {expected}");
        assert!((first.normal_force - k * 0.5 * 0.0005).abs() < 1e-9 * expected, "{first:?}");
        // B's top 1 mm below A's: N is in A alone
        let (first, second, top_a, _) = run(-0.001);
        assert_eq!(first.facet, top_a);
        assert_eq!(second.facet, NONE, "{second:?}");
    }

    /// Item 11 of docs/contact.md: a node where its body touches itself
    /// (two triangles of one piece meeting at it, four facets) held on a
    /// crack face a hair past the face's end, at a slightly concave vertex
    /// of the other piece, as traced in the quick caving case. The mean of
    /// its four facets' normals is 39° off the face's (within item 1's 75°,
    /// beyond the 30° past an end allows), and the next face is deeper
    /// than the contact was, so it lost the contact and sank. Its west face
    /// lies along the face and now slides on: held on the face at its
    /// depth, `α = k ℓ` with `ℓ` at least the west face's half.
    #[test]
    fn a_node_where_its_body_touches_itself_slides_past_an_end_on_a_face_along_the_facet() {
        let (k, depth, past) = (1e9, 1.2e-4, 1e-4);
        // the other piece, west of x = 0: the face A up to the vertex at
        // the origin, then B turning 1.7° to the right (a concave vertex)
        let west: [Vec2; 5] = [[-2.0, -1.0], [0.0, -1.0], [0.0, 0.0], [0.03, 1.0], [-2.0, 1.0]];
        // the pinched node P (index 5) 0.12 mm inside, 0.1 mm past A's end;
        // triangles (P, 6, 7) and (P, 8, 9), 6 and 9 copies at one point
        let p: Vec2 = [-depth, past];
        let x: Vec<Vec2> =
            west.iter().copied().chain([p, [1.0, 0.4], [-depth, 1.0], [1.0, -0.2], [1.0, 0.4]]).collect();
        let mut facets: Vec<([u32; 2], u16)> = (0..5).map(|i| ([i, (i + 1) % 5], 0)).collect();
        facets.extend([([5, 6], 0), ([6, 7], 0), ([7, 5], 0), ([5, 8], 0), ([8, 9], 0), ([9, 5], 0)]);
        let apex = vec![[-1.0, 0.0]; facets.len()];
        let surface = Surface::new(x.len(), &facets, &x, &apex);
        let mut broad = crate::BroadPhase::new(0.5);
        broad.build(&surface, &x);
        let b = surface.index_of[5] as usize;
        assert_eq!((surface.node_facets.row(b).len(), surface.faces[b]), (4, [NONE; 2]));
        let facet = |nodes: [u32; 2]| surface.facets.iter().position(|f| f.nodes == nodes).unwrap() as u32;
        let (face_a, face_b) = (facet([1, 2]), facet([2, 3]));
        let law = InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap();
        let out = with_inputs(&x, &surface, &broad, law, None, |inp| {
            // the case: past A's end the mean normal is more than 30° off,
            // and B lies deeper than the contact on A was
            let n_a = inp.frames[face_a as usize].normal();
            let mean = node_normal(&surface, inp.frames, b);
            assert!(mean[0] * n_a[0] + mean[1] * n_a[1] > -SMOOTH_COS, "{mean:?}");
            let (xi, gap) = inp.frames[face_a as usize].project(p, x[1]);
            assert!(xi > 1.0 && (gap + depth).abs() < 1e-15, "{xi} {gap}");
            assert!(inp.frames[face_b as usize].project(p, x[2]).1 < -depth * (1.0 + 10.0 * DEPTH_SLACK));
            let nb = surface.nodes.len();
            let mut states = vec![ContactState::default(); nb];
            states[b] = ContactState { facet: face_a, depth, ..Default::default() };
            evaluate_once(inp, states, vec![ContactState::default(); nb]).0
        });
        let held = out[0][b];
        assert_eq!(held.facet, face_a, "{held:?}");
        assert!((held.gap + depth).abs() < 1e-15, "{held:?}");
        let ell = held.normal_force / (k * depth);
        let all: f64 = surface.node_facets.row(b).iter().map(|&f| 0.5 * surface.facets[f as usize].length).sum();
        let west = 0.5 * (1.0 - past);
        assert!((west..=all).contains(&ell), "tributary {ell}: at least {west}, at most {all}");
    }

    /// Item 10 of docs/contact.md: the tip of a 20° wedge pressed head-on
    /// into a flat face. Each of its faces is 80° from opposing the face,
    /// beyond item 1's 75°, so neither took it up and the tip went on into
    /// the rock (10 cm in the demo). Now the face nearer to opposing it
    /// bears, with its half projected on the facet: `ℓ = ½ L |m·n| = w/2`
    /// for a wedge of half-width `w` at its base; moved 1 mm in within the
    /// step, the tip carries `k (w/2) × 1 mm` (closed form to 1e-9).
    /// Turned by 30°, one face opposes the facet within 75° and bears by
    /// item 1 as before: `ℓ = ½ L cos 50°`.
    #[test]
    fn a_sharp_corner_pressed_head_on_bears_on_the_face() {
        let (k, delta, half_width) = (1e9, 1e-3, (10f64).to_radians().tan());
        let run = |tilt: f64| {
            // the wedge, its tip at the origin pointing down, turned by
            // `tilt` about the tip, then pushed δ down
            let (sn, cs) = tilt.sin_cos();
            let turn = |p: Vec2| [cs * p[0] - sn * p[1], sn * p[0] + cs * p[1] - delta];
            let wedge: [Vec2; 3] = [[0.0, 0.0], [half_width, 1.0], [-half_width, 1.0]].map(turn);
            let block: [Vec2; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 0.0], [-1.0, 0.0]];
            let (x, surface, broad) = blocks(&[&wedge, &block]);
            let b = surface.index_of[0] as usize;
            assert_ne!(surface.faces[b][0], NONE, "the tip is a corner");
            let top = surface.facets.iter().position(|f| f.nodes == [5, 6]).unwrap() as u32;
            let law = InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap();
            with_inputs(&x, &surface, &broad, law, Some((0, [0.0, -20.0])), |inp| {
                let none = vec![ContactState::default(); surface.nodes.len()];
                let (out, _) = evaluate_once(inp, none.clone(), none);
                let held: Vec<NodeContact> = [out[0][b], out[1][b]].into_iter().filter(|c| c.facet != NONE).collect();
                assert!(held.iter().all(|c| c.facet == top), "{held:?}");
                held
            })
        };
        let held = run(0.0);
        assert_eq!(held.len(), 1, "{held:?}");
        let expected = k * 0.5 * half_width * delta;
        assert!((held[0].normal_force - expected).abs() < 1e-9 * expected, "{:?}, expected {expected}", held[0]);
        let held = run(30f64.to_radians());
        assert_eq!(held.len(), 1, "{held:?}");
        let face = f64::hypot(half_width, 1.0);
        let expected = k * 0.5 * face * 50f64.to_radians().cos() * delta;
        assert!((held[0].normal_force - expected).abs() < 1e-9 * expected, "{:?}, expected {expected}", held[0]);
    }

    /// Item 8 of docs/contact.md: at a junction of joints a block's corner
    /// face bears on the block across the joint, which lies along it, not
    /// on the block diagonally across, whose corner it meets only at that
    /// facet's end, even where that one is the shallower penetration. Four
    /// unit blocks meet at the origin; the upper right one's corner,
    /// moving left, has gone 0.5 mm into the lower left block's side at its
    /// top end and 1.5 mm into the upper left block's side, whose corner
    /// lies 2 mm lower. Taking the shallower one left the upper two blocks
    /// to pass into each other (7.6 cm in the demo).
    #[test]
    fn a_corner_bears_on_the_face_along_it_not_on_a_corner_it_meets() {
        let upper_left: [Vec2; 4] = [[-1.0, -0.002], [0.001, -0.002], [0.001, 1.0], [-1.0, 1.0]];
        let lower_left: [Vec2; 4] = [[-1.0, -1.0], [0.0, -1.0], [0.0, 0.0], [-1.0, 0.0]];
        let corner = [-0.0005, -0.0005];
        let upper_right: [Vec2; 4] = [corner, [1.0, -0.0005], [1.0, 1.0], [-0.0005, 1.0]];
        let (x, surface, broad) = blocks(&[&upper_left, &lower_left, &upper_right]);
        let facet = |a: Vec2, b: Vec2| {
            let at = |p: Vec2| x.iter().position(|&q| q == p).unwrap() as u32;
            surface.facets.iter().position(|f| f.nodes == [at(a), at(b)]).unwrap() as u32
        };
        let (across, diagonal) = (facet([0.001, -0.002], [0.001, 1.0]), facet([0.0, -1.0], [0.0, 0.0]));
        let node = 8; // the upper right block's corner
        let b = surface.index_of[node] as usize;
        let left_face = facet([-0.0005, 1.0], corner);
        assert_eq!(surface.faces[b][0], left_face, "a corner; its first face the left one");
        // moving left at 20 m/s: both depths entered within the step
        let law = InterfaceLaw::new(1e9, 1e9, 0.5, 0.0, 0.0).unwrap();
        let found = with_inputs(&x, &surface, &broad, law, Some((node, [-20.0, 0.0])), |inp| {
            let none = vec![ContactState::default(); surface.nodes.len()];
            let (out, _) = evaluate_once(inp, none.clone(), none);
            (out[0][b].facet, out[0][b].gap)
        });
        assert_eq!(found.0, across, "the left face bears on the block across the joint, not {diagonal}");
        assert!((found.1 + 0.0015).abs() < 1e-12, "at its depth there: {}", found.1);
    }
}
