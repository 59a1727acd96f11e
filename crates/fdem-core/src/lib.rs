//! The small types and constants the fdem crates share, defined once.
//!
//! Every other crate depends on this one and re-exports what its own API
//! names (`fdem_element::Vec2`, `fdem_contact::CHUNK`, `fdem_solver::CHUNK`,
//! …), so that a crate's boundary (the material and the element know no
//! mesh, the contact knows no material) needs no other crate for them. It
//! holds no physics and depends on nothing.

/// A 2D vector `[x, y]` (m, m/s or N depending on use).
pub type Vec2 = [f64; 2];

/// Nodes, elements, boundary nodes or facets per parallel work item. Fixed,
/// so that partial sums (and therefore results) do not depend on the
/// thread count; one value for every crate, so that no two parallel loops
/// that must agree can be chunked differently.
pub const CHUNK: usize = 1024;

/// Marks "none" in index arrays.
pub const NONE: u32 = u32::MAX;
