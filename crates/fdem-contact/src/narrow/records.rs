//! The contact records of one boundary node: what it remembers between
//! steps ([`ContactState`]) and its contact in this step ([`NodeContact`],
//! whose force is worked out from its normal and tangential forces and its
//! dashpot's normal), each with the form checkpoints hold of it.

use super::Dashpot;
use crate::surface::Surface;
use crate::{Vec2, NONE};

/// What a boundary node remembers between steps. 32 bytes: it is read and
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
    ///
    /// [`NarrowInputs::resumed`]: super::NarrowInputs::resumed
    pub resumed: u32,
    /// Elastic tangential gap `g_tᵉ` (m), carried over to an adjacent facet.
    pub elastic_gap: f64,
    /// The penetration (m, ≥ 0) at the last evaluation (for a resumed
    /// contact: before the topology change). A contact that moves to
    /// another facet, other than by entering it through its line, may be no
    /// deeper than this plus the step's approach: its spring energy would
    /// otherwise jump without work.
    pub depth: f64,
    /// Penetration (m, ≥ 0) the spring does not count: the depth beyond the
    /// spring it had at which a node found already inside a facet's
    /// element, without entering it through its line, was taken up
    /// (docs/contact.md, "Which facet a node touches", item 7). The spring
    /// acts on `depth − offset` only, so taking it up holds the node where
    /// it is without energy from nothing; the offset follows the node out
    /// as it backs off and never grows. Zero for a contact entered through
    /// the facet's line. Checkpoints keep the non-zero ones (format 12).
    pub offset: f64,
}

impl Default for ContactState {
    fn default() -> Self {
        Self { facet: NONE, resumed: NONE, elastic_gap: 0.0, depth: 0.0, offset: 0.0 }
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
        ContactState { facet: s.facet, resumed: NONE, elastic_gap: s.elastic_gap, depth: s.depth, offset: 0.0 }
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

impl NodeContact {
    /// Sets [`NodeContact::ends`] from the surface (after a restore).
    pub fn locate(&mut self, surface: &Surface) {
        if self.facet != NONE {
            self.ends = surface.facets[self.facet as usize].ends;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
