//! The free surfaces of a mesh: boundary facets with their interface law,
//! the boundary nodes, and per node its own facets.

use fdem_mesh::Csr;

use crate::{Vec2, NONE};

/// One boundary facet, oriented with the body on its left (outward normal
/// `(dy, −dx)/L`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceFacet {
    /// Start and end node (mesh ids).
    pub nodes: [u32; 2],
    /// Index of the interface law.
    pub law: u16,
    /// Reference length (m), for tributary lengths.
    pub length: f64,
    /// Deepest penetration accepted behind this facet (m): half the height
    /// of its element over it. A node deeper than this is on the far side.
    pub depth: f64,
    /// A stable identity that survives rebuilds of the surface (the solver
    /// uses `3 e + k`, edge `k` of element `e`), ascending along `facets`:
    /// lets the broad phase and the friction memory follow a facet through
    /// topology changes.
    pub key: u32,
    /// The boundary-node indices of `nodes` (derived, not saved: set by
    /// [`Surface::derive`]), so that a contact on this facet finds its
    /// nodes' rows without two more random reads of `index_of`.
    #[serde(skip)]
    pub ends: [u32; 2],
}

/// The free surfaces of the current mesh.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Surface {
    /// All boundary facets.
    pub facets: Vec<SurfaceFacet>,
    /// Mesh ids of the nodes on any facet, ascending.
    pub nodes: Vec<u32>,
    /// For every mesh node its index in `nodes`, or [`NONE`].
    pub index_of: Vec<u32>,
    /// For every boundary node (index in `nodes`) the facets it belongs to.
    pub node_facets: Csr,
    /// For every boundary node at a corner of its body (its two facets'
    /// normals more than 30° apart in the reference configuration, see
    /// [`Surface::derive`]) the facet ending at it and the facet starting
    /// from it: each face bears on the other bodies by itself (two contacts
    /// per corner node). `[NONE, NONE]` for a node on a smooth stretch of
    /// surface (one contact, along the node's mean normal) or on more than
    /// two facets. Derived data: not saved, rebuilt on restore.
    #[serde(skip)]
    pub faces: Vec<[u32; 2]>,
}

impl Surface {
    /// Builds the surface of a mesh with `n_nodes` nodes from its boundary
    /// facets `(nodes, law)`, the reference positions and, per facet, the
    /// reference position of its element's third node.
    /// Facets are keyed by their position; see [`Surface::with_keys`].
    pub fn new(n_nodes: usize, facets: &[([u32; 2], u16)], x_ref: &[Vec2], apex: &[Vec2]) -> Self {
        let keys: Vec<u32> = (0..facets.len() as u32).collect();
        Self::with_keys(n_nodes, facets, x_ref, apex, &keys)
    }

    /// [`Surface::new`] with a stable key per facet (strictly ascending).
    pub fn with_keys(n_nodes: usize, facets: &[([u32; 2], u16)], x_ref: &[Vec2], apex: &[Vec2], keys: &[u32]) -> Self {
        debug_assert!(keys.windows(2).all(|w| w[0] < w[1]));
        let mut surface_facets = Vec::with_capacity(facets.len());
        for (k, &([a, b], law)) in facets.iter().enumerate() {
            let (pa, pb) = (x_ref[a as usize], x_ref[b as usize]);
            let d = [pb[0] - pa[0], pb[1] - pa[1]];
            // a plain square root: `hypot` (careful about overflow, which
            // reference lengths never approach) is several times slower,
            // and surfaces are rebuilt at every crack insertion
            let length = (d[0] * d[0] + d[1] * d[1]).sqrt();
            let c = apex[k];
            let height = ((c[0] - pa[0]) * d[1] - (c[1] - pa[1]) * d[0]).abs() / length;
            surface_facets.push(SurfaceFacet {
                nodes: [a, b],
                law,
                length,
                depth: 0.5 * height,
                key: keys[k],
                ends: [NONE; 2],
            });
        }
        let mut on = vec![false; n_nodes];
        for f in &surface_facets {
            on[f.nodes[0] as usize] = true;
            on[f.nodes[1] as usize] = true;
        }
        let mut index_of = vec![NONE; n_nodes];
        let mut nodes = Vec::new();
        for (i, &o) in on.iter().enumerate() {
            if o {
                index_of[i] = nodes.len() as u32;
                nodes.push(i as u32);
            }
        }
        let node_facets = Csr::from_pairs(
            nodes.len(),
            surface_facets
                .iter()
                .enumerate()
                .flat_map(|(k, f)| f.nodes.map(|n| (index_of[n as usize] as usize, k as u32))),
        );
        let mut surface = Self { facets: surface_facets, nodes, index_of, node_facets, faces: Vec::new() };
        surface.derive(x_ref);
        surface
    }

    /// Sets the derived data that is not saved ([`SurfaceFacet::ends`],
    /// [`Surface::faces`]) from the rest and the reference positions
    /// `x_ref`: after building or restoring.
    pub fn derive(&mut self, x_ref: &[Vec2]) {
        let index_of = &self.index_of;
        for f in &mut self.facets {
            f.ends = f.nodes.map(|n| index_of[n as usize]);
        }
        self.find_faces(x_ref);
    }

    /// Fills [`Surface::faces`] from the reference positions `x_ref`: a
    /// boundary node with exactly two facets, one ending and one starting at
    /// it, whose outward normals differ by more than 30° (`n₁·n₂ <
    /// cos 30°`) is a corner. The test is on the reference configuration,
    /// so a node's kind changes only with the topology (its angle changes
    /// only with strain).
    fn find_faces(&mut self, x_ref: &[Vec2]) {
        let normal = |k: u32| self.facet_normal(x_ref, k);
        self.faces = (0..self.nodes.len())
            .map(|b| {
                let node = self.nodes[b];
                let row = self.node_facets.row(b);
                if row.len() != 2 {
                    return [NONE; 2];
                }
                let (k0, k1) = (row[0], row[1]);
                let [into, from] = if self.facets[k0 as usize].nodes[1] == node { [k0, k1] } else { [k1, k0] };
                if self.facets[into as usize].nodes[1] != node || self.facets[from as usize].nodes[0] != node {
                    return [NONE; 2];
                }
                let (m, n) = (normal(into), normal(from));
                if m[0] * n[0] + m[1] * n[1] < crate::SMOOTH_COS {
                    [into, from]
                } else {
                    [NONE; 2]
                }
            })
            .collect();
    }

    /// Outward normal (unit) of facet `f` at positions `x`: `(dy, −dx)/L`.
    /// (A plain square root: `hypot`'s care for overflow, which lengths of
    /// metres never approach, is several times slower, and topology
    /// changes compute this for every boundary node.)
    pub fn facet_normal(&self, x: &[Vec2], f: u32) -> Vec2 {
        let [a, b] = self.facets[f as usize].nodes;
        let (pa, pb) = (x[a as usize], x[b as usize]);
        let d = [pb[0] - pa[0], pb[1] - pa[1]];
        let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
        [d[1] / len, -d[0] / len]
    }

    /// Mean outward normal (unit) of boundary node `b` at positions `x`:
    /// the normalised sum of its facets' normals (zero where they cancel).
    /// The same numbers as the narrow phase's node normal from the facet
    /// frames at `x`.
    pub fn mean_normal(&self, x: &[Vec2], b: usize) -> Vec2 {
        let mut n = [0.0; 2];
        for &f in self.node_facets.row(b) {
            let m = self.facet_normal(x, f);
            n = [n[0] + m[0], n[1] + m[1]];
        }
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        if len > 0.0 {
            [n[0] / len, n[1] / len]
        } else {
            n
        }
    }

    /// Largest tributary length (m) boundary node `b` can have: half of each
    /// of its facets (for the stable step).
    pub fn tributary_max(&self, b: usize) -> f64 {
        self.node_facets.row(b).iter().map(|&k| 0.5 * self.facets[k as usize].length).sum()
    }

    /// Whether two facets share a node.
    pub fn adjacent(&self, f: u32, g: u32) -> bool {
        let (a, b) = (self.facets[f as usize].nodes, self.facets[g as usize].nodes);
        a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_surface() {
        // unit square, nodes 0..4 counter-clockwise, bottom facet a joint (law 1)
        let x = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let facets = [([0, 1], 1), ([1, 2], 0), ([2, 3], 0), ([3, 0], 0)];
        let apex = [[1.0, 1.0], [0.0, 0.0], [0.0, 0.0], [1.0, 1.0]];
        let s = Surface::new(4, &facets, &x, &apex);
        assert_eq!(s.nodes, vec![0, 1, 2, 3]);
        assert_eq!(s.tributary_max(0), 1.0);
        assert!(s.adjacent(0, 1) && !s.adjacent(0, 2));
        assert!((s.facets[0].depth - 0.5).abs() < 1e-15);
    }
}
