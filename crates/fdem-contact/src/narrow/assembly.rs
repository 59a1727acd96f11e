//! The sequential assembly of the contact forces: each contact's force
//! spread to its node and to the facet's two ends (eq. 2.7), node by node
//! in boundary-node order, so that the sums do not depend on the thread
//! count; and the list of the contacts with a dashpot, for the node pass.

use super::NodeContact;
use crate::{Vec2, NONE};

/// Adds every contact force into `forces`, and the dashpot parts also into
/// `damping` (one entry per boundary node, zeroed first), node by node in
/// boundary-node order (a node's first contact, then its corner's second):
/// deterministic. Counts in `damped` the dashpots that act on each boundary
/// node (as the node, or as a facet end with a non-zero weight), and lists
/// the contacts with a dashpot in `dashpots` (as `2b + k`, `k` = 0 for the
/// first contact, 1 for the second), in the same order. Reads the contacts
/// of the busy nodes only (`busy` as left by [`evaluate`]: a contact
/// implies a memory).
///
/// [`evaluate`]: super::evaluate
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

/// Adds the force `f` of a contact of node `b` on the facet `[fa, fb]` at
/// `ξ` into `out` (by boundary node): `f` on the node, `−(1−ξ) f` and `−ξ f`
/// on the facet's ends (eq. 2.7).
#[inline(always)]
pub(super) fn spread(out: &mut [Vec2], [b, fa, fb]: [usize; 3], xi: f64, f: Vec2) {
    for d in 0..2 {
        out[b][d] += f[d];
        out[fa][d] -= (1.0 - xi) * f[d];
        out[fb][d] -= xi * f[d];
    }
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
}
