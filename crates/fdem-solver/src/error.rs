//! Errors of model set-up and of a run, each naming the offending entity.

use fdem_material::ParameterError;
use fdem_mesh::MeshError;

/// A model that cannot be simulated.
#[derive(Clone, Debug, PartialEq)]
pub enum SetupError {
    /// The mesh failed validation.
    Mesh(MeshError),
    /// Material `index` has an invalid parameter.
    Material {
        /// Position in the material table.
        index: usize,
        /// The parameter problem.
        error: ParameterError,
    },
    /// Any other inconsistency (array length, id range, facet not on the
    /// boundary…), as a sentence naming the entity.
    Invalid(String),
}

impl std::fmt::Display for SetupError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SetupError::Mesh(e) => write!(f, "{e}"),
            SetupError::Material { index, error } => write!(f, "material {index}: {error}"),
            SetupError::Invalid(s) => f.write_str(s),
        }
    }
}

impl std::error::Error for SetupError {}

impl From<MeshError> for SetupError {
    fn from(e: MeshError) -> Self {
        SetupError::Mesh(e)
    }
}

/// A run that had to stop. The state is that of the failed step.
#[derive(Clone, Debug, PartialEq)]
pub enum RunError {
    /// An element's area became zero or negative (or not finite).
    InvertedElement {
        /// The element (if several, the first in the solver's internal
        /// order: the smallest id unless the run renumbers).
        element: u32,
        /// The step that produced it.
        step: u64,
        /// Simulated time at the end of that step (s).
        time: f64,
    },
    /// A nodal quantity became NaN or infinite.
    NonFinite {
        /// The node (if several, the first in the solver's internal order:
        /// the smallest id unless the run renumbers).
        node: u32,
        /// Which quantity (`velocity`, `position`).
        quantity: &'static str,
        /// The step.
        step: u64,
        /// Simulated time (s).
        time: f64,
    },
    /// The energy balance shows energy created (a numerical instability):
    /// `−residual` exceeded the watchdog's fraction of the largest term.
    EnergyGrowth {
        /// Energy created, `−residual` (J per unit thickness).
        created: f64,
        /// The largest term of the balance (J per unit thickness).
        largest: f64,
        /// The held energy (kinetic + elastic, J per unit thickness) at the
        /// check before and at this one.
        held: [f64; 2],
        /// The step at which the check found it.
        step: u64,
        /// Simulated time (s).
        time: f64,
    },
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::InvertedElement { element, step, time } => write!(
                f,
                "element {element} inverted (area <= 0) at step {step}, time {time:.6e} s; \
                 reduce the time-step safety factor or the load rate, or check the supports"
            ),
            RunError::NonFinite { node, quantity, step, time } => {
                write!(f, "{quantity} of node {node} became NaN or infinite at step {step}, time {time:.6e} s")
            }
            RunError::EnergyGrowth { created, largest, held, step, time } => write!(
                f,
                "energy grew without a source at step {step}, time {time:.6e} s: the balance shows {created:.4e} J \
                 created, {:.1}% of its largest term ({largest:.4e} J; kinetic + elastic {:.4e} J, {:.4e} J at the \
                 check before); the run is unstable or a contact creates energy (reduce the time-step safety \
                 factor or the contact stiffness; the threshold is the energy_growth setting)",
                100.0 * created / largest,
                held[1],
                held[0]
            ),
        }
    }
}

impl std::error::Error for RunError {}
