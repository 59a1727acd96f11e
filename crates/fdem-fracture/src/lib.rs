//! Fracture by the rotating-crack model (paper 2.4 and Fig. 2, DESIGN §4.4).
//!
//! * [`nodal`]: the nodal failure factor `F̄_p` and crack direction `θ̄_p`
//!   as area-weighted averages over the adjacent elements (eqs. 2.22–2.23),
//!   directions averaged as doubled-angle vectors.
//! * [`insertion`]: where a crack through a node goes (along an edge, or
//!   splitting the crossed element and its neighbour), planned on the mesh
//!   as it was at the check, without conflicts between insertions, and
//!   applied as topology edits the solver carries its data through.
//!
//! The crate knows no material: it sees connectivity, positions, and per
//! element a failure factor and a direction.

pub mod insertion;
pub mod nodal;

pub use fdem_core::Vec2;
pub use insertion::{plan, plan_in_order, Edits, FractureParams, NewNode, NodeFailure, PlanScratch};
pub use nodal::{direction_angle, doubled_direction, nodal_failure};
