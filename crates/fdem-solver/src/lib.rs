//! The state and the time loop of fdem (DESIGN §3, §4.2).
//!
//! [`Simulation`] owns every array a step reads or writes, in
//! struct-of-arrays form indexed by `u32` node and element ids, and advances
//! it with the modified central-difference scheme. One step:
//!
//! 1. node pass (parallel over nodes): gather the element forces of each node
//!    through the node→element CSR list in a fixed order, add body and
//!    surface forces, update the half-step velocity with mass-proportional
//!    damping, apply supports and prescribed velocities, move the node;
//! 2. element pass (parallel over elements): co-rotational kinematics,
//!    stress update through the material law, internal forces on the new
//!    configuration, inverted-element check;
//! 3. surface loads (follower pressure) on the new configuration.
//!
//! Both passes work on fixed-size chunks whose partial sums (energies,
//! first bad entity) are reduced in chunk order, so a run is bit-for-bit the
//! same for any number of threads.

mod bonds;
mod checkpoint;
mod clock;
mod contact;
mod energy;
mod error;
mod excavation;
mod fracture;
mod lineage;
mod loads;
pub mod material_point;
mod model;
mod passes;
mod readout;
mod renumber;
mod setup;
mod simulation;
mod stable_step;
mod sums;
mod topology;

/// Steps between checks of the energy-growth watchdog
/// ([`Settings::energy_growth`]).
pub const ENERGY_CHECK_INTERVAL: u64 = 50;

/// Steps between the spatial renumberings that motion calls for, as the
/// block-caving case sets [`Settings::renumber_every`] (and as every run
/// with [`Settings::renumber`] did before checkpoint format 11): besides
/// the ones crack insertion's growth triggers, the kernel renumbers at
/// every multiple of this step count. Falling and mixing rock spoils the order as surely as
/// new elements do: at 3.5 s of the paper-scale caving run, where few
/// cracks open, a renumbering (60 ms on 2 threads, about four steps) made
/// the step 16% faster, and the gain wore off over about 2 500 steps
/// (docs/renumbering.md).
pub const RENUMBER_INTERVAL: u64 = 1000;

pub use checkpoint::{CheckpointError, FORMAT_VERSION as CHECKPOINT_FORMAT};
pub use energy::Energies;
pub use error::{RunError, SetupError};
pub use fdem_contact::{Bond, MixedMode};
pub use fdem_fracture::FractureParams;
pub use fdem_material::{CrackBand, PlasticState, Softening};
pub use fdem_mesh::validate as validate_mesh;
pub use fracture::InsertionAudit;

/// Mesh generation and editing, re-exported for the bindings.
pub mod mesh {
    pub use fdem_mesh::generate::{triangulate, triangulate_uniform, GenerateError, Generated};
    pub use fdem_mesh::split::split_along_edges;
}
pub use fdem_core::CHUNK;
pub(crate) use fdem_core::NONE;
pub use loads::{Amplitude, Constraint, PressureLoad};
pub use model::{
    ContactSpec, ExcavationStage, FractureSpec, InterfaceSpec, LawSpec, MaterialSpec, ModelSpec, Release, Settings,
};
pub use simulation::{ContactInfo, ContactStats, PhaseTimes, Simulation};
