//! The response of one contact on the facet the search chose: penalty
//! springs sized by the node's tributary length, the normal dashpot's
//! estimate on the last velocities, the elastic tangential gap carried over
//! from the facet before, Coulomb friction with cohesion over the node's
//! share of the interface (appendix D), and the energy the springs hold.

use super::projection::projects_inside;
use super::search::{resumed_direction, DEPTH_SLACK, FOUND_INSIDE};
use super::{ContactPartial, ContactState, Dashpot, FacetFrame, NarrowInputs, NodeContact};
use crate::law::friction_update;
use crate::surface::Surface;
use crate::{Vec2, NONE};

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

/// The springs' share of boundary node `b` on a contact whose facet has
/// normal `n`: its tributary length (m) and the mass (kg/m) its dashpot
/// sees. At a corner (`face`, the node's bearing facet) the bearing face's
/// half, and the dashpot sees that face's share of the node's mass, so
/// that the two contacts' dashpots together never exceed one on the whole
/// node (the stable step's bound).
#[inline]
fn share(inp: &NarrowInputs<'_>, b: usize, node: usize, n: Vec2, face: Option<u32>) -> (f64, f64) {
    match face {
        None => (tributary(inp.surface, inp.frames, b, n), inp.mass[node]),
        Some(k) => {
            let m = inp.frames[k as usize].normal();
            let half = 0.5 * inp.surface.facets[k as usize].length;
            (half * (-(m[0] * n[0] + m[1] * n[1])).max(0.0), inp.mass[node] * half / inp.surface.tributary_max(b))
        }
    }
}

/// The energy held in contact `c`'s springs (J/m), boundary node `b`
/// bearing with `face` (as in [`respond`]) and memory `state`:
/// `½ α_n (−g − offset)² + ½ α_t g_tᵉ²` as [`respond`] counts it. `α_n`
/// is read back from the spring's force `f_s = α_n (−g − offset)` and
/// `α_t = α_n k_t / k_n` (both springs share the node's tributary length);
/// only a spring the offset leaves unloaded, which has no force to read
/// it from, works its share out again.
#[inline]
pub(super) fn held_energy(
    inp: &NarrowInputs<'_>,
    b: usize,
    face: Option<u32>,
    c: &NodeContact,
    state: &ContactState,
) -> f64 {
    let law = &inp.laws[inp.surface.facets[c.facet as usize].law as usize];
    let loaded = (-c.gap - state.offset).max(0.0);
    let alpha_n = if loaded > 0.0 {
        c.dashpot.spring / loaded
    } else if state.elastic_gap != 0.0 {
        let node = inp.surface.nodes[b] as usize;
        law.normal_stiffness * share(inp, b, node, inp.frames[c.facet as usize].normal(), face).0
    } else {
        return 0.0;
    };
    let alpha_t = alpha_n * (law.shear_stiffness / law.normal_stiffness);
    0.5 * c.dashpot.spring * loaded + 0.5 * alpha_t * state.elastic_gap * state.elastic_gap
}

/// The spring (m of penetration) a node found inside a facet keeps from
/// its memory `state` ([`FOUND_INSIDE`]), its new spring being `alpha_n`
/// (N/m per m): the loaded length it had, `depth − offset`, scaled so
/// that the spring holds no more energy than it did, `√(α_old / α_n)`
/// with `α_old` its old facet's law and share; none for a node without a
/// contact last step (a resumed one's old facet is gone, so its spring
/// cannot be compared, and is let go). Taking the loaded length alone
/// would let a node pass from a facet it grazes to one it faces squarely
/// and gain energy from nothing.
#[inline]
fn kept_spring(
    inp: &NarrowInputs<'_>,
    b: usize,
    node: usize,
    state: &ContactState,
    face: Option<u32>,
    alpha_n: f64,
) -> f64 {
    if state.facet == NONE || alpha_n <= 0.0 {
        return 0.0;
    }
    let old = state.facet as usize;
    let law = &inp.laws[inp.surface.facets[old].law as usize];
    let alpha_old = law.normal_stiffness * share(inp, b, node, inp.frames[old].normal(), face).0;
    (state.depth - state.offset).max(0.0) * (alpha_old / alpha_n).min(1.0).sqrt()
}

/// The forces of one contact of boundary node `b` (mesh id `node`) on the
/// facet chosen by `evaluate_node` (`evaluation.rs`; `best`: rank, facet,
/// ξ, gap); `face` is the node's own facet that bears at a corner (`None`
/// for a node on a smooth stretch, which bears with all its facets).
#[inline]
pub(super) fn respond(
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
    let (trib, ms) = share(inp, b, node, n, face);
    let (alpha_n, alpha_t) = (law.normal_stiffness * trib, law.shear_stiffness * trib);
    // The dashpot is sized for the pair's relative motion: critical damping
    // of a spring between two masses uses their reduced mass. Sizing it with
    // the node's mass alone over-damps (explicitly: destabilises) a light
    // facet node, e.g. a block corner under a heavier node.
    let mf = (1.0 - xi) * inp.mass[ia] + xi * inp.mass[ib];
    let m = if mf > 0.0 { ms * mf / (ms + mf) } else { ms };
    let dashpot = law.damping_ratio * 2.0 * (alpha_n * m).sqrt();
    // a node taken up where it was found inside does not count that depth
    // beyond the spring it had (none for a node without contact): a node
    // whose contact moves to a facet it lies deeper in keeps its load, not
    // drops it and sinks; the offset follows it out and never grows
    // (`ContactState::offset`)
    let depth = -gap;
    let offset = if rank == FOUND_INSIDE {
        (depth - kept_spring(inp, b, node, state, face, alpha_n)).max(0.0)
    } else if rank == 2 && state.resumed == NONE {
        0.0
    } else if rank == 0 {
        // the facet touched last step: its spring may grow by the node's
        // motion towards it this step, not more. The gap's rule can switch
        // under a node (past a facet's start, the corner there sharpened
        // past the 30° up to which the previous facet's line bounds the
        // body, and a node 4 cm from it went from 4 µm to 21 mm deep in
        // one step: 4.7 MJ from nothing in the paper-scale run); what it
        // jumps by goes into the offset
        let most = (state.depth - state.offset).max(0.0) * (1.0 + DEPTH_SLACK)
            + 2.0 * gap_rate.abs() * inp.dt
            + 1e-12 * facet.length;
        state.offset.min(depth).max(0.0).max(depth - most)
    } else {
        state.offset.min(depth).max(0.0)
    };
    let spring = alpha_n * (depth - offset);
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
    *state = ContactState { facet: f, resumed: NONE, elastic_gap: new_gap, depth, offset };
    acc.contacts += 1;
    acc.friction += work;
    acc.stored += 0.5 * alpha_n * (depth - offset) * (depth - offset) + 0.5 * alpha_t * new_gap * new_gap;
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
