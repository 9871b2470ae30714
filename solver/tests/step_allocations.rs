//! The hot loop allocates nothing: once a pull is under way, a step of the
//! paper's n = 3 knot as the protocol takes it (the adaptive clock's
//! checkpoint, detection, frictional contact solve, implicit rod step) makes
//! no heap allocation. Counted by a global allocator that tallies
//! allocations made on this test's thread.
use nalgebra::Vector3;
use solver::external::Environment;
use solver::knot::{self, KnotSpec};
use solver::material::Material;
use solver::pipeline::{ContactOptions, World};
use solver::rod::{End, Rod};
use solver::stepper::NewtonOptions;
use solver::time_step::{AdaptiveOptions, TimeStep};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

// SAFETY: every call is forwarded to the system allocator unchanged.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        // SAFETY: the caller's layout contract is passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `System.alloc` with this layout.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|a| a.set(a.get() + 1));
        // SAFETY: as for `dealloc`, and `new_size` is the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

#[test]
fn a_pulling_step_allocates_nothing() {
    let shape = knot::build(&KnotSpec::paper(3)).expect("paper knot builds");
    assert!(allocations() > 0, "the counter sees this thread's allocations");
    let mut rod = Rod::new(&shape.points, 1.6e-3, Material::default()).expect("valid rod");
    rod.clamp(End::Start);
    rod.clamp(End::Finish);
    let newton = NewtonOptions {
        force_scale: Some(rod.section.ei / (1.6e-3 * 1.6e-3)),
        ..NewtonOptions::default()
    };
    let env = Environment {
        gravity: Vector3::zeros(),
        damping: 20.0,
    };
    let mut world = World::new(vec![rod], env, ContactOptions::default(), newton);
    for _ in 0..300 {
        world.step(5e-4).expect("relaxation step");
    }
    world.env.damping = 0.0;
    world.rods[0].move_clamp(End::Start, Vector3::new(-3e-3, 0.0, 0.0));
    world.rods[0].move_clamp(End::Finish, Vector3::new(3e-3, 0.0, 0.0));
    // Warm-up: buffers grow to the largest contact set they meet.
    let mut clock = TimeStep::new(AdaptiveOptions::up_to(5e-4));
    for _ in 0..200 {
        clock.advance(&mut world).expect("pulling step");
    }
    let before = allocations();
    let mut contacts = 0;
    for _ in 0..200 {
        let step = clock.advance(&mut world).expect("pulling step");
        contacts = contacts.max(step.report.contacts);
    }
    let made = allocations() - before;
    assert!(contacts > 50, "a step in contact ({contacts} contacts)");
    assert_eq!(
        made, 0,
        "{made} allocations in 200 pulling steps with up to {contacts} contacts"
    );
}
