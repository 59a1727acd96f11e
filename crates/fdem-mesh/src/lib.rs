//! Triangle-mesh topology shared by the fdem crates.
//!
//! Node and element ids are `u32` indices into flat arrays (DESIGN §2).
//! Triangles are counter-clockwise; edge `k` of a triangle runs from its
//! vertex `k` to vertex `(k + 1) % 3`, so a boundary facet taken in that
//! direction has the body on its left and its outward normal is the edge
//! direction rotated clockwise.
//!
//! * [`csr`]: compressed sparse rows, for node→element and node→facet lists
//!   that let the solver gather per node in a fixed order.
//! * [`validate`]: checks of user meshes that name the offending entity.
//! * [`edges`]: unique edges, their adjacent elements and the free facets.
//! * [`generate`]: quality meshes conforming to segments (joint traces).
//! * [`split`]: opening edges into interfaces by duplicating nodes.

pub mod csr;
pub mod edges;
pub mod generate;
pub mod split;
pub mod validate;

pub use csr::Csr;
pub use edges::{boundary_facets, edge_adjacency, EdgeAdjacency, Facet};
pub use validate::{validate, MeshError};

/// Node id.
pub type NodeId = u32;
/// Element id.
pub type ElemId = u32;
/// A point `[x, y]` (m).
pub type Point = fdem_core::Vec2;

/// Node→element incidence as a CSR list whose items encode
/// `element * 3 + local vertex`, sorted by element id for each node.
pub fn node_elements(n_nodes: usize, triangles: &[[u32; 3]]) -> Csr {
    Csr::from_pairs(
        n_nodes,
        triangles.iter().enumerate().flat_map(|(e, t)| (0..3).map(move |k| (t[k] as usize, (e * 3 + k) as u32))),
    )
}
