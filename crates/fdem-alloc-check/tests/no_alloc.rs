//! DESIGN's rule for the time loop: no allocation in a step except on a
//! topology change. A global allocator counts the allocations made while
//! a window of steps runs, after a warm-up that lets every buffer reach its
//! size: steps of a contacting, yielding run with the broad phase rebuilt
//! every few steps (fracture off), steps with fracture checks that
//! insert nothing, and steps whose bonds (young cracks) neither grow nor
//! break; on 1 and 2 threads, none of fdem's. A check whose candidates
//! cannot separate plans them and inserts nothing: its planning is
//! watched by itself too.
//!
//! rayon's scheduler allocates now and then on more than one thread (the
//! garbage bags of crossbeam-epoch, under its work-stealing deques): an
//! allocation in the window is looked up in its backtrace, and those are
//! left out.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

#[path = "../../fdem-solver/tests/common/impact.rs"]
mod impact;
use fdem_solver::Simulation;
use impact::impact;

struct Counting;

/// Every allocation (and reallocation) since start.
static CALLS: AtomicU64 = AtomicU64::new(0);
/// Whether a window is being watched.
static WATCH: AtomicBool = AtomicBool::new(false);
/// In the window: fdem's allocations (all but the scheduler's), with the
/// backtrace of the first.
static OURS: AtomicU64 = AtomicU64::new(0);
static FIRST: Mutex<String> = Mutex::new(String::new());

thread_local! {
    /// Set while this thread looks up an allocation (which allocates).
    static LOOKING: Cell<bool> = const { Cell::new(false) };
}

/// Counts one allocation, and in a window finds whose it is.
fn count() {
    CALLS.fetch_add(1, Ordering::Relaxed);
    if !WATCH.load(Ordering::Relaxed) || LOOKING.with(Cell::get) {
        return;
    }
    LOOKING.with(|l| l.set(true));
    let trace = std::backtrace::Backtrace::force_capture().to_string();
    // the scheduler's: its epoch garbage, and its queues of jobs (the
    // injector that takes each `install` from outside the pool adds a
    // block every 63 jobs, so a step now and then allocates one)
    let scheduler = trace.contains("crossbeam_epoch") || trace.contains("<rayon_core::job::JobRef>");
    if !scheduler && OURS.fetch_add(1, Ordering::Relaxed) == 0 {
        *FIRST.lock().unwrap_or_else(|e| e.into_inner()) = trace;
    }
    LOOKING.with(|l| l.set(false));
}

// SAFETY: forwards every call to the system allocator unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Runs `steps` steps of `sim` as a watched window: fdem's allocations in
/// it, with the backtrace of the first.
fn window(sim: &mut Simulation, steps: u64) -> (u64, String) {
    OURS.store(0, Ordering::Relaxed);
    WATCH.store(true, Ordering::Relaxed);
    sim.step(steps).expect("the impact runs");
    WATCH.store(false, Ordering::Relaxed);
    let ours = OURS.load(Ordering::Relaxed);
    (ours, FIRST.lock().unwrap_or_else(|e| e.into_inner()).clone())
}

/// Runs `steps` steps of `sim` as a watched window, and fails with the
/// first of fdem's allocations in it.
fn watch(sim: &mut Simulation, steps: u64, what: &str) {
    let (ours, first) = window(sim, steps);
    assert_eq!(ours, 0, "{ours} allocations in {steps} steps ({what}); the first:\n{first}");
}

/// One test, not two: the counter is global, and the harness allocates
/// (its report of one test) while another test runs.
#[test]
fn steps_without_topology_changes_allocate_nothing() {
    contacting_yielding_steps();
    fracture_checks_that_insert_nothing();
    steps_with_bonds_that_keep_their_count();
    planning_that_separates_nothing();
}

fn planning_that_separates_nothing() {
    use fdem_fracture::{plan, FractureParams, NodeFailure, PlanScratch};
    // 3 × 3 unit cells, node (i, j) = 4j + i, cracks vertical (σ1 along
    // x): node 0, a corner, has its crack along the boundary and out of
    // the material (nothing to cut), node 5 is next to a crack at node 6
    // (a fresh crack does not start there). A fragmented impact's checks
    // re-plan a couple of hundred such candidates each.
    let x: Vec<[f64; 2]> = (0..16).map(|k| [(k % 4) as f64, (k / 4) as f64]).collect();
    let mut t = Vec::new();
    for j in 0..3u32 {
        for i in 0..3u32 {
            let (a, b, c, d) = (4 * j + i, 4 * j + i + 1, 4 * j + i + 5, 4 * j + i + 4);
            t.extend([[a, b, c], [a, c, d]]);
        }
    }
    let csr = fdem_mesh::node_elements(x.len(), &t);
    let active = vec![true; t.len()];
    let normal = vec![0.0; x.len()];
    let mut cracked = vec![false; x.len()];
    cracked[6] = true;
    let failure = NodeFailure { normal: &normal, cracked: &cracked };
    let params = FractureParams::default();
    let mut scratch = PlanScratch::default();
    for round in 0..3 {
        OURS.store(0, Ordering::Relaxed);
        WATCH.store(true, Ordering::Relaxed);
        let edits = plan(&mut scratch, &t, &active, &csr, &x, &[0, 5], &failure, &params);
        WATCH.store(false, Ordering::Relaxed);
        let ours = OURS.load(Ordering::Relaxed);
        assert!(edits.inserted_at.is_empty() && edits.waiting.is_empty(), "round {round}");
        // the first round sizes the scratch
        if round > 0 {
            let first = FIRST.lock().unwrap_or_else(|e| e.into_inner()).clone();
            assert_eq!(ours, 0, "{ours} allocations planning what cannot separate; the first:\n{first}");
        }
    }
}

fn contacting_yielding_steps() {
    for threads in [1, 2] {
        // the impact without crack insertion: the block lands on the platen
        // at step 80 and bounces off at about step 300; steps 150-290 are
        // in contact, yielding and ringing, and slide a little
        let mut spec = impact(24, 12);
        spec.fracture = None;
        // a margin of 0.1 mm (against 8 mm by default) rebuilds the broad
        // phase every few steps, so that the tree's periodic full rebuild
        // (every 16th) happens in the window too
        if let Some(c) = spec.contact.as_mut() {
            c.margin = Some(1e-4);
        }
        let built = CALLS.load(Ordering::Relaxed);
        let mut sim = Simulation::new(spec, threads).expect("the impact model is valid");
        assert!(CALLS.load(Ordering::Relaxed) > built, "the counting allocator is not the one in use");
        sim.step(150).expect("warm-up");
        let (plastic, friction) = (sim.energies().plastic, sim.energies().friction);
        let builds = sim.contact_stats().broad_phase_builds;
        watch(&mut sim, 140, &format!("contact, {threads} threads"));
        let contacts = sim.contact_stats().contacts;
        let rebuilt = sim.contact_stats().broad_phase_builds - builds;
        assert!(rebuilt >= 20, "only {rebuilt} broad-phase builds in the window");
        assert!(contacts > 20, "the block should press on the platen: {contacts} contacts");
        let e = sim.energies();
        assert!(e.plastic > plastic && e.friction > friction, "the block should yield and slide while watched");
    }
}

fn fracture_checks_that_insert_nothing() {
    for threads in [1, 2] {
        // the impact with crack insertion, watched in flight before it lands
        // (step 80): a fracture check every 5 steps, none inserting
        let mut sim = Simulation::new(impact(24, 12), threads).expect("the impact model is valid");
        sim.step(10).expect("warm-up");
        watch(&mut sim, 60, &format!("12 fracture checks, {threads} threads"));
        assert_eq!(sim.insertions(), Some(0));
    }
}

fn steps_with_bonds_that_keep_their_count() {
    for threads in [1, 2] {
        // the impact with crack insertion after it landed: young cracks
        // hold bonds, which are updated and whose forces are added up in
        // every step. A step watched alone counts when neither it nor the
        // step before it inserted a crack or broke a bond (the step after
        // an insertion sizes the node pass's buffers to the new mesh).
        let mut sim = Simulation::new(impact(24, 12), threads).expect("the impact model is valid");
        sim.step(300).expect("warm-up");
        let (mut counted, mut last) = (0, (sim.insertions(), sim.bonds().len()));
        let mut changed_before = true;
        for _ in 0..400 {
            let (ours, first) = window(&mut sim, 1);
            let now = (sim.insertions(), sim.bonds().len());
            let changed = now != last;
            if !changed && !changed_before && now.1 > 0 && sim.steps() % 1000 != 0 {
                assert_eq!(
                    ours,
                    0,
                    "{ours} allocations in step {} with bonds, {threads} threads; the first:\n{first}",
                    sim.steps()
                );
                counted += 1;
            }
            (last, changed_before) = (now, changed);
        }
        assert!(counted >= 20, "only {counted} steps with bonds and no change, {threads} threads");
    }
}
