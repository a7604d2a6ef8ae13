//! The Falcon driver allocates nothing per tick: read (reply, resync, FK)
//! and command (Jacobian, packet) through the emulator, with lost, garbled
//! and split replies, counted by an allocator in its own test binary.

use std::path::Path;

use crate::counting_alloc::allocations_during;

use hapticlab::device::HapticDevice;
use hapticlab::device::falcon::emulator::{EmulatedFalcon, EmulatorConfig};
use hapticlab::device::falcon::{FalconConfig, FalconDevice};
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;
use hapticlab::profile::hardware::EmulatorSection;

#[test]
fn no_allocation_per_falcon_tick() {
    let lp = LoadedProfile::thesis();
    let sim = SimDevice::new(&lp.profile, Path::new("."), Some("S2"), 4).unwrap();
    let emu = EmulatedFalcon::new(
        sim,
        EmulatorConfig {
            device: EmulatorSection {
                drop_rate: 0.03,
                garble_rate: 0.03,
                split_rate: 0.2,
                ..EmulatorSection::default()
            },
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
    let (allocations, ()) = allocations_during(|| {
        for j in 1..=3000 {
            tick(k + j);
        }
    });
    assert_eq!(allocations, 0, "allocations in 3000 ticks");
    let s = dev.stats();
    assert!(s.missed_replies > 0 && s.bad_packets > 0, "{s:?}");
}
