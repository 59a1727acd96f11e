//! Facet geometry for the narrow phase: each facet's frame at the current
//! positions ([`FacetFrame`]), the projection of a node on a facet and the
//! test that the node lies behind it (within the end slack and the depth
//! limit), a boundary node's outward normal, and the gap past a shallow
//! convex corner of the surface.

use rayon::prelude::*;

use crate::surface::{Surface, MANY};
use crate::{Vec2, CHUNK, NONE, SMOOTH_COS};

/// Slack on the projection parameter `ξ` (fraction of the facet): a node a
/// little past the end of a surface still bears on its last facet (its
/// projection clamped to the end). Without it, the end nodes of a joint
/// whose two sides drift apart by round-off-sized shear (a micron) drop out
/// of contact and the rock beside the joint's end carries nothing.
/// The broad phase pads every facet box by this much of its length too, so
/// that the whole region where the narrow phase accepts a contact is listed.
pub(crate) const XI_SLACK: f64 = 0.05;

/// Past the end of a facet where item 5's corner test does not apply (its
/// body turns there by 30° or more, or inwards, or its surface stops), the
/// facet's line extended bears a node only while
/// the node lies no further past the end than this share of the facet's
/// length plus [`SHARP_PAST_DEPTH`] times its penetration
/// ([`bears_past_sharp_end`]). [`XI_SLACK`] is for a joint's end nodes that
/// shear has moved a micron past the other block's corner; a node
/// centimetres past a corner lies over whatever is beyond it, not over this
/// body. With the whole slack (5%: 20 cm on the caving case's 4 m joints)
/// a block sliding off a 4 m ledge was held up 25.4 cm past its edge
/// against the closed form's 12.5 cm (12.7 with the limit), and the
/// corners at a junction of four blocks held each other's faces extended
/// while the blocks sheared, so the diagonal blocks' corners ran into each
/// other "in contact" (docs/contact.md, "Which facet a node touches",
/// item 6, and "Tightening contact at corners").
pub(crate) const SHARP_PAST_LENGTH: f64 = 1e-3;

/// See [`SHARP_PAST_LENGTH`]: the share of the node's penetration (m per m)
/// it may lie past a sharp corner, so that on a short facet the slack is
/// still of the order of the contact's own depth.
pub(crate) const SHARP_PAST_DEPTH: f64 = 2.0;

/// Whether a node that projects past an end of a facet (`ξ` outside
/// `[0, 1]`, within [`XI_SLACK`]) with gap `gap` (m, negative inside) on a
/// facet of length `len` (m) still bears on it where the body has a sharp
/// or inward corner there (or ends): no further past than [`SHARP_PAST_LENGTH`] `len` +
/// [`SHARP_PAST_DEPTH`] `|gap|`.
#[inline]
pub(super) fn bears_past_sharp_end(xi: f64, gap: f64, len: f64) -> bool {
    let past = if xi > 1.0 { xi - 1.0 } else { -xi } * len;
    past <= SHARP_PAST_LENGTH * len - SHARP_PAST_DEPTH * gap
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
pub(super) fn node_normal(surface: &Surface, frames: &[FacetFrame], b: usize) -> Vec2 {
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

/// How squarely the face of boundary node `b` that opposes `n` most
/// squarely does so: the least `m·n` over the outward normals `m` of the
/// node's facets. At a node where its body touches itself (more than two
/// facets, two wedges of one body meeting at the node) it tells whether a
/// face of its own lies along a facet of normal `n`. The mean of its
/// facets' normals points between the wedges, at no face: 42° off the
/// face that held a pinched node of the quick caving case on a crack
/// face, so that the node, a hair past the facet's end, lost the contact
/// (past an end only a face within 30° of head-on slides on) and sank 4.5
/// cm into the other piece by 0.8 s (docs/contact.md, "Which facet a node
/// touches", item 11).
#[inline]
pub(super) fn most_opposed(surface: &Surface, frames: &[FacetFrame], b: usize, n: Vec2) -> f64 {
    surface.node_facets.row(b).iter().fold(f64::INFINITY, |least, &k| {
        let m = frames[k as usize].normal();
        least.min(m[0] * n[0] + m[1] * n[1])
    })
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
pub(super) fn corner_gap(surface: &Surface, frames: &[FacetFrame], f: u32, at_end: bool, s: Vec2) -> Option<f64> {
    let d = frames[f as usize].t;
    // the turn from the first facet along the surface to the second: from
    // `f` to the next one past its end, from the previous one to `f` before
    // its start (sine and cosine)
    let turn = |k: u32| {
        let e = frames[k as usize].t;
        let cross = d[0] * e[1] - d[1] * e[0];
        (if at_end { cross } else { -cross }, d[0] * e[0] + d[1] * e[1])
    };
    let k = match surface.links[f as usize][usize::from(at_end)] {
        NONE => return None,
        MANY => {
            // At a node where the body touches itself (four facets) two
            // facets qualify; the one on the same wedge of the body turns
            // most to the left (walking with the body on the left, the
            // boundary of one wedge turns left of the other's). Chosen by
            // geometry, not by index, so that it does not depend on the
            // numbering.
            let [a, b] = surface.facets[f as usize].nodes;
            let v = if at_end { b } else { a };
            let bv = surface.index_of[v as usize];
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
            k
        }
        k => k,
    };
    // the frame's first point is that node's position, to the bit
    let frame = &frames[k as usize];
    let e = frame.t;
    let turn = turn(k).0;
    let smooth = d[0] * e[0] + d[1] * e[1] >= SMOOTH_COS;
    (turn > 0.0 && smooth).then(|| frame.project(s, frame.a).1)
}

/// The projection test of a candidate: the node projects onto the facet
/// within the end slack (`ξ`) and lies behind it, no deeper than its depth
/// limit (`−depth ≤ gap < 0`). Written without short-circuits, so that a
/// row of candidates is tested without a branch each.
#[inline(always)]
// a NaN gap passes here, as it always has; `&` instead of `&&` throughout
#[allow(clippy::neg_cmp_op_on_partial_ord, clippy::manual_range_contains)]
pub(super) fn projects_inside(xi: f64, gap: f64, depth: f64) -> bool {
    (xi >= -XI_SLACK) & (xi <= 1.0 + XI_SLACK) & !(gap >= 0.0) & !(gap < -depth)
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
}
