//! A fingerprint of a fracturing, contacting run, for refactors that must
//! change no result bit: a rock block hits a fixed platen at 10 m/s (the
//! fragmenting impact of `benchmarks/fracture_impact.py` on a structured
//! mesh, with renumbering on), and the example prints a hash of the whole
//! saved state (`checkpoint_bytes`) at 1, 2 and 3 threads, with the cracks,
//! contacts and energy residual of the run. Run it before and after the
//! change and compare the lines.
//!
//! Run: `cargo run --release -p fdem-solver --example state_hash [steps]`

use std::hash::{DefaultHasher, Hasher};

use fdem_solver::Simulation;

#[path = "../tests/common/impact.rs"]
mod impact;
use impact::impact;

fn main() {
    let steps: u64 = std::env::args().nth(1).map_or(1500, |a| a.parse().expect("steps must be an integer"));
    let spec = impact(40, 20);
    for threads in [1, 2, 3] {
        let mut sim = Simulation::new(spec.clone(), threads).expect("the impact model is valid");
        sim.step(steps).expect("the impact runs");
        let mut hash = DefaultHasher::new();
        hash.write(&sim.checkpoint_bytes(b""));
        let e = sim.energies();
        println!(
            "threads {threads}: steps {} time {:e} elements {} insertions {:?} bonds {} contacts {} \
             residual {:e} state hash {:016x}",
            sim.steps(),
            sim.time(),
            sim.n_elements(),
            sim.insertions(),
            sim.bonds().len(),
            sim.contact_stats().contacts,
            e.residual(),
            hash.finish()
        );
    }
}
