//! Out of memory in `toolconf_controller_create` is a status, never an abort: this test
//! binary's allocator refuses the k-th allocation from a point on, for every k until a create
//! succeeds, and each create then gives `TOOLCONF_OUT_OF_MEMORY` with nothing written, nothing
//! left allocated and nothing registered. One test in its own binary: the allocator and the
//! registry of handles are the process's.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicIsize, AtomicUsize, Ordering};

use toolconf_cabi::bodies::Controller;
use toolconf_cabi::toolconf_core::{Arm2, ArmModel, TaskKind};
use toolconf_cabi::{handles, status};

toolconf_cabi::export_model!(Arm2, arm2);

/// The system allocator, refusing every allocation once `REFUSE_AFTER` allocations more have
/// been made (negative: never), and counting the bytes it holds.
struct Refusing;

static REFUSE_AFTER: AtomicIsize = AtomicIsize::new(-1);
static HELD: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Refusing {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let left = REFUSE_AFTER.load(Ordering::SeqCst);
        if left == 0 {
            return core::ptr::null_mut();
        }
        if left > 0 {
            REFUSE_AFTER.store(left - 1, Ordering::SeqCst);
        }
        let p = System.alloc(layout);
        if !p.is_null() {
            HELD.fetch_add(layout.size(), Ordering::SeqCst);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        HELD.fetch_sub(layout.size(), Ordering::SeqCst);
        System.dealloc(ptr, layout)
    }
}

#[global_allocator]
static ALLOCATOR: Refusing = Refusing;

fn create(handle: &mut *mut Controller) -> i32 {
    let task = Arm2::paper_task(TaskKind::Position);
    let flat = |blocks: &[nalgebra::SMatrix<f64, 2, 2>]| -> Vec<f64> {
        blocks.iter().flat_map(|m| m.as_slice().to_vec()).collect()
    };
    let goals: Vec<f64> = task
        .goal
        .iter()
        .flat_map(|g| g.as_slice().to_vec())
        .collect();
    let precisions = flat(&task.precision);
    let p = [0.3, 0.4, 0.5, 0.2];
    let position = TaskKind::ALL
        .iter()
        .position(|k| *k == TaskKind::Position)
        .unwrap() as u32;
    // The inputs are allocated above, before the allocator starts refusing.
    REFUSE_AFTER.store(ALLOW.load(Ordering::SeqCst) as isize, Ordering::SeqCst);
    let held = HELD.load(Ordering::SeqCst);
    // SAFETY: the arrays hold the model's sizes.
    let code = unsafe {
        toolconf_controller_create(
            p.as_ptr(),
            position,
            goals.as_ptr(),
            precisions.as_ptr(),
            1.0,
            [0.1; 2].as_ptr(),
            1000.0,
            handle,
        )
    };
    REFUSE_AFTER.store(-1, Ordering::SeqCst);
    if code != status::OK {
        assert_eq!(
            HELD.load(Ordering::SeqCst),
            held,
            "a failed create kept memory"
        );
    }
    code
}

static ALLOW: AtomicUsize = AtomicUsize::new(0);

#[test]
fn out_of_memory_in_create_is_a_status() {
    for (refused, allowed) in (0..16).enumerate() {
        ALLOW.store(allowed, Ordering::SeqCst);
        let live = handles::live();
        let mut h = 7 as *mut Controller;
        let code = create(&mut h);
        if code == status::OK {
            // Its box, then room in the registry (empty in this process until now).
            assert!(refused >= 2, "{refused} allocations of create were refused");
            // SAFETY: a live handle.
            assert_eq!(unsafe { toolconf_controller_destroy(h) }, status::OK);
            assert_eq!(handles::live(), live);
            return;
        }
        assert_eq!(
            code,
            status::OUT_OF_MEMORY,
            "{}",
            toolconf_cabi::status::last_error()
        );
        assert!(toolconf_cabi::status::last_error().contains("out of memory"));
        assert_eq!(h as usize, 7, "a failed create wrote a handle");
        assert_eq!(handles::live(), live, "a failed create registered a handle");
    }
    panic!("create never succeeded with 16 allocations");
}
