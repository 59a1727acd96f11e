//! DESIGN's rule for the time loop: no allocation in a step except on a
//! topology change. A global allocator that counts calls watches steps of
//! a contacting, yielding run with no crack insertions (fracture off):
//! after a warm-up that lets every buffer reach its size, not one
//! allocation, on 1 and on 2 threads.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

#[path = "../../fdem-solver/tests/common/impact.rs"]
mod impact;
use fdem_solver::Simulation;
use impact::impact;

struct Counting;

static CALLS: AtomicU64 = AtomicU64::new(0);

/// The counter is global: the tests take turns (the harness runs them on
/// threads side by side).
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

// SAFETY: forwards every call to the system allocator unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        CALLS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        CALLS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

#[test]
fn contacting_yielding_steps_allocate_nothing() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for threads in [1, 2] {
        // the impact without crack insertion: the block lands on the platen
        // at step 80 and bounces off at about step 300; steps 150-290 are
        // in contact, yielding and ringing
        let mut spec = impact(24, 12);
        spec.fracture = None;
        let built = CALLS.load(Ordering::Relaxed);
        let mut sim = Simulation::new(spec, threads).expect("the impact model is valid");
        assert!(CALLS.load(Ordering::Relaxed) > built, "the counting allocator is not the one in use");
        sim.step(150).expect("warm-up");
        let (plastic, friction) = (sim.energies().plastic, sim.energies().friction);
        let before = CALLS.load(Ordering::Relaxed);
        sim.step(140).expect("the impact runs");
        let calls = CALLS.load(Ordering::Relaxed) - before;
        let contacts = sim.contact_stats().contacts;
        assert!(contacts > 20, "the block should press on the platen: {contacts} contacts");
        let e = sim.energies();
        assert!(e.plastic > plastic && e.friction > friction, "the block should yield and slide while watched");
        assert_eq!(calls, 0, "{calls} allocations in 140 steps on {threads} threads");
    }
}

#[test]
fn fracture_checks_that_insert_nothing_allocate_nothing() {
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for threads in [1, 2] {
        // the impact with crack insertion, watched in flight before it lands
        // (step 80): a fracture check every 5 steps, none inserting
        let mut sim = Simulation::new(impact(24, 12), threads).expect("the impact model is valid");
        sim.step(10).expect("warm-up");
        let before = CALLS.load(Ordering::Relaxed);
        sim.step(60).expect("the impact runs");
        let calls = CALLS.load(Ordering::Relaxed) - before;
        assert_eq!(sim.insertions(), Some(0));
        assert_eq!(calls, 0, "{calls} allocations in 60 steps (12 fracture checks) on {threads} threads");
    }
}
