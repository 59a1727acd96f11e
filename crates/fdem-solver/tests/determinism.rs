//! Issue 34 (3): a fracturing, contacting run gives the same bits on any
//! thread count, and a restart on another thread count continues it bit
//! for bit (DESIGN §3). The case is the fragmenting impact of
//! `benchmarks/fracture_impact.py` on a small structured mesh, with
//! renumbering on: cracks, cohesive bonds, contacts with dashpots and
//! friction, insertions that change the surface every few checks.

mod common;
use common::impact::impact;
use fdem_solver::Simulation;

/// Steps of the run: past the first contact (about 60 steps), well into
/// fragmentation. The restart is taken at a step that is not a check step.
const STEPS: u64 = 700;
const RESTART_AT: u64 = 347;

fn run(threads: usize) -> Simulation {
    let mut sim = Simulation::new(impact(24, 12), threads).expect("the impact model is valid");
    sim.step(STEPS).expect("the impact runs");
    sim
}

#[test]
fn a_fragmenting_impact_is_bit_for_bit_on_1_2_3_and_16_threads_and_across_a_restart() {
    let one = run(1);
    // the case does what it is here for: it fractures, bonds and touches
    let cracks = one.insertions().unwrap_or(0);
    let contacts = one.contact_stats().contacts;
    // (1 176 cracks, 507 bonds and 1 408 contacts when written)
    assert!(cracks >= 200 && one.bonds().len() >= 100 && contacts >= 200, "{cracks} cracks, {contacts} contacts");
    let want = one.checkpoint_bytes(b"");
    for threads in [2, 3, 16] {
        let got = run(threads).checkpoint_bytes(b"");
        assert!(got == want, "{threads} threads diverged from 1");
    }
    // saved on 16 threads mid-run, restored on 3, run to the end
    let mut a = Simulation::new(impact(24, 12), 16).expect("the impact model is valid");
    a.step(RESTART_AT).expect("the impact runs");
    let saved = a.checkpoint_bytes(b"mid-run");
    drop(a);
    let (mut b, user) = Simulation::from_checkpoint_bytes(&saved, 3).expect("the checkpoint restores");
    assert_eq!(user, b"mid-run");
    b.step(STEPS - RESTART_AT).expect("the restored run goes on");
    assert!(b.checkpoint_bytes(b"") == want, "the run restored on 3 threads diverged");
}
