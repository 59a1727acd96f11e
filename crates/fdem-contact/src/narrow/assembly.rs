//! The assembly of the contact forces: each contact's force spread to its
//! node and to the facet's two ends (eq. 2.7), in parallel over fixed
//! chunks of boundary nodes and in a fixed order, so that the sums do not
//! depend on the thread count ([`Scatter`]); and the list of the contacts
//! with a dashpot, for the node pass.

use rayon::prelude::*;

use super::NodeContact;
use crate::{Vec2, CHUNK, NONE};

/// Scratch of the chunked scatters ([`assemble`], and the dashpots'
/// [`assemble_dashpots`](super::assemble_dashpots)): per chunk of
/// [`CHUNK`] boundary nodes, what its contacts add to boundary nodes of
/// other chunks, and its contacts with a dashpot. Kept between steps, so
/// that the lists keep their capacity (no allocation once warm).
///
/// The order of the sums, the same on any thread count: a boundary node
/// first gets, in contact order, what the contacts of its own chunk add
/// (its own contacts and those whose facet it ends), then what each other
/// chunk's contacts add, chunk by chunk, each in contact order. With every
/// node in one chunk (fewer than [`CHUNK`] boundary nodes) that is contact
/// order, the order of the serial assembly this replaced.
#[derive(Debug, Default)]
pub struct Scatter {
    /// Per chunk: the contributions to boundary nodes of other chunks, as
    /// `4 (2b + k) + j`: share `j` ([`shares`]) of contact `k` of node `b`,
    /// worked out again when added (the same arithmetic, so the same bits;
    /// 4 bytes an entry instead of 40).
    cross: Vec<Cross>,
    /// Per chunk: dashpot counts on boundary nodes of other chunks.
    cross_damped: Vec<Vec<u32>>,
    /// Per chunk: its contacts with a dashpot (`2b + k`).
    dashpots: Vec<Vec<u32>>,
    /// Per chunk: the dashpots' contributions to boundary nodes of other
    /// chunks, as `4 l + j`: share `j` of link `l`.
    cross_dashpot: Vec<Cross>,
}

/// Entries each chunk's cross lists hold before they grow: an eighth of
/// what a chunk's contacts could send to other chunks (two contacts a
/// node, two facet ends each). About 7% of the contributions cross chunks
/// in the fragmenting impact with renumbering on (a chunk of 1 024 nodes
/// sends about 430), so the lists seldom grow; when one does, it keeps
/// its capacity (an allocation of the time loop, a few per chunk in a run).
/// With 4-byte entries the reserve is about 14 KB a chunk.
const CROSS_RESERVE: usize = CHUNK / 2;

/// One chunk's contributions to the boundary nodes of other chunks, in the
/// order its contacts made them, and the same sorted (stably) by the chunk
/// they go to, so that each receiving chunk adds its share from every
/// sending chunk in parallel with the others: chunk by chunk in order,
/// each in contact order, the order of a serial pass over the lists. (That
/// serial pass over about 7% of all contributions was 1% of a fragmenting
/// impact's run at one thread, and so a bound on its speed-up.) Each
/// receiving chunk reads the bounds of its run in every sending chunk's
/// list: chunks² reads a step, some 2 500 at the paper's scale.
#[derive(Debug, Default)]
struct Cross {
    /// The contributions (codes of the caller's), in contact order.
    codes: Vec<u32>,
    /// The receiving chunk of each.
    to: Vec<u32>,
    /// The codes sorted by receiving chunk, stably.
    sorted: Vec<u32>,
    /// Where each receiving chunk's run starts in `sorted` (chunks + 1).
    starts: Vec<u32>,
}

impl Cross {
    fn clear(&mut self) {
        self.codes.clear();
        self.to.clear();
    }

    fn push(&mut self, code: u32, to: usize) {
        self.codes.push(code);
        self.to.push((to / CHUNK) as u32);
    }

    fn reserve(&mut self, chunks: usize) {
        for list in [&mut self.codes, &mut self.to, &mut self.sorted] {
            list.reserve(CROSS_RESERVE.saturating_sub(list.len()));
        }
        self.starts.reserve((chunks + 1).saturating_sub(self.starts.len()));
    }

    /// Sorts the codes by receiving chunk (a counting sort: stable), for
    /// `chunks` chunks.
    fn sort(&mut self, chunks: usize) {
        let starts = &mut self.starts;
        starts.clear();
        starts.resize(chunks + 1, 0);
        for &t in &self.to {
            starts[t as usize + 1] += 1;
        }
        for c in 0..chunks {
            starts[c + 1] += starts[c];
        }
        self.sorted.resize(self.codes.len(), 0);
        // `starts[t]` runs on as chunk `t`'s entries are placed, and ends
        // where chunk `t + 1`'s begin: shifted back after
        for (&code, &t) in self.codes.iter().zip(&self.to) {
            let at = &mut starts[t as usize];
            self.sorted[*at as usize] = code;
            *at += 1;
        }
        for c in (1..=chunks).rev() {
            starts[c] = starts[c - 1];
        }
        starts[0] = 0;
    }

    /// The codes this chunk sends to chunk `to`, in contact order.
    fn to_chunk(&self, to: usize) -> &[u32] {
        &self.sorted[self.starts[to] as usize..self.starts[to + 1] as usize]
    }
}

impl Scatter {
    /// Sizes the lists for `boundary_nodes` boundary nodes (at a topology
    /// change): one per chunk, each with room for [`CROSS_RESERVE`] entries.
    pub fn reserve(&mut self, boundary_nodes: usize) {
        let chunks = boundary_nodes.div_ceil(CHUNK);
        self.size(chunks);
        for list in self.cross.iter_mut().chain(&mut self.cross_dashpot) {
            list.reserve(chunks);
        }
        for list in &mut self.cross_damped {
            list.reserve(CROSS_RESERVE.saturating_sub(list.len()));
        }
        for list in &mut self.dashpots {
            list.reserve((2 * CHUNK).saturating_sub(list.len()));
        }
    }

    fn size(&mut self, chunks: usize) {
        self.cross.resize_with(chunks, Cross::default);
        self.cross_damped.resize_with(chunks, Vec::new);
        self.dashpots.resize_with(chunks, Vec::new);
        self.cross_dashpot.resize_with(chunks, Cross::default);
    }
}

/// `f` on the node, `−(1−ξ) f` and `−ξ f` on the facet's ends (eq. 2.7),
/// as (boundary node, force) pairs for `[b, fa, fb]`; `x + −(w f)` is
/// `x − w f` to the bit.
#[inline(always)]
fn shares([b, fa, fb]: [usize; 3], xi: f64, f: Vec2) -> [(usize, Vec2); 3] {
    let neg = |w: f64| [-(w * f[0]), -(w * f[1])];
    [(b, f), (fa, neg(1.0 - xi)), (fb, neg(xi))]
}

/// Adds every contact force into `forces`, and the dashpot parts also into
/// `damping` (one entry per boundary node, zeroed first), in the order of
/// [`Scatter`], in parallel over chunks of boundary nodes: deterministic.
/// Counts in `damped` the dashpots that act on each boundary node (as the
/// node, or as a facet end with a non-zero weight), and lists the contacts
/// with a dashpot in `dashpots` (as `2b + k`, `k` = 0 for the first
/// contact, 1 for the second) in contact order. Reads the contacts of the
/// busy nodes only (`busy` as left by [`evaluate`]: a contact implies a
/// memory).
///
/// [`evaluate`]: super::evaluate
#[allow(clippy::too_many_arguments)]
pub fn assemble(
    contacts: [&[NodeContact]; 2],
    busy: &[u8],
    forces: &mut [Vec2],
    damping: &mut [Vec2],
    damped: &mut [u16],
    dashpots: &mut Vec<u32>,
    scratch: &mut Scatter,
) {
    let nb = busy.len();
    let chunks = nb.div_ceil(CHUNK);
    scratch.size(chunks);
    forces[nb..].iter_mut().for_each(|f| *f = [0.0; 2]);
    damping[nb..].iter_mut().for_each(|f| *f = [0.0; 2]);
    damped[nb..].iter_mut().for_each(|d| *d = 0);
    let Scatter { cross, cross_damped, dashpots: chunk_dashpots, .. } = scratch;
    forces[..nb]
        .par_chunks_mut(CHUNK)
        .zip(damping[..nb].par_chunks_mut(CHUNK))
        .zip(damped[..nb].par_chunks_mut(CHUNK))
        .zip(cross.par_iter_mut().zip(cross_damped.par_iter_mut()).zip(chunk_dashpots.par_iter_mut()))
        .enumerate()
        .for_each(|(c, (((fc, dc), nc), ((cross, cross_damped), ids)))| {
            fc.iter_mut().for_each(|f| *f = [0.0; 2]);
            dc.iter_mut().for_each(|f| *f = [0.0; 2]);
            nc.iter_mut().for_each(|d| *d = 0);
            cross.clear();
            cross_damped.clear();
            ids.clear();
            let base = c * CHUNK;
            let len = fc.len();
            let local = |t: usize| t.wrapping_sub(base) < len;
            for j in 0..len {
                let b = base + j;
                let flags = busy[b];
                if flags == 0 {
                    continue;
                }
                for k in 0..2 {
                    let ct = &contacts[k][b];
                    if flags & (1 << k) == 0 || ct.facet == NONE {
                        continue;
                    }
                    let [fa, fb] = ct.ends.map(|i| i as usize);
                    let fs = shares([b, fa, fb], ct.xi, ct.force());
                    let ds = shares([b, fa, fb], ct.xi, ct.damping_force());
                    for (j, ((t, wf), (_, wd))) in fs.into_iter().zip(ds).enumerate() {
                        if local(t) {
                            let i = t - base;
                            for e in 0..2 {
                                fc[i][e] += wf[e];
                                dc[i][e] += wd[e];
                            }
                        } else {
                            cross.push(4 * (2 * b as u32 + k as u32) + j as u32, t);
                        }
                    }
                    if ct.dashpot.coefficient > 0.0 {
                        ids.push(2 * b as u32 + k as u32);
                        for (t, w) in [(b, 1.0), (fa, 1.0 - ct.xi), (fb, ct.xi)] {
                            if w > 0.0 {
                                if local(t) {
                                    nc[t - base] = nc[t - base].saturating_add(1);
                                } else {
                                    cross_damped.push(t as u32);
                                }
                            }
                        }
                    }
                }
            }
            cross.sort(chunks);
        });
    // what crosses chunks: each receiving chunk from every sending chunk in
    // order ([`Cross`])
    let cross = &*cross;
    forces[..nb].par_chunks_mut(CHUNK).zip(damping[..nb].par_chunks_mut(CHUNK)).enumerate().for_each(
        |(to, (fc, dc))| {
            let base = to * CHUNK;
            for list in cross {
                for &code in list.to_chunk(to) {
                    let (id, j) = ((code / 4) as usize, (code % 4) as usize);
                    let (b, ct) = (id / 2, &contacts[id % 2][id / 2]);
                    let ends = [b, ct.ends[0] as usize, ct.ends[1] as usize];
                    let (t, wf) = shares(ends, ct.xi, ct.force())[j];
                    let (_, wd) = shares(ends, ct.xi, ct.damping_force())[j];
                    for e in 0..2 {
                        fc[t - base][e] += wf[e];
                        dc[t - base][e] += wd[e];
                    }
                }
            }
        },
    );
    for list in cross_damped.iter() {
        for &t in list {
            damped[t as usize] = damped[t as usize].saturating_add(1);
        }
    }
    dashpots.clear();
    for ids in chunk_dashpots.iter() {
        dashpots.extend_from_slice(ids);
    }
}

/// Adds each dashpot's force (`links`, in contact order, as
/// [`dashpot_forces`](super::dashpot_forces) left them) into `out` (per
/// boundary node, zeroed first): on the node and, weighted, on the facet's
/// ends (eq. 2.7), in the order of [`Scatter`], in parallel over chunks of
/// boundary nodes.
pub fn assemble_dashpots(links: &[super::DashpotLink], out: &mut [Vec2], scratch: &mut Scatter) {
    let nb = out.len();
    let chunks = nb.div_ceil(CHUNK);
    scratch.size(chunks);
    let cross = &mut scratch.cross_dashpot;
    out.par_chunks_mut(CHUNK).zip(cross.par_iter_mut()).enumerate().for_each(|(c, (oc, cross))| {
        oc.iter_mut().for_each(|f| *f = [0.0; 2]);
        cross.clear();
        let base = c * CHUNK;
        // the links of this chunk's nodes: links are in contact order
        let first = links.partition_point(|l| (l.bnodes[0] as usize) < base);
        let last = links.partition_point(|l| (l.bnodes[0] as usize) < base + oc.len());
        for (n, l) in links[first..last].iter().enumerate() {
            for (j, (t, wf)) in link_shares(l).into_iter().enumerate() {
                if t.wrapping_sub(base) < oc.len() {
                    let i = t - base;
                    oc[i][0] += wf[0];
                    oc[i][1] += wf[1];
                } else {
                    cross.push(4 * (first + n) as u32 + j as u32, t);
                }
            }
        }
        cross.sort(chunks);
    });
    let cross = &*cross;
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(to, oc)| {
        let base = to * CHUNK;
        for list in cross {
            for &code in list.to_chunk(to) {
                let (t, wf) = link_shares(&links[(code / 4) as usize])[(code % 4) as usize];
                oc[t - base][0] += wf[0];
                oc[t - base][1] += wf[1];
            }
        }
    });
}

/// A dashpot link's force (along its normal) as [`shares`].
#[inline(always)]
fn link_shares(l: &super::DashpotLink) -> [(usize, Vec2); 3] {
    shares(l.bnodes.map(|i| i as usize), l.xi, [l.force * l.normal[0], l.force * l.normal[1]])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::narrow::{assemble_dashpots, dashpot_forces, Dashpot, DashpotLink};

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
        assemble([&first, &corner], &busy, &mut forces, &mut damping, &mut damped, &mut ids, &mut Scatter::default());
        let nodes: Vec<u32> = (0..nb as u32).map(|b| 10 + b).collect();
        let mass: Vec<f64> = (0..nb + 10).map(|i| 1.0 + i as f64).collect();
        let v: Vec<Vec2> = (0..nb + 10).map(|i| [0.1 * i as f64, 0.3 - 0.05 * i as f64]).collect();
        let mut links = vec![DashpotLink::default(); ids.len()];
        dashpot_forces([&first, &corner], &ids, &nodes, &damped, &mass, &v, 0.1, &mut links);
        let computed: Vec<f64> = links.iter().map(|l| l.force).collect();
        let fd: Vec<f64> = (0..links.len()).map(|i| 0.5 + i as f64).collect();
        links.iter_mut().zip(&fd).for_each(|(l, &f)| l.force = f);
        assemble_dashpots(&links, &mut dashpot_sum, &mut Scatter::default());
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

    /// Over several chunks of boundary nodes the sums follow the order of
    /// [`Scatter`] (each node: its own chunk's contacts in contact order,
    /// then every other chunk's, chunk by chunk), bit for bit, on 1 and 3
    /// threads, for the contact forces, their dashpot parts, the dashpot
    /// counts and list, and the dashpots' scatter.
    #[test]
    fn the_chunked_assembly_sums_in_its_documented_order_on_any_thread_count() {
        let nb = 2 * CHUNK + CHUNK / 2;
        // a small deterministic generator (no dependency for one test)
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let empty = NodeContact { facet: NONE, ..Default::default() };
        let mut contacts = [vec![empty; nb], vec![empty; nb]];
        let mut busy = vec![0u8; nb];
        for b in 0..nb {
            for k in 0..2 {
                if next() % 3 == 0 {
                    continue;
                }
                // facet ends near the node mostly, anywhere now and then
                let near = |r: u64| ((b as u64 + r % 40 + nb as u64 - 20) % nb as u64) as u32;
                let (ra, rb) = (next(), next());
                let ends = if ra % 10 == 0 { [(ra % nb as u64) as u32, near(rb)] } else { [near(ra), near(rb)] };
                let f = (next() % 1000) as f64 * 1e3 - 4e5;
                contacts[k][b] = NodeContact {
                    facet: (next() % 5000) as u32,
                    xi: (next() % 1001) as f64 / 1000.0,
                    normal_force: f,
                    tangential_force: 0.37 * f,
                    dashpot: Dashpot {
                        normal: [0.6, -0.8],
                        coefficient: if next() % 4 == 0 { 0.0 } else { 1.0 + f.abs() },
                        spring: 1.0,
                    },
                    ends,
                    ..empty
                };
                busy[b] |= 1 << k;
            }
        }
        // the documented order, written out
        let chunk = |t: usize| t / CHUNK;
        let mut want_f = vec![[0.0; 2]; nb];
        let mut want_d = vec![[0.0; 2]; nb];
        let mut want_n = vec![0u16; nb];
        let mut want_ids = Vec::new();
        for pass in 0..=nb.div_ceil(CHUNK) {
            // pass 0: every node's own chunk; pass p: what chunk p − 1 adds elsewhere
            for b in 0..nb {
                for k in 0..2 {
                    let c = &contacts[k][b];
                    if c.facet == NONE {
                        continue;
                    }
                    if pass == 0 && c.dashpot.coefficient > 0.0 {
                        want_ids.push(2 * b as u32 + k as u32);
                    }
                    let [fa, fb] = c.ends.map(|i| i as usize);
                    for (t, wf) in shares([b, fa, fb], c.xi, c.force()) {
                        let mine = chunk(t) == chunk(b);
                        if (pass == 0 && mine) || (pass > 0 && !mine && chunk(b) == pass - 1) {
                            want_f[t][0] += wf[0];
                            want_f[t][1] += wf[1];
                        }
                    }
                    for (t, wd) in shares([b, fa, fb], c.xi, c.damping_force()) {
                        let mine = chunk(t) == chunk(b);
                        if (pass == 0 && mine) || (pass > 0 && !mine && chunk(b) == pass - 1) {
                            want_d[t][0] += wd[0];
                            want_d[t][1] += wd[1];
                        }
                    }
                    if pass == 0 && c.dashpot.coefficient > 0.0 {
                        for (t, w) in [(b, 1.0), (fa, 1.0 - c.xi), (fb, c.xi)] {
                            want_n[t] += u16::from(w > 0.0);
                        }
                    }
                }
            }
        }
        assert!(want_ids.len() > 1000);
        let links: Vec<DashpotLink> = want_ids
            .iter()
            .map(|&id| {
                let c = &contacts[(id % 2) as usize][(id / 2) as usize];
                DashpotLink {
                    bnodes: [id / 2, c.ends[0], c.ends[1]],
                    xi: c.xi,
                    normal: c.dashpot.normal,
                    force: 1.0 + (id % 97) as f64,
                }
            })
            .collect();
        let mut want_p = vec![[0.0; 2]; nb];
        for pass in 0..=nb.div_ceil(CHUNK) {
            for l in &links {
                let b = l.bnodes[0] as usize;
                let f = [l.force * l.normal[0], l.force * l.normal[1]];
                for (t, wf) in shares(l.bnodes.map(|i| i as usize), l.xi, f) {
                    let mine = chunk(t) == chunk(b);
                    if (pass == 0 && mine) || (pass > 0 && !mine && chunk(b) == pass - 1) {
                        want_p[t][0] += wf[0];
                        want_p[t][1] += wf[1];
                    }
                }
            }
        }
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (mut f, mut d, mut n, mut ids, mut p) =
                (vec![[9.0; 2]; nb], vec![[9.0; 2]; nb], vec![9u16; nb], vec![7u32], vec![[9.0; 2]; nb]);
            let mut scratch = Scatter::default();
            pool.install(|| {
                assemble([&contacts[0], &contacts[1]], &busy, &mut f, &mut d, &mut n, &mut ids, &mut scratch);
                assemble_dashpots(&links, &mut p, &mut scratch);
            });
            assert!(f == want_f && d == want_d, "forces on {threads} threads");
            assert_eq!(n, want_n);
            assert_eq!(ids, want_ids);
            assert!(p == want_p, "dashpots on {threads} threads");
        }
    }
}
