//! Constant-strain triangle (CST) kernels for explicit plane-strain dynamics.
//!
//! Everything here is a pure function on one element: three node coordinates,
//! three node velocities, a stress. No mesh, no material law, no allocation.
//! The solver calls these in its parallel element loop.
//!
//! Conventions (DESIGN §2): SI units, tension positive, stress stored as
//! `[xx, yy, zz, xy]`, triangles counter-clockwise.
//!
//! * [`kinematics`]: areas, shape-function gradients, deformation gradient,
//!   polar rotation, rate of deformation.
//! * [`corotational`]: the Green–Naghdi co-rotational update of the paper's
//!   eqs. 2.17–2.20 split into the parts before and after the material law.
//! * [`forces`]: internal nodal forces `f = A Bᵀ σ` and lumped mass.
//! * [`stability`]: the element's own highest eigenfrequency of the lumped
//!   system, for the critical time step (DESIGN §4.2).

pub mod batch;
pub mod corotational;
pub mod forces;
pub mod kinematics;
pub mod stability;
pub mod tensor;

pub use fdem_core::Vec2;

/// The three nodes of one triangle, counter-clockwise.
pub type Tri<T> = [T; 3];

pub use corotational::{CorotationalFrame, StrainRate};
pub use forces::{internal_forces, lumped_mass};
pub use kinematics::{reference_inverse, signed_area, ReferenceShape};
pub use stability::{critical_time_step, max_frequency, max_frequency_deformed};
