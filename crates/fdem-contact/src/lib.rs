//! Contact between the free surfaces of an FDEM model (paper 2.1 and
//! appendix D, DESIGN §4.5).
//!
//! The contact crate knows no material: it receives node positions,
//! velocities and masses, the boundary facets with the index of their
//! interface law, and returns nodal forces.
//!
//! * [`law`]: interface laws (penalties, Coulomb friction, cohesion,
//!   damping) and the friction update of appendix D.
//! * [`surface`]: the free surfaces of the current mesh: facets, boundary
//!   nodes, tributary lengths.
//! * [`broad`]: candidate (node, facet) pairs from a parry2d BVH of facet
//!   boxes enlarged by a margin, kept until some node has moved more than
//!   half the margin.
//! * [`cohesive`]: bonds that carry the rest of the fracture energy across
//!   a crack inserted before its material had fully softened.
//! * [`narrow`]: node-to-segment projection, penetration, forces spread to
//!   the facet's nodes by its shape functions (eq. 2.7), assembly.

pub mod broad;
pub mod cohesive;
pub mod law;
pub mod narrow;
pub mod surface;

pub use broad::BroadPhase;
pub use cohesive::{Bond, BondResponse, MixedMode};
pub use law::{InterfaceLaw, LawError};
pub use narrow::{ContactState, Dashpot, NodeContact};
pub use surface::{Surface, SurfaceFacet};

/// A 2D vector `[x, y]`.
pub type Vec2 = [f64; 2];

/// Boundary nodes (or facets) per parallel work item; fixed so that sums do
/// not depend on the thread count.
pub const CHUNK: usize = 1024;

/// Two adjacent facets whose normals differ by less than 30° continue one
/// surface; more is a corner.
pub(crate) const SMOOTH_COS: f64 = 0.866;

/// Marks "none" in index arrays.
pub const NONE: u32 = u32::MAX;
