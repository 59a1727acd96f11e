//! Narrow phase: node-to-segment penalty contact (paper 2.1, eqs. 2.3–2.7)
//! with Coulomb friction and cohesion (appendix D) and a compression-only
//! normal dashpot.
//!
//! One contact evaluation, in the order the solver runs it, file by file:
//!
//! * `projection.rs`: every facet's frame at the current positions, the
//!   projection of a node on a facet and the test that it lies behind it,
//!   node normals, the gap past a shallow convex corner.
//! * `evaluation.rs`: the parallel pass over the boundary nodes, its
//!   inputs, outputs, busy flags and per-chunk sums; per node, the search
//!   and the response of each contact (two at a corner of a body).
//! * `search.rs`: which candidate facet each contact of a node takes up.
//! * `response.rs`: the springs, dashpot estimate, friction and cohesion of
//!   one contact on its facet.
//! * `records.rs`: what a node remembers between steps and its contact in
//!   this step, with their saved forms.
//! * `assembly.rs`: the sums of the contact forces and of the dashpots'
//!   per boundary node, in parallel over fixed chunks, in a fixed order.
//! * `dashpot.rs`: the dashpots' forces on the predicted velocities, in the
//!   node pass.

mod assembly;
mod dashpot;
mod evaluation;
mod projection;
mod records;
mod response;
mod search;

pub use assembly::{assemble, assemble_dashpots, Scatter};
pub use dashpot::{dashpot_forces, Dashpot, DashpotLink};
pub use evaluation::{evaluate, evaluate_after_change, mark_busy, ContactPartial, Contacts, NarrowInputs};
pub(crate) use projection::XI_SLACK;
pub use projection::{facet_frames, project, FacetFrame};
pub use records::{ContactState, NodeContact};
