//! A counting global allocator for tests that check that hot loops do not allocate: it
//! counts each thread's heap allocations and reallocations and passes every call on to the
//! system allocator. Included by `#[path]` from the test binaries that use it (the planning
//! crate's `tests/allocations.rs`, the simulator's `tests/world_plan.rs`); it becomes the
//! allocator of that binary only.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use hearth_planning::motion::MotionValidator;
use hearth_planning::space::Space;
use hearth_planning::validity::{RobotValidity, StateValidator};

/// The system allocator, counting each thread's allocations and reallocations.
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: a thread's last deallocations can run after its counter is gone.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every call is passed on to `System` unchanged; counting touches only a
// thread-local `Cell` with a constant initialiser, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract is `System::alloc`'s.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The allocations this thread makes while running `f`, and `f`'s result.
pub fn allocations<T>(f: impl FnOnce() -> T) -> (u64, T) {
    let before = ALLOCATIONS.with(Cell::get);
    let out = f();
    (ALLOCATIONS.with(Cell::get) - before, out)
}

/// Checks `states` and the edges between consecutive ones twice, and asserts that the second
/// pass answered as the first and allocated nothing. The first pass fills what a check fills
/// once: the cells of the self-collision certificate tables its checks land in. The states
/// must mix free and colliding ones, and some edges must be free. `label` names the case.
pub fn assert_checks_do_not_allocate<S: Space>(
    label: &str,
    validity: &mut RobotValidity,
    motions: &mut MotionValidator<S>,
    states: &[Vec<f64>],
) {
    let mut pass = || {
        let valid = states.iter().filter(|q| validity.is_valid(q)).count();
        let free = states
            .windows(2)
            .filter(|p| motions.check_motion(validity, &p[0], &p[1]))
            .count();
        (valid, free)
    };
    let warm = pass();
    let (n, (valid, free)) = allocations(&mut pass);
    assert_eq!((valid, free), warm, "{label}: the same answers in both passes");
    assert!(
        valid > 0 && valid < states.len(),
        "{label}: the states mix free and colliding ({valid} of {} free)",
        states.len()
    );
    assert!(free > 0, "{label}: some edges are free");
    assert_eq!(
        n,
        0,
        "{label}: {} state and edge checks allocated {n} times",
        2 * states.len()
    );
}
