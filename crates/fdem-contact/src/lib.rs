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
pub use cohesive::{Bond, BondResponse, Kink, MixedMode};
pub use fdem_core::{Vec2, CHUNK, NONE};
pub use law::{InterfaceLaw, LawError};
pub use narrow::{ContactState, Dashpot, NodeContact};
pub use surface::{Surface, SurfaceFacet};

/// Two adjacent facets whose normals differ by less than 30° continue one
/// surface; more is a corner.
pub(crate) const SMOOTH_COS: f64 = 0.866;
