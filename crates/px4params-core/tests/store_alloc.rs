//! The store never allocates after construction: a counting global allocator watches every
//! operation on a store whose memory is fixed-size arrays, as firmware would reserve it.
//! (Its own test binary; only the counting thread's allocations count: libtest's main thread
//! allocates while it waits, which made the count flaky under load.)

mod common;

use std::alloc::{GlobalAlloc, Layout as AllocLayout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use px4params_core::compile::OwnedLayout;
use px4params_core::leaf::Target;
use px4params_core::store::{plan, ParamDef, Slot, Store, Which};
use px4params_core::value::LeafSource;
use px4params_core::Scalar;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set on the thread whose allocations are counted (const-initialized: reading it never
    /// allocates, so the allocator may read it).
    static COUNTED: Cell<bool> = const { Cell::new(false) };
}

fn count() {
    if COUNTED.try_with(Cell::get).unwrap_or(false) {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
    }
}

// SAFETY: forwards to the system allocator unchanged; only counts calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: AllocLayout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: AllocLayout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: AllocLayout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_allocation_after_construction() {
    COUNTED.with(|c| c.set(true));
    let mut owned = OwnedLayout::default();
    let ina = common::ina238(&mut owned);
    let battery = common::battery_info(&mut owned);
    let layout = owned.as_layout();
    let mut defs = [ParamDef::instanced(ina, 4), ParamDef::shared(battery)];
    let capacity = plan(&layout, &mut defs).unwrap();
    let mut slots = [Slot::default(); 64];
    let mut bytes = [0u8; 1024];
    assert!(capacity.slots <= slots.len() && capacity.bytes <= bytes.len());
    let mut store = Store::new(&layout, &defs[..], &mut slots[..], &mut bytes[..]).unwrap();
    let talk = [
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(0),
        Scalar::Uint(1),
        Scalar::Uint(0x45),
        Scalar::Uint(200),
        Scalar::Float(0.0003),
    ];

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    for round in 0..100u64 {
        let i = store.add(0, None).unwrap();
        store
            .set_from(
                &layout,
                0,
                i,
                Which::Default,
                &mut LeafSource::new(&talk),
                false,
            )
            .unwrap();
        store
            .set_leaf(
                &layout,
                0,
                i,
                Which::Value,
                Target::Index(5),
                Scalar::Uint(round),
                false,
            )
            .unwrap();
        store
            .set_leaf(
                &layout,
                0,
                i,
                Which::Value,
                Target::Path("bus._tag"),
                Scalar::Uint(1),
                false,
            )
            .unwrap();
        let (_, value) = store
            .get_leaf(&layout, 0, i, Which::Value, Target::Path("current"))
            .unwrap();
        assert_eq!(value, Scalar::Uint(round));
        assert!(store.changed(0, i).unwrap());
        assert!(store.add(0, Some(i)).is_err()); // errors do not allocate either
        assert!(store
            .set_leaf(
                &layout,
                0,
                i,
                Which::Value,
                Target::Index(0),
                Scalar::Uint(1),
                false
            )
            .is_err());
        store.reset(0, i).unwrap();
        store.mark_used(0, i).unwrap();
        assert_eq!(store.instances(0).unwrap().count(), 1);
        store.remove(0, i).unwrap();
        store
            .set_leaf(
                &layout,
                1,
                0,
                Which::Value,
                Target::Path("voltage"),
                Scalar::Float(12.5),
                false,
            )
            .unwrap();
        store.mark_saved();
    }
    assert_eq!(ALLOCATIONS.load(Ordering::SeqCst) - before, 0);
}
