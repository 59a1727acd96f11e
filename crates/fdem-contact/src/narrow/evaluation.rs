//! The narrow phase's pass over the boundary nodes, parallel over fixed
//! chunks: its inputs ([`NarrowInputs`]) and outputs ([`Contacts`], one
//! [`ContactPartial`] per chunk), the busy flags that let it skip the nodes
//! with no memory and no candidate, and per node the search and the
//! response of each of its contacts. Right after a topology change, the
//! nodes the change left as they were keep their contacts
//! ([`evaluate_after_change`]).

use rayon::prelude::*;

use fdem_mesh::Csr;

use super::projection::projects_inside;
use super::response::{held_energy, respond};
use super::search::Search;
use super::{ContactState, FacetFrame, NodeContact};
use crate::law::InterfaceLaw;
use crate::surface::Surface;
use crate::{Vec2, CHUNK, NONE};

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

/// Inputs of the narrow phase.
pub struct NarrowInputs<'a> {
    /// Node positions `x^{n+1}` (m).
    pub x: &'a [Vec2],
    /// Node positions in the reference configuration (m): two facets whose
    /// ends lie at the same reference points, in reverse order, are the two
    /// faces of one crack or joint (item 7 of docs/contact.md). Every
    /// node's, or empty: then no facet has a twin.
    pub x_ref: &'a [Vec2],
    /// Node velocities `v^{n+½}` (m/s).
    pub v: &'a [Vec2],
    /// Node masses (kg/m).
    pub mass: &'a [f64],
    /// The surfaces.
    pub surface: &'a Surface,
    /// Every facet's frame at `x` ([`facet_frames`]).
    ///
    /// [`facet_frames`]: super::facet_frames
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

/// The contacts of the boundary nodes: per node a first contact and a
/// second one. At a corner of its body ([`Surface::faces`]) each of the
/// corner's two faces bears on the other bodies by itself; on a smooth
/// stretch the second bears on a second body the node lies deeper in than
/// in the first's (where three bodies meet; `Search::run`). A corner
/// node pushed out diagonally (prestressed rock at a joint crossing) needs
/// a force on each face; with a single contact it can press on one facet
/// only and the rock around the corner ends up in tension (measured: +2 MPa
/// at an X crossing of joints along the principal axes of a K0 state).
#[derive(Debug)]
pub struct Contacts<'a> {
    /// First contact's memory, per boundary node.
    pub states: &'a mut [ContactState],
    /// Second contact's memory, per boundary node.
    pub corner_states: &'a mut [ContactState],
    /// First contact of this step, per boundary node.
    pub out: &'a mut [NodeContact],
    /// Second contact of this step, per boundary node (facet [`NONE`]
    /// where there is none).
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
///
/// In parallel: it reads every memory (some 5 MB late in the paper-scale
/// run) at every crack insertion.
pub fn mark_busy(states: &[ContactState], corner_states: &[ContactState], busy: &mut [u8]) {
    busy.par_iter_mut().zip(states).zip(corner_states).with_min_len(CHUNK).for_each(|((f, s), s2)| {
        *f = u8::from(*s != ContactState::default()) | u8::from(*s2 != ContactState::default()) << 1;
    });
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
///
/// [`Dashpot`]: super::Dashpot
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
                    let faces = inp.surface.faces[b];
                    for (k, (state, contact)) in [(&st[j], &oc[j]), (&st2[j], &oc2[j])].into_iter().enumerate() {
                        if busy[j] & (1 << k) != 0 && contact.facet != NONE {
                            acc.contacts += 1;
                            acc.kept += 1;
                            let face = (faces[0] != NONE).then(|| faces[k]);
                            acc.stored += held_energy(inp, b, face, contact, state);
                        }
                    }
                    continue;
                }
                busy[j] = evaluate_node(inp, b, [&mut st[j], &mut st2[j]], [&mut oc[j], &mut oc2[j]], &mut acc);
            }
            *part = acc;
        });
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
    let mut busy = 0;
    for k in 0..2 {
        let face = (slots == 2).then(|| faces[k]);
        match best[k] {
            Some((r, f, xi, gap, ..)) => {
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

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::narrow::facet_frames;

    /// One evaluation from the given memories of both contacts: both
    /// contacts of every node and the chunk partials.
    pub(in crate::narrow) fn evaluate_once(
        inp: &NarrowInputs<'_>,
        mut states: Vec<ContactState>,
        mut corner_states: Vec<ContactState>,
    ) -> ([Vec<NodeContact>; 2], Vec<ContactPartial>) {
        evaluate_in_place(inp, &mut states, &mut corner_states)
    }

    /// [`evaluate_once`], leaving the updated memories in place.
    pub(in crate::narrow) fn evaluate_in_place(
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
            x_ref: &[],
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
