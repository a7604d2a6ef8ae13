//! The Falcon driver allocates nothing per tick: read (reply, resync, FK)
//! and command (Jacobian, packet) through the emulator, with lost, garbled
//! and split replies, counted by an allocator in its own test binary.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

use hapticlab::device::HapticDevice;
use hapticlab::device::falcon::emulator::{EmulatedFalcon, EmulatorConfig};
use hapticlab::device::falcon::{FalconConfig, FalconDevice};
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count_one() {
    let _ = COUNTING.try_with(|on| {
        if on.get() {
            let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count_one();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count_one();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_allocation_per_falcon_tick() {
    let lp = LoadedProfile::thesis();
    let sim = SimDevice::new(&lp.profile, Path::new("."), Some("S2"), 4).unwrap();
    let emu = EmulatedFalcon::new(
        sim,
        EmulatorConfig {
            drop_rate: 0.03,
            garble_rate: 0.03,
            split_rate: 0.2,
            ..EmulatorConfig::default()
        },
    );
    let mut dev = FalconDevice::open(emu, FalconConfig::default(), &mut |_| {}).unwrap();
    let hold = [0.0, -0.004, -0.03];
    let mut tick = |k: u32| {
        let r = dev.read(f64::from(k) * 0.001).unwrap();
        let f = if r.homed {
            [0, 1, 2].map(|a| 300.0 * (hold[a] - r.pos_m[a]))
        } else {
            [0.0; 3]
        };
        dev.command(f).unwrap();
        r.homed
    };
    // Homing first (the emulated hand), outside the count.
    let mut k = 1;
    while !tick(k) {
        k += 1;
        assert!(k < 10_000, "not homed");
    }
    COUNTING.with(|on| on.set(true));
    for j in 1..=3000 {
        tick(k + j);
    }
    COUNTING.with(|on| on.set(false));
    assert_eq!(ALLOCATIONS.with(Cell::get), 0, "allocations in 3000 ticks");
    let s = dev.stats();
    assert!(s.missed_replies > 0 && s.bad_packets > 0, "{s:?}");
}
