//! Narrow phase: node-to-segment penalty contact (paper 2.1, eqs. 2.3–2.7)
//! with Coulomb friction and cohesion (appendix D) and a compression-only
//! normal dashpot.

use rayon::prelude::*;

use fdem_mesh::Csr;

use crate::law::{friction_update, InterfaceLaw};
use crate::surface::Surface;
use crate::{Vec2, CHUNK, NONE, SMOOTH_COS};

/// Slack on the projection parameter `ξ` (fraction of the facet): a node a
/// little past the end of a surface still bears on its last facet (its
/// projection clamped to the end). Without it, the end nodes of a joint
/// whose two sides drift apart by round-off-sized shear (a micron) drop out
/// of contact and the rock beside the joint's end carries nothing.
/// The broad phase pads every facet box by this much of its length too, so
/// that the whole region where the narrow phase accepts a contact is listed.
pub(crate) const XI_SLACK: f64 = 0.05;

/// Relative slack on the depth a contact that moves to another facet (or
/// resumes after a topology change) may have: its spring energy may grow by
/// at most about `2 × DEPTH_SLACK` of its value.
const DEPTH_SLACK: f64 = 1e-3;

/// A node only touches a facet whose outward normal opposes the node's own
/// surface normal by more than this cosine (surfaces in contact face each
/// other): `n_node · n_facet < −FACING_COS`, i.e. within about 75° of
/// head-on. This keeps a node of a flat surface lying under a corner of the
/// other body from catching that body's side face.
const FACING_COS: f64 = 0.25;

/// What a boundary node remembers between steps. 24 bytes: it is read and
/// written for every contact in every step (with the resumed direction in
/// the record, 48 bytes, a late step of the paper-scale caving run took
/// about 3% longer; docs/contact.md).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(from = "SavedState", into = "SavedState")]
pub struct ContactState {
    /// The facet it touched last step, or [`NONE`].
    pub facet: u32,
    /// Set when a topology change (a crack, an excavation) took away the
    /// facet this node was pressing on, or created the node as a copy of
    /// one that was: that facet's index before the change (its nodes are in
    /// [`NarrowInputs::resumed`]), whose direction `b − a` is the one
    /// `elastic_gap` is measured along; [`NONE`] otherwise. The next
    /// evaluation may then take up a contact that is already penetrated
    /// (its spring energy was counted before the change, so no energy
    /// appears), once; without this rule a new contact must be entered
    /// through the facet's line (no energy pump at corners) and every joint
    /// spring cut by a crack would vanish. The evaluation that follows
    /// every topology change clears it.
    pub resumed: u32,
    /// Elastic tangential gap `g_tᵉ` (m), carried over to an adjacent facet.
    pub elastic_gap: f64,
    /// The penetration (m, ≥ 0) at the last evaluation (for a resumed
    /// contact: before the topology change). A contact that moves to
    /// another facet, other than by entering it through its line, may be no
    /// deeper than this plus the step's approach: its spring energy would
    /// otherwise jump without work.
    pub depth: f64,
}

impl Default for ContactState {
    fn default() -> Self {
        Self { facet: NONE, resumed: NONE, elastic_gap: 0.0, depth: 0.0 }
    }
}

/// A [`ContactState`] as checkpoints hold it (formats 1–6), with the
/// resumed facet's direction in the record. A checkpoint is written between
/// steps, after the evaluation that clears every resumed mark, so a file
/// always holds `None` there (and one that held a direction would restore
/// it as an ordinary memory).
#[derive(serde::Serialize, serde::Deserialize)]
struct SavedState {
    facet: u32,
    elastic_gap: f64,
    resumed_along: Option<Vec2>,
    depth: f64,
}

impl From<SavedState> for ContactState {
    fn from(s: SavedState) -> Self {
        ContactState { facet: s.facet, resumed: NONE, elastic_gap: s.elastic_gap, depth: s.depth }
    }
}

impl From<ContactState> for SavedState {
    fn from(s: ContactState) -> Self {
        debug_assert_eq!(s.resumed, NONE, "a resumed mark outlived the evaluation after its change");
        SavedState { facet: s.facet, elastic_gap: s.elastic_gap, resumed_along: None, depth: s.depth }
    }
}

/// The contact of one boundary node in this step.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(from = "SavedContact", into = "SavedContact")]
pub struct NodeContact {
    /// The facet touched, or [`NONE`].
    pub facet: u32,
    /// Position of the node's projection on the facet, `ξ ∈ [0, 1]`.
    pub xi: f64,
    /// Normal gap `g_n` (m, negative = penetration).
    pub gap: f64,
    /// The normal dashpot as the node pass applies it. Saved apart from the
    /// rest (checkpoint format 6).
    #[serde(skip)]
    pub dashpot: Dashpot,
    /// Normal force `f_n ≥ 0` (N/m).
    pub normal_force: f64,
    /// Tangential force (N/m).
    pub tangential_force: f64,
    /// Whether the contact slipped in this step.
    pub slipping: bool,
    /// The facet's two nodes as boundary-node indices, for the sequential
    /// assembly (looked up here, in parallel, so that the assembly reads
    /// nothing else). Derived: not saved, see [`NodeContact::locate`].
    #[serde(skip)]
    pub ends: [u32; 2],
}

/// A [`NodeContact`] as checkpoints hold it (formats 1–6): with the
/// forces, which the record no longer keeps ([`NodeContact::force`] works
/// them out from the normal and tangential forces and the dashpot's normal,
/// to the bit). The record is written for every contact in every step and
/// read by the assembly and the dashpot stage: 32 bytes fewer (112 → 80)
/// made a late step of the paper-scale caving run about 5% faster
/// (docs/contact.md).
#[derive(serde::Serialize, serde::Deserialize)]
struct SavedContact {
    facet: u32,
    xi: f64,
    gap: f64,
    force: Vec2,
    damping_force: Vec2,
    normal_force: f64,
    tangential_force: f64,
    slipping: bool,
}

impl From<SavedContact> for NodeContact {
    /// The record from a file. Its dashpot is not in this block: a format-6
    /// file restores it from its own block; for an older file (none saved)
    /// the normal and the spring force are recovered from the saved forces
    /// (`f = f_n n + f_t (n_y, −n_x)`, `f_d = (f_n − f_s) n`), with no
    /// dashpot, so that the forces come out as saved (to round-off).
    fn from(c: SavedContact) -> Self {
        let SavedContact { facet, xi, gap, force, damping_force, normal_force, tangential_force, slipping } = c;
        let (nf, ft) = (normal_force, tangential_force);
        let det = nf * nf + ft * ft;
        let d_len = damping_force[0].hypot(damping_force[1]);
        let (normal, spring) = if det > 0.0 {
            let n = [(nf * force[0] - ft * force[1]) / det, (ft * force[0] + nf * force[1]) / det];
            (n, nf - (damping_force[0] * n[0] + damping_force[1] * n[1]))
        } else if d_len > 0.0 {
            // no force after the no-pull clamp: `f_d = −f_s n`
            ([-damping_force[0] / d_len, -damping_force[1] / d_len], d_len)
        } else {
            ([0.0; 2], 0.0)
        };
        let dashpot = Dashpot { normal, coefficient: 0.0, spring };
        NodeContact { facet, xi, gap, dashpot, normal_force, tangential_force, slipping, ..Default::default() }
    }
}

impl From<NodeContact> for SavedContact {
    fn from(c: NodeContact) -> Self {
        let NodeContact { facet, xi, gap, normal_force, tangential_force, slipping, .. } = c;
        SavedContact {
            facet,
            xi,
            gap,
            force: c.force(),
            damping_force: c.damping_force(),
            normal_force,
            tangential_force,
            slipping,
        }
    }
}

impl NodeContact {
    /// Force on the node (N/m): the normal force along the dashpot's
    /// (the facet's) normal `n`, the tangential one along `t = (−n_y, n_x)`;
    /// the facet's nodes get `−(1−ξ)` and `−ξ` times it.
    #[inline(always)]
    pub fn force(&self) -> Vec2 {
        let (n, nf, ft) = (self.dashpot.normal, self.normal_force, self.tangential_force);
        let t = [-n[1], n[0]];
        [nf * n[0] - ft * t[0], nf * n[1] - ft * t[1]]
    }

    /// The normal dashpot's part of [`NodeContact::force`] (N/m): its
    /// estimate from the velocities of the step before ([`Dashpot`]), which
    /// the node pass replaces by the dashpot's force on the predicted
    /// velocities.
    #[inline(always)]
    pub fn damping_force(&self) -> Vec2 {
        let fd = self.normal_force - self.dashpot.spring;
        let n = self.dashpot.normal;
        [fd * n[0], fd * n[1]]
    }
}

/// A contact's normal dashpot (paper D, DESIGN §4.5), applied by the node
/// pass on the relative normal velocity that the step's other forces would
/// give, by a backward-Euler step ([`dashpot_forces`]):
///
/// `f_d = max(−c ġᵉ / (1 + c h / μ), −f_s)`
///
/// with `ġᵉ` the predicted gap rate, `h` the velocity step, `f_s` the
/// spring's normal force (no pull), and `μ` the pair's effective mass along
/// the normal with each node's mass shared among the `n` dashpots that act
/// on it: `1/μ = n_s/m_s + (1−ξ)² n_a/m_a + ξ² n_b/m_b`. For an isolated
/// pair (`n = 1`) this is the exact backward-Euler dashpot; dashpots that
/// share nodes together never take more than the backward-Euler step of
/// their sum (the sharing), so the dashpots never shorten the stable step,
/// and a pair moving together (a falling stack) feels no drag.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dashpot {
    /// The facet's outward unit normal `n`.
    pub normal: Vec2,
    /// Dashpot coefficient `c` (N·s/m per metre of thickness); zero for none.
    pub coefficient: f64,
    /// The spring's normal force `f_s ≥ 0` (N/m).
    pub spring: f64,
}

impl NodeContact {
    /// Sets [`NodeContact::ends`] from the surface (after a restore).
    pub fn locate(&mut self, surface: &Surface) {
        if self.facet != NONE {
            self.ends = surface.facets[self.facet as usize].ends;
        }
    }
}

/// Sums of one chunk of nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactPartial {
    /// Candidate pairs evaluated.
    pub pairs: u64,
    /// Active contacts.
    pub contacts: u64,
    /// Of these, contacts kept as the step's evaluation left them
    /// ([`evaluate_after_change`]).
    pub kept: u64,
    /// Work dissipated by friction (J/m).
    pub friction: f64,
    /// Elastic energy in the penalty springs (J/m).
    pub stored: f64,
}

/// Projection of point `s` on the facet `[a, b]`: `(ξ, g_n, n, t, L)`.
#[inline(always)]
pub fn project(s: Vec2, a: Vec2, b: Vec2) -> (f64, f64, Vec2, Vec2, f64) {
    let frame = FacetFrame::of(a, b);
    let (xi, gap) = frame.project(s, a);
    (xi, gap, frame.normal(), frame.t, frame.len)
}

/// The current geometry of one facet: its unit tangent `t` (first node to
/// second), length (m), the position of its first node and its depth limit
/// (m, [`SurfaceFacet::depth`](crate::SurfaceFacet::depth)). Its outward
/// normal is `n = (t_y, −t_x)`. One 48-byte record holds everything the
/// candidate test reads, so that testing a candidate is one random read
/// instead of three (the facet, its frame, its first node's position): the
/// test is latency-bound in a fractured mesh, whose new nodes and elements
/// lie far from their neighbours in memory. (It also held the facet nodes'
/// velocities for a contact's relative velocity; read from the nodes
/// instead, the 32 bytes fewer written for every facet in every step made
/// the contact pass of a late step of the paper-scale caving run 5–15%
/// faster: docs/contact.md.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FacetFrame {
    /// Unit tangent.
    pub t: Vec2,
    /// Length (m).
    pub len: f64,
    /// Position of the first node (m).
    pub a: Vec2,
    /// Deepest penetration accepted behind the facet (m).
    pub depth: f64,
}

impl Default for FacetFrame {
    fn default() -> Self {
        Self { t: [0.0; 2], len: 0.0, a: [0.0; 2], depth: f64::INFINITY }
    }
}

impl FacetFrame {
    /// The frame of the facet `[a, b]` (no depth limit, at rest).
    #[inline(always)]
    pub fn of(a: Vec2, b: Vec2) -> Self {
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        Self { t: [d[0] / len, d[1] / len], len, a, ..Self::default() }
    }

    /// Outward normal (unit).
    #[inline(always)]
    pub fn normal(&self) -> Vec2 {
        [self.t[1], -self.t[0]]
    }

    /// Projection of point `s` on the facet starting at `a`: `(ξ, g_n)`,
    /// the same numbers as [`project`].
    #[inline(always)]
    pub fn project(&self, s: Vec2, a: Vec2) -> (f64, f64) {
        let (t, n) = (self.t, self.normal());
        let r = [s[0] - a[0], s[1] - a[1]];
        ((r[0] * t[0] + r[1] * t[1]) / self.len, r[0] * n[0] + r[1] * n[1])
    }
}

/// Every facet's [`FacetFrame`] at positions `x` (parallel over fixed
/// chunks), once per contact evaluation: the candidate
/// tests, node normals and tributary lengths read them instead of
/// recomputing a square root per use (each facet's frame was computed 5–6
/// times per step before).
pub fn facet_frames(surface: &Surface, x: &[Vec2], frames: &mut [FacetFrame]) {
    frames.par_chunks_mut(CHUNK).enumerate().for_each(|(c, out)| {
        for (j, fr) in out.iter_mut().enumerate() {
            let facet = &surface.facets[c * CHUNK + j];
            let [a, b] = facet.nodes.map(|n| n as usize);
            *fr = FacetFrame { depth: facet.depth, ..FacetFrame::of(x[a], x[b]) };
        }
    });
}

/// Outward normal of boundary node `b` (unit): the sum of its own facets'
/// normals `(dy, −dx)` at the current positions.
#[inline]
fn node_normal(surface: &Surface, frames: &[FacetFrame], b: usize) -> Vec2 {
    let mut n = [0.0; 2];
    for &k in surface.node_facets.row(b) {
        let m = frames[k as usize].normal();
        n[0] += m[0];
        n[1] += m[1];
    }
    let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
    if len > 0.0 {
        [n[0] / len, n[1] / len]
    } else {
        n
    }
}

/// Tributary length (m) of boundary node `b` on a contact whose facet has
/// normal `n`: half of each of the node's own facets, projected on the
/// contact facet's line, `ℓ = ½ Σ_k L_k max(0, −m_k · n)` (`m_k` the
/// facet's outward normal). A node inside an interface counts both halves,
/// a corner node touching a flat face only its side on that face, and a
/// crack face meeting a joint at an angle only its projection. The weight
/// is continuous in the facets' orientation, so a crack inserted at a node,
/// or a facet turning, changes the node's spring gradually; an
/// all-or-nothing facing test made the spring of a joint node jump threefold
/// at a crack insertion (measured on the block-caving case).
#[inline]
fn tributary(surface: &Surface, frames: &[FacetFrame], b: usize, n: Vec2) -> f64 {
    surface
        .node_facets
        .row(b)
        .iter()
        .map(|&k| {
            let m = frames[k as usize].normal();
            0.5 * surface.facets[k as usize].length * (-(m[0] * n[0] + m[1] * n[1])).max(0.0)
        })
        .sum()
}

/// The length (m) over which boundary node `b`'s contact on facet `f`
/// (outward normal `n`) carries the interface's cohesion: its tributary
/// length (of its bearing face `face` at a corner, else of all its facets),
/// each own facet's half counted in full where only this node's side
/// presses on the other, and half where the other side's nodes press on
/// this one's facet too (two-pass contact: both passes then carry the same
/// stretch of interface, and each carries half of it).
///
/// Whether the other pass covers the half of own facet `k` is read from the
/// geometry at this step: an end of the touched facet (the other body's
/// nearest nodes) penetrates facet `k` within its span. Node on node, a
/// coincident node penetrates both own facets at their shared vertex;
/// nodes of one side between those of the other penetrate the facets they
/// lie on; a block on one long facet of another body has no node of that
/// body on its facets and carries all of `c ℓ` itself. With `½ c ℓ` for
/// every node regardless, a block on a single long facet carried half its
/// cohesion (issue 32: it slid at +0.50 m/s² against 1.36 m/s² due).
#[inline]
fn cohesive_length(inp: &NarrowInputs<'_>, b: usize, f: u32, n: Vec2, face: Option<u32>) -> f64 {
    let frame = &inp.frames[f as usize];
    let ends = [frame.a, [frame.a[0] + frame.len * frame.t[0], frame.a[1] + frame.len * frame.t[1]]];
    let half = |k: u32| {
        let own = &inp.frames[k as usize];
        let m = own.normal();
        let h = 0.5 * inp.surface.facets[k as usize].length * (-(m[0] * n[0] + m[1] * n[1])).max(0.0);
        let covered = ends.iter().any(|&p| {
            let (xi, gap) = own.project(p, own.a);
            projects_inside(xi, gap, own.depth)
        });
        if covered {
            0.5 * h
        } else {
            h
        }
    };
    match face {
        Some(k) => half(k),
        None => inp.surface.node_facets.row(b).iter().map(|&k| half(k)).sum(),
    }
}

/// At a shallow convex corner of the surface (a turn of less than 30°), the
/// signed gap (negative inside) of point `s` from the line of the facet
/// that follows facet `f` past its end (`at_end`) or precedes it before its
/// start; `None` at a concave or sharp corner (or without such a facet).
/// Facets run with the body on their left, so a left turn is convex. Only
/// shallow corners need this: there a contact slides on from one facet to
/// the next without the entry check (rank 1 in `evaluate_node`); at a sharp
/// corner the slack keeps two blocks' aligned corners in contact.
#[inline]
fn corner_gap(surface: &Surface, x: &[Vec2], frames: &[FacetFrame], f: u32, at_end: bool, s: Vec2) -> Option<f64> {
    let [a, b] = surface.facets[f as usize].nodes;
    let v = if at_end { b } else { a };
    let bv = surface.index_of[v as usize];
    let d = frames[f as usize].t;
    // the turn from the first facet along the surface to the second: from
    // `f` to the next one past its end, from the previous one to `f` before
    // its start (sine and cosine)
    let turn = |k: u32| {
        let e = frames[k as usize].t;
        let cross = d[0] * e[1] - d[1] * e[0];
        (if at_end { cross } else { -cross }, d[0] * e[0] + d[1] * e[1])
    };
    // At a node where the body touches itself (four facets) two facets
    // qualify; the one on the same wedge of the body turns most to the left
    // (walking with the body on the left, the boundary of one wedge turns
    // left of the other's). Chosen by geometry, not by index, so that it
    // does not depend on the numbering.
    let mut next = surface.node_facets.row(bv as usize).iter().copied().filter(|&k| {
        let [p, q] = surface.facets[k as usize].nodes;
        k != f && if at_end { p == v } else { q == v }
    });
    let angle = |k: u32| {
        let (sin, cos) = turn(k);
        sin.atan2(cos)
    };
    let mut k = next.next()?;
    for other in next {
        if angle(other) > angle(k) {
            k = other;
        }
    }
    let p = surface.facets[k as usize].nodes[0];
    let e = frames[k as usize].t;
    let turn = turn(k).0;
    let smooth = d[0] * e[0] + d[1] * e[1] >= SMOOTH_COS;
    (turn > 0.0 && smooth).then(|| frames[k as usize].project(s, x[p as usize]).1)
}

/// Inputs of the narrow phase.
pub struct NarrowInputs<'a> {
    /// Node positions `x^{n+1}` (m).
    pub x: &'a [Vec2],
    /// Node velocities `v^{n+½}` (m/s).
    pub v: &'a [Vec2],
    /// Node masses (kg/m).
    pub mass: &'a [f64],
    /// The surfaces.
    pub surface: &'a Surface,
    /// Every facet's frame at `x` ([`facet_frames`]).
    pub frames: &'a [FacetFrame],
    /// Candidate facets per boundary node.
    pub candidates: &'a Csr,
    /// Interface laws by index.
    pub laws: &'a [InterfaceLaw],
    /// The nodes `[a, b]` of the facets before the last topology change,
    /// by their index then: a resumed contact ([`ContactState::resumed`])
    /// reads the direction `x_b − x_a` of its old facet here.
    pub resumed: &'a [[u32; 2]],
    /// The step (s), for the tangential slip increment.
    pub dt: f64,
}

/// The contacts of the boundary nodes: per node a first contact and, at a
/// corner of its body ([`Surface::faces`]), a second one, so that each of
/// the corner's two faces bears on the other bodies by itself. A corner
/// node pushed out diagonally (prestressed rock at a joint crossing) needs
/// a force on each face; with a single contact it can press on one facet
/// only and the rock around the corner ends up in tension (measured: +2 MPa
/// at an X crossing of joints along the principal axes of a K0 state).
#[derive(Debug)]
pub struct Contacts<'a> {
    /// First contact's memory, per boundary node.
    pub states: &'a mut [ContactState],
    /// Second contact's memory, per boundary node: used at corner nodes
    /// only; elsewhere it must be empty, and it is left untouched.
    pub corner_states: &'a mut [ContactState],
    /// First contact of this step, per boundary node.
    pub out: &'a mut [NodeContact],
    /// Second contact of this step, per boundary node (facet [`NONE`] but
    /// at corners; left untouched elsewhere).
    pub corner_out: &'a mut [NodeContact],
    /// Per boundary node: bit 0 set when the first memory is not empty, bit
    /// 1 when the second is not ([`mark_busy`]; kept up to date by
    /// [`evaluate`]). A node with no memory and no candidate is skipped
    /// without reading its memory or contacts, and the assembly visits only
    /// the busy nodes: reading every node's 80-byte contact record to find
    /// most of them empty was most of the (serial) assembly's time.
    pub busy: &'a mut [u8],
}

/// Sets the busy flags ([`Contacts::busy`]) from the memories: after the
/// memories were set other than by [`evaluate`] (a topology change, a
/// restore).
pub fn mark_busy(states: &[ContactState], corner_states: &[ContactState], busy: &mut [u8]) {
    for ((f, s), s2) in busy.iter_mut().zip(states).zip(corner_states) {
        *f = u8::from(*s != ContactState::default()) | u8::from(*s2 != ContactState::default()) << 1;
    }
}

/// Evaluates the contacts of every boundary node (parallel over fixed
/// chunks): per contact, picks among the node's candidate facets the one
/// that continues the contact best, then the least penetrated (ties to the
/// smaller facet id), and applies the penalty, dashpot and friction laws.
/// Updates the states, fills the contacts and one partial per chunk.
pub fn evaluate(inp: &NarrowInputs<'_>, c: Contacts<'_>, partials: &mut [ContactPartial]) {
    evaluate_where(inp, c, partials, None);
}

/// [`evaluate`] at the same positions right after a topology change that
/// left some nodes' contacts as they were, without slip (`inp.dt = 0`):
/// a node flagged in `kept` (per boundary node: its memories and contacts
/// were carried over from the step's evaluation, and the change touched
/// neither it nor its own facets) that penetrates none of its candidate
/// facets flagged in `changed` (per facet: an end of it was touched) keeps
/// its contacts as the step's evaluation left them; only its held energy
/// and its contacts are counted. Every other node is evaluated as by
/// [`evaluate`].
///
/// What such a node's evaluation reads is the same as in the step's (the
/// positions, its candidates and their neighbours, its own facets and its
/// memory), so it would find the same contacts with the same gaps; it
/// would differ only in the dashpot's estimate, which depends on the step
/// and which the node pass replaces anyway ([`Dashpot`]), and through it
/// in the friction limit. Evaluating every contact again cost 6.5 ms of
/// the 28 ms an insertion took late in the paper-scale caving run on 2
/// threads (docs/caving.md).
pub fn evaluate_after_change(
    inp: &NarrowInputs<'_>,
    c: Contacts<'_>,
    partials: &mut [ContactPartial],
    kept: &[u8],
    changed: &[u8],
) {
    debug_assert_eq!(kept.len(), c.states.len());
    debug_assert_eq!(changed.len(), inp.surface.facets.len());
    evaluate_where(inp, c, partials, Some((kept, changed)));
}

/// [`evaluate`], or with `after` (`kept`, `changed`)
/// [`evaluate_after_change`]. One function for both, so that the search
/// and the response are inlined into one loop as before the second (with
/// two callers the compiler stopped inlining them: the narrow phase ran
/// 3–7% slower on one thread).
fn evaluate_where(
    inp: &NarrowInputs<'_>,
    c: Contacts<'_>,
    partials: &mut [ContactPartial],
    after: Option<(&[u8], &[u8])>,
) {
    // a node the change left as it was, and that penetrates none of its
    // candidate facets with a touched end (the search passes over a
    // candidate it does not penetrate; which candidates the node
    // penetrates does not depend on the extent of the candidate lists,
    // which depends on the run's history, e.g. on when the mesh was last
    // renumbered)
    let keep = |b: usize| {
        let Some((kept, changed)) = after else { return false };
        let s = inp.x[inp.surface.nodes[b] as usize];
        kept[b] != 0
            && inp.candidates.row(b).iter().all(|&f| {
                changed[f as usize] == 0 || {
                    let frame = &inp.frames[f as usize];
                    let (xi, gap) = frame.project(s, frame.a);
                    !projects_inside(xi, gap, frame.depth)
                }
            })
    };
    // the chunks are zipped: a short array would silently drop nodes
    debug_assert!([c.corner_states.len(), c.out.len(), c.corner_out.len(), c.busy.len()]
        .iter()
        .all(|&l| l == c.states.len()));
    c.states
        .par_chunks_mut(CHUNK)
        .zip(c.corner_states.par_chunks_mut(CHUNK))
        .zip(c.out.par_chunks_mut(CHUNK).zip(c.corner_out.par_chunks_mut(CHUNK)))
        .zip(c.busy.par_chunks_mut(CHUNK).zip(partials.par_iter_mut()))
        .enumerate()
        .for_each(|(c, (((st, st2), (oc, oc2)), (busy, part)))| {
            let mut acc = ContactPartial::default();
            for j in 0..st.len() {
                let b = c * CHUNK + j;
                if busy[j] == 0 && inp.candidates.row(b).is_empty() {
                    continue;
                }
                if keep(b) {
                    for (k, (state, contact)) in [(&st[j], &oc[j]), (&st2[j], &oc2[j])].into_iter().enumerate() {
                        if busy[j] & (1 << k) != 0 && contact.facet != NONE {
                            acc.contacts += 1;
                            acc.kept += 1;
                            acc.stored += held_energy(inp, contact, state.elastic_gap);
                        }
                    }
                    continue;
                }
                busy[j] = evaluate_node(inp, b, [&mut st[j], &mut st2[j]], [&mut oc[j], &mut oc2[j]], &mut acc);
            }
            *part = acc;
        });
}

/// The energy held in contact `c`'s springs (J/m) with the elastic
/// tangential gap `elastic_gap` (its memory's): `½ α_n g² + ½ α_t g_tᵉ²`
/// as [`respond`] counts it, with `α_n = f_s / (−g)` from the spring's
/// normal force `f_s = −α_n g` (a contact's gap is negative) and `α_t =
/// α_n k_t / k_n` (both springs share the node's tributary length).
#[inline]
fn held_energy(inp: &NarrowInputs<'_>, c: &NodeContact, elastic_gap: f64) -> f64 {
    let law = &inp.laws[inp.surface.facets[c.facet as usize].law as usize];
    let depth = -c.gap;
    let alpha_t = c.dashpot.spring / depth * (law.shear_stiffness / law.normal_stiffness);
    0.5 * c.dashpot.spring * depth + 0.5 * alpha_t * elastic_gap * elastic_gap
}

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
/// surface) or one parallel to a resumed contact's, 2 a new contact;
/// `None` when the contact may not take it up. Keeping the same facet stops
/// a node near a corner of the other body from flipping between two
/// normals. A new contact must have been entered through the facet's line
/// within this step (its penetration no deeper than its normal approach): a
/// node that slides onto the end of a facet from the side would otherwise
/// start with a finite penetration, and the penalty energy ½α g² would
/// appear without work (an energy pump at every corner).
#[inline]
fn rank(inp: &NarrowInputs<'_>, node: usize, state: &ContactState, c: &Candidate) -> Option<u8> {
    let (f, n, gap) = (c.f, c.n, c.gap);
    if f == state.facet {
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
            return None;
        }
        let [ia, ib] = inp.surface.facets[c.f as usize].nodes;
        let (a, b) = (inp.x[ia as usize], inp.x[ib as usize]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let parallel = (d[0] * e[0] + d[1] * e[1]).abs() >= SMOOTH_COS * (d[0] * d[0] + d[1] * d[1]).sqrt() * c.len;
        Some(if parallel { 1 } else { 2 })
    } else {
        no_deeper(0.0).then_some(2)
    }
}

/// The direction `x_b − x_a` (m) of the facet `[a, b]` that was number
/// `old` before the last topology change ([`ContactState::resumed`]).
#[inline]
fn resumed_direction(inp: &NarrowInputs<'_>, old: u32) -> Vec2 {
    let [a, b] = inp.resumed[old as usize];
    let (pa, pb) = (inp.x[a as usize], inp.x[b as usize]);
    [pb[0] - pa[0], pb[1] - pa[1]]
}

/// The projection test of a candidate: the node projects onto the facet
/// within the end slack (`ξ`) and lies behind it, no deeper than its depth
/// limit (`−depth ≤ gap < 0`). Written without short-circuits, so that a
/// row of candidates is tested without a branch each.
#[inline(always)]
// a NaN gap passes here, as it always has; `&` instead of `&&` throughout
#[allow(clippy::neg_cmp_op_on_partial_ord, clippy::manual_range_contains)]
fn projects_inside(xi: f64, gap: f64, depth: f64) -> bool {
    (xi >= -XI_SLACK) & (xi <= 1.0 + XI_SLACK) & !(gap >= 0.0) & !(gap < -depth)
}

/// Per contact: (rank, facet, ξ, gap, facing) of the best candidate so far.
type Best = Option<(u8, u32, f64, f64, f64)>;

/// The candidate search of one boundary node: what every candidate test
/// reads, and the search's running state.
struct Search<'i, 'a> {
    inp: &'i NarrowInputs<'a>,
    /// Boundary index and mesh id of the node, and its position.
    b: usize,
    node: usize,
    s: Vec2,
    /// The node's two faces at a corner ([`Surface::faces`]).
    faces: [u32; 2],
    /// Contacts the node has: 1 on a smooth stretch, 2 at a corner.
    slots: usize,
    best: [Best; 2],
    /// Each contact's bearing normal, computed on first use.
    own: [Option<Vec2>; 2],
}

impl<'i, 'a> Search<'i, 'a> {
    /// A search for boundary node `b`, nothing found yet.
    #[inline]
    fn new(inp: &'i NarrowInputs<'a>, b: usize) -> Self {
        let node = inp.surface.nodes[b] as usize;
        let faces = inp.surface.faces[b];
        let slots = if faces[0] == NONE { 1 } else { 2 };
        Self { inp, b, node, s: inp.x[node], faces, slots, best: [None; 2], own: [None; 2] }
    }

    /// Finds each contact's best candidate. The facet a contact touched
    /// last step ranks 0 ([`rank`]) and so beats every other candidate
    /// whenever it still qualifies: it is tested first, and the others only
    /// for a contact that it no longer holds. Most contacts keep their facet
    /// step after step (a closed joint, a resting block), so most nodes in
    /// contact test one candidate instead of all of them; what is found is
    /// the same as testing all of them.
    #[inline]
    fn run(&mut self, states: &[&mut ContactState; 2], acc: &mut ContactPartial) {
        let row = self.inp.candidates.row(self.b);
        let mut open = [false; 2];
        for k in 0..self.slots {
            let f = states[k].facet;
            if f != NONE && row.binary_search(&f).is_ok() {
                self.consider(f, [k == 0, k == 1], states, acc);
            }
            open[k] = !matches!(self.best[k], Some((0, ..)));
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
        for k in (0..slots).filter(|&k| open[k]) {
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
            // touch a facet it has already passed
            if facing > -FACING_COS || (!on_facet && facing > -SMOOTH_COS) {
                continue;
            }
            if !on_facet {
                let g = *corner.get_or_insert_with(|| corner_gap(inp.surface, inp.x, inp.frames, f, xi > 1.0, self.s));
                match g {
                    Some(g) if g >= 0.0 => return,
                    Some(g) => c.gap = gap.max(g),
                    None => {}
                }
            }
            let gap = c.gap;
            let Some(r) = rank(inp, self.node, &*states[k], &c) else { continue };
            // equal ranks: the shallower penetration; an exact tie (a node
            // at the vertex two facets share) goes to the facet that faces
            // the node's face more squarely, so the choice is geometric,
            // not by facet index, and does not depend on the numbering
            if self.best[k]
                .is_none_or(|(rb, _, _, g, fb)| r < rb || (r == rb && (gap > g || (gap == g && facing < fb))))
            {
                self.best[k] = Some((r, f, xi, gap, facing));
            }
        }
    }
}

/// Evaluates both contacts of boundary node `b`; returns its busy flags.
#[inline]
fn evaluate_node(
    inp: &NarrowInputs<'_>,
    b: usize,
    states: [&mut ContactState; 2],
    out: [&mut NodeContact; 2],
    acc: &mut ContactPartial,
) -> u8 {
    let mut search = Search::new(inp, b);
    search.run(&states, acc);
    let Search { node, faces, slots, best, .. } = search;
    // a smooth node's second contact stays empty from the topology change
    // that made it smooth (`adopt` starts every memory empty): not touched
    debug_assert!(slots == 2 || (*states[1] == ContactState::default() && out[1].facet == NONE));
    let mut busy = 0;
    for k in 0..slots {
        let face = (slots == 2).then(|| faces[k]);
        match best[k] {
            Some((r, f, xi, gap, _)) => {
                let best = (r, f, xi, gap);
                *out[k] = respond(inp, b, node, &mut *states[k], best, face, acc);
                busy |= 1 << k;
            }
            // no contact: clear what is not clear already (most boundary
            // nodes touch nothing, step after step; rewriting their memory
            // and output cost a measurable share of the step in memory
            // traffic). A contact (`out[k].facet` set) always leaves a
            // memory, so an empty memory means an empty contact too, and the
            // contact need not be read.
            None => {
                if *states[k] != ContactState::default() {
                    *states[k] = ContactState::default();
                    *out[k] = NodeContact { facet: NONE, ..Default::default() };
                }
            }
        }
    }
    busy
}

/// The forces of one contact of boundary node `b` (mesh id `node`) on the
/// facet chosen by [`evaluate_node`] (`best`: rank, facet, ξ, gap); `face`
/// is the node's own facet that bears at a corner (`None` for a node on a
/// smooth stretch, which bears with all its facets).
#[inline]
fn respond(
    inp: &NarrowInputs<'_>,
    b: usize,
    node: usize,
    state: &mut ContactState,
    best: (u8, u32, f64, f64),
    face: Option<u32>,
    acc: &mut ContactPartial,
) -> NodeContact {
    let (rank, f, xi, gap) = best;
    let continues = rank == 1;
    let xi = xi.clamp(0.0, 1.0);
    let facet = &inp.surface.facets[f as usize];
    let law = &inp.laws[facet.law as usize];
    let (ia, ib) = (facet.nodes[0] as usize, facet.nodes[1] as usize);
    let (n, t) = (inp.frames[f as usize].normal(), inp.frames[f as usize].t);
    let (v, [va, vb]) = (inp.v, [inp.v[ia], inp.v[ib]]);
    let vrel = [v[node][0] - (1.0 - xi) * va[0] - xi * vb[0], v[node][1] - (1.0 - xi) * va[1] - xi * vb[1]];
    let gap_rate = vrel[0] * n[0] + vrel[1] * n[1];
    // the node's springs: stiffness per unit area × its share of the
    // contact; at a corner the bearing face's half, and the dashpot sees
    // that face's share of the node's mass, so that the two contacts'
    // dashpots together never exceed one on the whole node (the stable
    // step's bound)
    let (trib, ms) = match face {
        None => (tributary(inp.surface, inp.frames, b, n), inp.mass[node]),
        Some(k) => {
            let m = inp.frames[k as usize].normal();
            let half = 0.5 * inp.surface.facets[k as usize].length;
            (half * (-(m[0] * n[0] + m[1] * n[1])).max(0.0), inp.mass[node] * half / inp.surface.tributary_max(b))
        }
    };
    let (alpha_n, alpha_t) = (law.normal_stiffness * trib, law.shear_stiffness * trib);
    // The dashpot is sized for the pair's relative motion: critical damping
    // of a spring between two masses uses their reduced mass. Sizing it with
    // the node's mass alone over-damps (explicitly: destabilises) a light
    // facet node, e.g. a block corner under a heavier node.
    let mf = (1.0 - xi) * inp.mass[ia] + xi * inp.mass[ib];
    let m = if mf > 0.0 { ms * mf / (ms + mf) } else { ms };
    let dashpot = law.damping_ratio * 2.0 * (alpha_n * m).sqrt();
    let spring = -alpha_n * gap;
    // the pair's effective mass along the normal, as an impulse moves the
    // gap rate (a massless end moves with nothing: no term), for the
    // estimate
    let inv = |m: f64| if m > 0.0 { 1.0 / m } else { 0.0 };
    let inverse_mass = inv(inp.mass[node]) + (1.0 - xi) * (1.0 - xi) * inv(inp.mass[ia]) + xi * xi * inv(inp.mass[ib]);
    // the estimate of the dashpot on the last velocities, for the friction
    // limit and the readouts; the node pass applies it on the predicted ones
    let estimate = dashpot / (1.0 + dashpot * inp.dt * inverse_mass);
    let normal_force = (spring - estimate * gap_rate).max(0.0);
    // carry the elastic tangential gap, measured along the old facet's
    // direction `d`, over to a neighbouring facet or a resumed contact
    let carried = |d: Vec2| if d[0] * t[0] + d[1] * t[1] >= 0.0 { state.elastic_gap } else { -state.elastic_gap };
    let elastic_gap = if state.facet == f {
        state.elastic_gap
    } else if state.facet != NONE && inp.surface.adjacent(state.facet, f) && continues {
        let prev = &inp.surface.facets[state.facet as usize];
        let (pa, pb) = (inp.x[prev.nodes[0] as usize], inp.x[prev.nodes[1] as usize]);
        carried([pb[0] - pa[0], pb[1] - pa[1]])
    } else if state.resumed != NONE {
        carried(resumed_direction(inp, state.resumed))
    } else {
        0.0
    };
    let slip = inp.dt * (vrel[0] * t[0] + vrel[1] * t[1]);
    let cohesion = if law.cohesion > 0.0 { law.cohesion * cohesive_length(inp, b, f, n, face) } else { 0.0 };
    let (ft, new_gap, work) = friction_update(law, alpha_t, elastic_gap, slip, normal_force, cohesion);
    *state = ContactState { facet: f, resumed: NONE, elastic_gap: new_gap, depth: -gap };
    acc.contacts += 1;
    acc.friction += work;
    acc.stored += 0.5 * alpha_n * gap * gap + 0.5 * alpha_t * new_gap * new_gap;
    NodeContact {
        facet: f,
        xi,
        gap,
        dashpot: Dashpot { normal: n, coefficient: dashpot, spring },
        normal_force,
        tangential_force: ft,
        slipping: work > 0.0,
        ends: facet.ends,
    }
}

/// One contact's dashpot as the node pass applies it ([`Dashpot`]),
/// gathered by [`dashpot_forces`] (in parallel) so that
/// [`assemble_dashpots`] (sequential) reads one record per dashpot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DashpotLink {
    /// The node and the facet's two ends as boundary-node indices.
    pub bnodes: [u32; 3],
    /// Position `ξ` of the node's projection on the facet.
    pub xi: f64,
    /// The facet's outward unit normal.
    pub normal: Vec2,
    /// The dashpot's normal force on the node (N/m, along `normal`).
    pub force: f64,
}

/// Adds every contact force into `forces`, and the dashpot parts also into
/// `damping` (one entry per boundary node, zeroed first), node by node in
/// boundary-node order (a node's first contact, then its corner's second):
/// deterministic. Counts in `damped` the dashpots that act on each boundary
/// node (as the node, or as a facet end with a non-zero weight), and lists
/// the contacts with a dashpot in `dashpots` (as `2b + k`, `k` = 0 for the
/// first contact, 1 for the second), in the same order. Reads the contacts
/// of the busy nodes only (`busy` as left by [`evaluate`]: a contact
/// implies a memory).
pub fn assemble(
    contacts: [&[NodeContact]; 2],
    busy: &[u8],
    forces: &mut [Vec2],
    damping: &mut [Vec2],
    damped: &mut [u16],
    dashpots: &mut Vec<u32>,
) {
    forces.iter_mut().for_each(|f| *f = [0.0; 2]);
    damping.iter_mut().for_each(|f| *f = [0.0; 2]);
    damped.iter_mut().for_each(|d| *d = 0);
    dashpots.clear();
    for (b, &flags) in busy.iter().enumerate() {
        if flags == 0 {
            continue;
        }
        for k in 0..2 {
            let c = &contacts[k][b];
            if flags & (1 << k) == 0 || c.facet == NONE {
                continue;
            }
            let [fa, fb] = c.ends.map(|i| i as usize);
            spread(forces, [b, fa, fb], c.xi, c.force());
            spread(damping, [b, fa, fb], c.xi, c.damping_force());
            if c.dashpot.coefficient > 0.0 {
                dashpots.push(2 * b as u32 + k as u32);
                for (node, w) in [(b, 1.0), (fa, 1.0 - c.xi), (fb, c.xi)] {
                    if w > 0.0 {
                        damped[node] = damped[node].saturating_add(1);
                    }
                }
            }
        }
    }
}

/// Each listed contact's dashpot force into `links` (one per entry of
/// `dashpots`, the list of [`assemble`]), from the predicted velocities `v`
/// and the masses `mass` (by mesh id; `nodes` maps boundary index to mesh
/// id), the dashpot counts `damped` of [`assemble`] (per boundary node) and
/// the velocity step `h` (s): `f_d = max(−c ġᵉ / (1 + c h / μ), −f_s)`
/// ([`Dashpot`]), each node's mass shared among the dashpots on it (a
/// massless node moves with nothing: no term). In parallel.
pub fn dashpot_forces(
    contacts: [&[NodeContact]; 2],
    dashpots: &[u32],
    nodes: &[u32],
    damped: &[u16],
    mass: &[f64],
    v: &[Vec2],
    h: f64,
    links: &mut [DashpotLink],
) {
    links.par_iter_mut().zip(dashpots.par_iter()).with_min_len(CHUNK).for_each(|(link, &id)| {
        let (b, k) = ((id / 2) as usize, (id % 2) as usize);
        let c = &contacts[k][b];
        let d = &c.dashpot;
        let bnodes = [b as u32, c.ends[0], c.ends[1]];
        let w = [1.0, 1.0 - c.xi, c.xi];
        let (mut rel, mut inverse_mass) = ([0.0; 2], 0.0);
        for j in 0..3 {
            let node = nodes[bnodes[j] as usize] as usize;
            let sign = if j == 0 { 1.0 } else { -1.0 };
            rel[0] += sign * w[j] * v[node][0];
            rel[1] += sign * w[j] * v[node][1];
            let m = mass[node];
            if m > 0.0 {
                inverse_mass += w[j] * w[j] * f64::from(damped[bnodes[j] as usize]) / m;
            }
        }
        let rate = rel[0] * d.normal[0] + rel[1] * d.normal[1];
        let f = -d.coefficient * rate / (1.0 + d.coefficient * h * inverse_mass);
        *link = DashpotLink { bnodes, xi: c.xi, normal: d.normal, force: f.max(-d.spring) };
    });
}

/// Adds the dashpot forces of `links` ([`dashpot_forces`]) into `out` (one
/// entry per boundary node, zeroed first), in their order: deterministic.
pub fn assemble_dashpots(links: &[DashpotLink], out: &mut [Vec2]) {
    out.iter_mut().for_each(|f| *f = [0.0; 2]);
    for l in links {
        let f = [l.force * l.normal[0], l.force * l.normal[1]];
        spread(out, l.bnodes.map(|i| i as usize), l.xi, f);
    }
}

/// Adds the force `f` of a contact of node `b` on the facet `[fa, fb]` at
/// `ξ` into `out` (by boundary node): `f` on the node, `−(1−ξ) f` and `−ξ f`
/// on the facet's ends (eq. 2.7).
#[inline(always)]
fn spread(out: &mut [Vec2], [b, fa, fb]: [usize; 3], xi: f64, f: Vec2) {
    for d in 0..2 {
        out[b][d] += f[d];
        out[fa][d] -= (1.0 - xi) * f[d];
        out[fb][d] -= xi * f[d];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_of_a_point_below_a_facet() {
        // facet from (0,0) to (2,0): body above? No: body on the left of the
        // direction +x, i.e. above; outward normal is −y.
        let (xi, gap, n, t, len) = project([0.5, 0.1], [0.0, 0.0], [2.0, 0.0]);
        assert_eq!((xi, len), (0.25, 2.0));
        assert_eq!(n, [0.0, -1.0]);
        assert_eq!(t, [1.0, 0.0]);
        assert!((gap + 0.1).abs() < 1e-15); // 0.1 inside the body
    }

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
        let laws = [InterfaceLaw::new(1e9, 1e9, 0.5, 0.0, 0.0).unwrap()];
        let v = vec![[0.0; 2]; x.len()];
        let mass = vec![1.0; x.len()];
        let mut frames = vec![FacetFrame::default(); surface.facets.len()];
        facet_frames(surface, x, &mut frames);
        let inp = NarrowInputs {
            x,
            v: &v,
            mass: &mass,
            surface,
            frames: &frames,
            candidates: &broad.candidates,
            laws: &laws,
            resumed: &[],
            dt: 1e-4,
        };
        let mut states = vec![ContactState::default(); surface.nodes.len()];
        states[node_s] = ContactState { facet: last, depth: 0.01, ..Default::default() };
        assert_ne!(surface.faces[node_s][0], NONE, "the apex is a corner");
        evaluate_once(&inp, states.clone(), states)
    }

    /// One evaluation from the given memories of both contacts: both
    /// contacts of every node and the chunk partials.
    fn evaluate_once(
        inp: &NarrowInputs<'_>,
        mut states: Vec<ContactState>,
        mut corner_states: Vec<ContactState>,
    ) -> ([Vec<NodeContact>; 2], Vec<ContactPartial>) {
        evaluate_in_place(inp, &mut states, &mut corner_states)
    }

    /// [`evaluate_once`], leaving the updated memories in place.
    fn evaluate_in_place(
        inp: &NarrowInputs<'_>,
        states: &mut [ContactState],
        corner_states: &mut [ContactState],
    ) -> ([Vec<NodeContact>; 2], Vec<ContactPartial>) {
        let nb = states.len();
        let mut out = vec![NodeContact { facet: NONE, ..Default::default() }; nb];
        let mut corner_out = out.clone();
        let mut partials = vec![ContactPartial::default(); nb.div_ceil(CHUNK)];
        let mut busy = vec![0; nb];
        mark_busy(states, corner_states, &mut busy);
        let c = Contacts {
            states: &mut *states,
            corner_states: &mut *corner_states,
            out: &mut out,
            corner_out: &mut corner_out,
            busy: &mut busy,
        };
        evaluate(inp, c, &mut partials);
        // the flags the evaluation left are those of its memories, and every
        // contact has a memory (what the skipping and the assembly rely on)
        let mut expected = vec![0; nb];
        mark_busy(states, corner_states, &mut expected);
        assert_eq!(busy, expected, "busy flags out of step with the memories");
        for (k, list) in [&out, &corner_out].into_iter().enumerate() {
            assert!(list.iter().zip(&busy).all(|(c, f)| c.facet == NONE || f & (1 << k) != 0));
        }
        ([out, corner_out], partials)
    }

    /// The assembly over busy nodes adds the same forces in the same order
    /// as a walk over every node's contacts (node by node, a node's first
    /// contact, then its corner's second): bit for bit, including a node
    /// busy with its corner contact only and nodes whose memory outlived
    /// their contact; it lists the contacts with a dashpot in that order and
    /// counts the dashpots on each node, and the dashpot forces are added up
    /// in that order too.
    #[test]
    fn assembly_of_busy_nodes_matches_a_walk_over_every_contact() {
        let nb = 6;
        let empty = NodeContact { facet: NONE, ..Default::default() };
        let contact = |facet: u32, xi: f64, ends: [u32; 2], f: f64| NodeContact {
            facet,
            xi,
            normal_force: f,
            tangential_force: 0.3 * f,
            dashpot: Dashpot { normal: [0.6, -0.8], coefficient: f.abs(), spring: 1.0 },
            ends,
            ..empty
        };
        let mut first = vec![empty; nb];
        let mut corner = vec![empty; nb];
        first[0] = contact(4, 0.3, [2, 3], 1.7);
        first[3] = contact(1, 0.9, [0, 2], -2.1e6);
        first[5] = contact(2, 0.0, [3, 0], 3.3e-3); // at its facet's first end
        corner[1] = contact(0, 0.5, [3, 5], 7.0); // busy with its corner only
        corner[3] = contact(5, 0.25, [0, 1], 1.1e5);
        let mut busy: Vec<u8> = first
            .iter()
            .zip(&corner)
            .map(|(c, k)| u8::from(c.facet != NONE) | u8::from(k.facet != NONE) << 1)
            .collect();
        busy[4] = 1; // a memory without a contact this step
        first[0].dashpot.coefficient = 0.0; // no dashpot
        let (mut forces, mut damping, mut dashpot_sum) = (vec![[9.0; 2]; nb], vec![[9.0; 2]; nb], vec![[9.0; 2]; nb]);
        let (mut damped, mut ids) = (vec![9; nb], vec![7]);
        assemble([&first, &corner], &busy, &mut forces, &mut damping, &mut damped, &mut ids);
        let nodes: Vec<u32> = (0..nb as u32).map(|b| 10 + b).collect();
        let mass: Vec<f64> = (0..nb + 10).map(|i| 1.0 + i as f64).collect();
        let v: Vec<Vec2> = (0..nb + 10).map(|i| [0.1 * i as f64, 0.3 - 0.05 * i as f64]).collect();
        let mut links = vec![DashpotLink::default(); ids.len()];
        dashpot_forces([&first, &corner], &ids, &nodes, &damped, &mass, &v, 0.1, &mut links);
        let computed: Vec<f64> = links.iter().map(|l| l.force).collect();
        let fd: Vec<f64> = (0..links.len()).map(|i| 0.5 + i as f64).collect();
        links.iter_mut().zip(&fd).for_each(|(l, &f)| l.force = f);
        assemble_dashpots(&links, &mut dashpot_sum);
        let list: Vec<u32> = links.iter().map(|l| l.bnodes[0]).collect();
        let (mut want_f, mut want_d, mut want_p) = (vec![[0.0; 2]; nb], vec![[0.0; 2]; nb], vec![[0.0; 2]; nb]);
        let (mut want_damped, mut want_list) = (vec![0u16; nb], Vec::new());
        for b in 0..nb {
            for c in [&first[b], &corner[b]] {
                if c.facet == NONE {
                    continue;
                }
                let [fa, fb] = c.ends.map(|i| i as usize);
                for (out, f) in [(&mut want_f, c.force()), (&mut want_d, c.damping_force())] {
                    for d in 0..2 {
                        out[b][d] += f[d];
                        out[fa][d] -= (1.0 - c.xi) * f[d];
                        out[fb][d] -= c.xi * f[d];
                    }
                }
                // the dashpot: its force along the normal, on the node and
                // (weighted) on the facet's ends, each counted where its
                // weight is not zero
                if c.dashpot.coefficient > 0.0 {
                    let f = c.dashpot.normal.map(|n| fd[want_list.len()] * n);
                    want_list.push(b as u32);
                    for d in 0..2 {
                        want_p[b][d] += f[d];
                        want_p[fa][d] -= (1.0 - c.xi) * f[d];
                        want_p[fb][d] -= c.xi * f[d];
                    }
                    for (node, w) in [(b, 1.0), (fa, 1.0 - c.xi), (fb, c.xi)] {
                        want_damped[node] += u16::from(w > 0.0);
                    }
                }
            }
        }
        assert_eq!(ids, [3, 6, 7, 10]);
        assert_eq!(list, [1, 3, 3, 5]);
        assert_eq!(list, want_list);
        // each link's force from its predicted gap rate and the shared
        // inverse mass Σ w² (dashpots on the node) / m, written out
        for ((l, &got), &id) in links.iter().zip(&computed).zip(&ids) {
            let (b, k) = ((id / 2) as usize, id % 2);
            let c = if k == 0 { &first[b] } else { &corner[b] };
            let w = [1.0, 1.0 - l.xi, l.xi];
            let node_v = |j: usize| v[nodes[l.bnodes[j] as usize] as usize];
            let rel: Vec<f64> = (0..2).map(|d| node_v(0)[d] - w[1] * node_v(1)[d] - w[2] * node_v(2)[d]).collect();
            let rate = rel[0] * c.dashpot.normal[0] + rel[1] * c.dashpot.normal[1];
            let inv_mu: f64 = (0..3)
                .map(|j| {
                    let bj = l.bnodes[j] as usize;
                    w[j] * w[j] * f64::from(want_damped[bj]) / mass[nodes[bj] as usize]
                })
                .sum();
            let cc = c.dashpot.coefficient;
            let want = (-cc * rate / (1.0 + cc * 0.1 * inv_mu)).max(-c.dashpot.spring);
            assert!((got - want).abs() <= 1e-12 * want.abs().max(1.0), "{got} against {want}");
        }
        assert_eq!(forces, want_f);
        assert_eq!(damping, want_d);
        assert_eq!(dashpot_sum, want_p);
        assert_eq!(damped, want_damped);
        // node 0 is an end of three dashpots' facets, of node 5's with weight 0
        assert_eq!(damped[0], 2);
    }

    /// A contact record keeps its normal and tangential forces and its
    /// dashpot's normal; its force is worked out from them. A file holds
    /// the forces instead (the format of the saved record): one written and
    /// read back without its dashpot block (a file older than format 6)
    /// recovers the normal and the spring force from them, and so the same
    /// forces to round-off; the rest of the record exactly.
    #[test]
    fn a_saved_contact_without_its_dashpot_keeps_its_forces() {
        let (s, c) = (0.3f64.sin(), 0.3f64.cos());
        for (nf, ft, spring) in [(2.5e6, -7.1e5, 2.6e6), (3.0, 0.0, 1.0), (0.0, 0.0, 4.2e3), (1.0, 2.0, 1.0)] {
            let contact = NodeContact {
                facet: 7,
                xi: 0.375,
                gap: -1.5e-4,
                dashpot: Dashpot { normal: [s, -c], coefficient: 9.0e5, spring },
                normal_force: nf,
                tangential_force: ft,
                slipping: true,
                ends: [3, 4],
            };
            let saved = SavedContact::from(contact);
            assert_eq!((saved.force, saved.damping_force), (contact.force(), contact.damping_force()));
            let back = NodeContact::from(saved);
            let close = |a: Vec2, b: Vec2| (0..2).all(|d| (a[d] - b[d]).abs() <= 1e-12 * (1.0 + b[d].abs()));
            assert!(close(back.force(), contact.force()), "{back:?} against {contact:?}");
            assert!(close(back.damping_force(), contact.damping_force()), "{back:?} against {contact:?}");
            assert_eq!(back.dashpot.coefficient, 0.0);
            let NodeContact { facet, xi, gap, normal_force, tangential_force, slipping, .. } = back;
            assert_eq!((facet, xi, gap, normal_force, tangential_force, slipping), (7, 0.375, -1.5e-4, nf, ft, true));
        }
        // the force as the narrow phase forms it: `f_n n − f_t t` with the
        // facet's unit tangent `t` and `n = (t_y, −t_x)`, to the bit
        let t = [0.28, -0.96];
        let n = [t[1], -t[0]];
        let contact = NodeContact {
            dashpot: Dashpot { normal: n, coefficient: 1.0, spring: 0.5 },
            normal_force: 1.7,
            tangential_force: -0.3,
            ..Default::default()
        };
        assert_eq!(contact.force(), [1.7 * n[0] - -0.3 * t[0], 1.7 * n[1] - -0.3 * t[1]]);
    }

    /// The dashpot of an isolated pair is the backward-Euler step of the
    /// pair: a node of mass 2 approaching a facet whose ends have mass 1
    /// and 3 at ξ = ¼ (`1/μ = 1/2 + (¾)²/1 + (¼)²/3`) at a predicted gap
    /// rate −1, with `c = 4`, `h = 0.1`: `f = 4 / (1 + 0.4/μ)`; a pair
    /// moving together feels nothing; a separating pair's pull is cut at the
    /// spring force; with every node shared by two dashpots `1/μ` doubles.
    #[test]
    fn an_isolated_dashpot_is_the_backward_euler_step_of_its_pair() {
        let c = NodeContact {
            facet: 0,
            xi: 0.25,
            ends: [1, 2],
            dashpot: Dashpot { normal: [0.0, 1.0], coefficient: 4.0, spring: 0.5 },
            ..Default::default()
        };
        let empty = NodeContact { facet: NONE, ..Default::default() };
        let contacts = [vec![c, empty, empty], vec![empty; 3]];
        let busy = [1, 0, 0];
        let nodes = [0, 1, 2];
        let mass = [2.0, 1.0, 3.0];
        let inv_mu: f64 = 0.5 + 0.75 * 0.75 + 0.25 * 0.25 / 3.0;
        let mut ids = Vec::new();
        let (mut fs, mut ds, mut damped) = (vec![[0.0; 2]; 3], vec![[0.0; 2]; 3], vec![0; 3]);
        assemble([&contacts[0], &contacts[1]], &busy, &mut fs, &mut ds, &mut damped, &mut ids);
        assert_eq!(damped, [1, 1, 1]);
        let force = |v: [Vec2; 3], share: u16| {
            let mut l = [DashpotLink::default()];
            let counts = [share; 3];
            dashpot_forces([&contacts[0], &contacts[1]], &ids, &nodes, &counts, &mass, &v, 0.1, &mut l);
            l[0].force
        };
        let f = force([[0.0, -1.0], [0.0, 0.0], [0.0, 0.0]], 1);
        assert!((f - 4.0 / (1.0 + 0.4 * inv_mu)).abs() < 1e-15, "{f}");
        // the backward-Euler property: the impulse h f brings the gap rate
        // to −1 + h f / μ, and f = −c times that
        assert!((f + 4.0 * (-1.0 + 0.1 * f * inv_mu)).abs() < 1e-12);
        assert_eq!(force([[0.3, 2.0]; 3], 1), 0.0);
        assert_eq!(force([[0.0, 1.0], [0.0, 0.0], [0.0, 0.0]], 1), -0.5);
        // two dashpots on every node: 1/μ doubles
        let shared = force([[0.0, -1.0], [0.0, 0.0], [0.0, 0.0]], 2);
        assert!((shared - 4.0 / (1.0 + 0.8 * inv_mu)).abs() < 1e-15);
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
        let x: Vec<Vec2> = lower.iter().copied().chain(upper.iter().copied()).collect();
        // each block a counter-clockwise ring (body on the left), the
        // apex of every facet the block's centroid
        let mut facets = Vec::new();
        let mut apex = Vec::new();
        for (first, n) in [(0u32, 7u32), (7, 7)] {
            let ids: Vec<u32> = (first..first + n).collect();
            let c = ids.iter().fold([0.0; 2], |c, &i| [c[0] + x[i as usize][0] / 7.0, c[1] + x[i as usize][1] / 7.0]);
            for k in 0..ids.len() {
                facets.push(([ids[k], ids[(k + 1) % ids.len()]], 0));
                apex.push(c);
            }
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
            NarrowInputs { x, v, mass, surface, frames, candidates: &broad.candidates, laws, resumed: &[], dt: 1e-4 }
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
                for &f in inp.candidates.row(b) {
                    all.consider(f, [true, true], &memories, &mut ContactPartial::default());
                }
                assert_eq!(fast.best, all.best, "node {b}, shift {shift}");
                if (0..fast.slots).all(|k| matches!(fast.best[k], Some((0, ..)))) {
                    // every contact kept its facet: one test each
                    assert_eq!(acc.pairs, fast.slots as u64, "node {b}, shift {shift}");
                    kept += 1;
                }
                for (k, m) in memories.iter().enumerate().take(fast.slots) {
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

    /// Four unit squares meeting at the origin (an X crossing of two
    /// joints); the top-left one is pushed diagonally into the others by δ
    /// in each direction, as the prestressed corner of a block at a joint
    /// crossing is. Its corner node must bear with each face: on a facet
    /// with normal +y (its bottom face) and on one with normal −x (its
    /// right face), each with its own half facet as tributary length, so
    /// that the node receives `k δ ½ (−1, 1)` (closed form, no dashpot, no
    /// friction). With one contact per node it received one of the two
    /// components only.
    #[test]
    fn a_corner_pushed_into_a_crossing_bears_with_each_face() {
        let (k, delta, dt) = (1e9, 1e-3, 1e-4);
        // squares counter-clockwise: top-left (pushed), top-right,
        // bottom-left, bottom-right
        let origins = [[-1.0, 0.0], [0.0, 0.0], [-1.0, -1.0], [0.0, -1.0]];
        let mut x = Vec::new();
        let mut facets = Vec::new();
        let mut apex = Vec::new();
        for (q, o) in origins.iter().enumerate() {
            let shift = if q == 0 { [delta, -delta] } else { [0.0, 0.0] };
            let base = x.len() as u32;
            for c in [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]] {
                x.push([o[0] + c[0] + shift[0], o[1] + c[1] + shift[1]]);
            }
            for j in 0..4u32 {
                facets.push(([base + j, base + (j + 1) % 4], 0u16));
                apex.push(x[(base + (j + 2) % 4) as usize]);
            }
        }
        let surface = Surface::new(x.len(), &facets, &x, &apex);
        let corner = surface.index_of[1] as usize; // the pushed square's corner at the origin
        assert_ne!(surface.faces[corner][0], NONE);
        let mut broad = crate::BroadPhase::new(0.3);
        broad.build(&surface, &x);
        // the pushed square moved in by δ within this step: its contacts
        // are entered through the facets' lines
        let v: Vec<Vec2> = (0..x.len()).map(|i| if i < 4 { [delta / dt, -delta / dt] } else { [0.0; 2] }).collect();
        let mass = vec![1.0; x.len()];
        let mut frames = vec![FacetFrame::default(); surface.facets.len()];
        facet_frames(&surface, &x, &mut frames);
        let laws = [InterfaceLaw::new(k, k, 0.0, 0.0, 0.0).unwrap()];
        let inp = NarrowInputs {
            x: &x,
            v: &v,
            mass: &mass,
            surface: &surface,
            frames: &frames,
            candidates: &broad.candidates,
            laws: &laws,
            resumed: &[],
            dt,
        };
        let empty = vec![ContactState::default(); surface.nodes.len()];
        let ([out, corner_out], _) = evaluate_once(&inp, empty.clone(), empty);
        let (bottom, right) = (out[corner], corner_out[corner]);
        let half = 0.5 * k * delta;
        for (c, expected) in [(bottom, [0.0, half]), (right, [-half, 0.0])] {
            assert_ne!(c.facet, NONE);
            assert!((c.gap + delta).abs() < 1e-12, "{c:?}");
            for d in 0..2 {
                assert!((c.force()[d] - expected[d]).abs() < 1e-6 * half, "{c:?}, expected {expected:?}");
            }
        }
    }
}
