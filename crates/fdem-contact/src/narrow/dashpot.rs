//! The contacts' normal dashpots as the node pass applies them: on the
//! predicted velocities, by a backward-Euler step with each node's mass
//! shared among the dashpots on it ([`Dashpot`]); each dashpot's force is
//! worked out in parallel ([`dashpot_forces`]) and the forces are added up
//! per boundary node in a fixed order ([`assemble_dashpots`](super::assemble_dashpots)).

use rayon::prelude::*;

use super::NodeContact;
use crate::{Vec2, CHUNK};

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

/// One contact's dashpot as the node pass applies it ([`Dashpot`]),
/// gathered by [`dashpot_forces`] (in parallel) so that
/// [`assemble_dashpots`](super::assemble_dashpots) reads one record per dashpot.
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

/// Each listed contact's dashpot force into `links` (one per entry of
/// `dashpots`, the list of [`assemble`]), from the predicted velocities `v`
/// and the masses `mass` (by mesh id; `nodes` maps boundary index to mesh
/// id), the dashpot counts `damped` of [`assemble`] (per boundary node) and
/// the velocity step `h` (s): `f_d = max(−c ġᵉ / (1 + c h / μ), −f_s)`
/// ([`Dashpot`]), each node's mass shared among the dashpots on it (a
/// massless node moves with nothing: no term). In parallel.
///
/// [`assemble`]: super::assemble
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::narrow::assemble;
    use crate::NONE;

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
        assemble(
            [&contacts[0], &contacts[1]],
            &busy,
            &mut fs,
            &mut ds,
            &mut damped,
            &mut ids,
            &mut crate::narrow::Scatter::default(),
        );
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
}
