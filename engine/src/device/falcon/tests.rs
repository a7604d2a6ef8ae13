//! The driver's exits and faults against the emulator: the zero-force packet
//! waited for until it has left, before the device is closed; OUT and IN
//! failures in one streak; firmware that keeps the last force; motors that
//! lose their power.

use std::path::Path;
use std::sync::{Arc, Mutex};

use super::emulator::{EmulatedFalcon, EmulatorConfig};
use super::*;
use crate::device::sim::SimDevice;
use crate::profile::LoadedProfile;
use crate::profile::hardware::EmulatorSection;

fn emulator(device: EmulatorSection) -> EmulatedFalcon {
    let lp = LoadedProfile::thesis();
    let sim = SimDevice::new(&lp.profile, Path::new("."), None, 3).unwrap();
    EmulatedFalcon::new(
        sim,
        EmulatorConfig {
            device,
            ..EmulatorConfig::default()
        },
    )
}

/// Drive until homed and released, then push with `force`: the time reached.
fn home_then_push<T: FalconTransport>(dev: &mut FalconDevice<T>, force: [f64; 3]) -> f64 {
    let mut t = 0.0;
    for _ in 0..10_000 {
        t += 0.001;
        let r = dev.read(t).unwrap();
        dev.command(if r.homed { force } else { [0.0; 3] }).unwrap();
        if r.homed && dev.motor_commands() != [0; 3] {
            break;
        }
    }
    assert!(dev.is_homed(), "never homed");
    for _ in 0..50 {
        t += 0.001;
        dev.read(t).unwrap();
        dev.command(force).unwrap();
    }
    t
}

/// A USB link whose bulk OUT writes wait in the host until flushed (or
/// until the next read: the host keeps the bus moving); closing the device
/// cancels whatever is still queued, as usbfs does. What the firmware
/// applies is shared with the test, to be read after the device is gone.
struct QueuedOut {
    inner: EmulatedFalcon,
    queued: Vec<u8>,
    applied: Arc<Mutex<[i16; 3]>>,
}

impl QueuedOut {
    fn deliver(&mut self) -> Result<(), TransportError> {
        let bytes = std::mem::take(&mut self.queued);
        let r = self.inner.write(&bytes);
        *self.applied.lock().unwrap() = self.inner.motor();
        r
    }
}

impl FalconTransport for QueuedOut {
    fn kind(&self) -> &'static str {
        "falcon-emulator"
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.inner.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.queued.extend_from_slice(bytes);
        Ok(())
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.deliver()?;
        self.inner.read(buf, timeout)
    }
    fn flush(&mut self, _timeout: Duration) -> Result<(), TransportError> {
        self.deliver()
    }
    fn now(&self) -> Instant {
        self.inner.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.inner.advance_to(t_s)
    }
}

#[test]
fn dropping_the_device_delivers_the_zero_force_packet_before_closing() {
    let applied = Arc::new(Mutex::new([0i16; 3]));
    let transport = QueuedOut {
        inner: emulator(EmulatorSection {
            keeps_last_force: true,
            ..EmulatorSection::default()
        }),
        queued: Vec::new(),
        applied: applied.clone(),
    };
    let mut dev = FalconDevice::open(transport, FalconConfig::default(), &mut |_| {}).unwrap();
    home_then_push(&mut dev, [0.0, 1.5, 0.0]);
    // A force is held: the firmware applies it and would go on applying it.
    dev.read(20.0).unwrap();
    assert_ne!(*applied.lock().unwrap(), [0; 3]);
    let stats = dev.stats();
    drop(dev);
    // The zero packet left before the device closed: the motors are still.
    assert_eq!(*applied.lock().unwrap(), [0; 3]);
    assert_eq!(stats.safe_unconfirmed, 0);
}

/// A transport whose flush never completes: the wait is bounded and the
/// packet counted as unconfirmed.
struct NeverLeaves(EmulatedFalcon);

impl FalconTransport for NeverLeaves {
    fn kind(&self) -> &'static str {
        "falcon-emulator"
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.0.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.0.write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.0.read(buf, timeout)
    }
    fn flush(&mut self, timeout: Duration) -> Result<(), TransportError> {
        Err(TransportError::Io(format!(
            "1 USB write(s) still queued after {} ms",
            timeout.as_millis()
        )))
    }
    fn now(&self) -> Instant {
        self.0.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.0.advance_to(t_s)
    }
}

#[test]
fn a_zero_packet_that_does_not_leave_is_counted_unconfirmed() {
    let mut dev = FalconDevice::open(
        NeverLeaves(emulator(EmulatorSection::default())),
        FalconConfig::default(),
        &mut |_| {},
    )
    .unwrap();
    dev.read(0.001).unwrap();
    dev.make_safe();
    let s = dev.stats();
    assert_eq!((s.safe_confirmed, s.safe_unconfirmed), (0, 1));
}

/// Once `failing`, every `every`-th bulk OUT write fails (not a vanished
/// device); every read too when `reads` is set.
struct FailingWrites {
    inner: EmulatedFalcon,
    failing: bool,
    writes: u64,
    every: u64,
    reads: bool,
}

impl FalconTransport for FailingWrites {
    fn kind(&self) -> &'static str {
        "falcon-emulator"
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.inner.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.writes += u64::from(self.failing);
        if self.failing && self.writes.is_multiple_of(self.every) {
            return Err(TransportError::Transient(
                "bulk OUT transfer failed: fault".into(),
            ));
        }
        self.inner.write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        if self.failing && self.reads {
            return Err(TransportError::Transient("bulk IN endpoint stalled".into()));
        }
        self.inner.read(buf, timeout)
    }
    fn now(&self) -> Instant {
        self.inner.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.inner.advance_to(t_s)
    }
}

#[test]
fn a_failed_bulk_out_is_ridden_out_and_a_streak_with_in_errors_ends_the_link() {
    // One write in 50 fails: counted, sent again, the session goes on.
    let flaky = FailingWrites {
        inner: emulator(EmulatorSection::default()),
        failing: false,
        writes: 0,
        every: 50,
        reads: false,
    };
    let mut dev = FalconDevice::open(flaky, FalconConfig::default(), &mut |_| {}).unwrap();
    dev.transport_mut().failing = true;
    for k in 1..3000 {
        let t = f64::from(k) * 0.001;
        dev.read(t).unwrap();
        dev.command([0.0; 3]).unwrap();
    }
    let s = dev.stats();
    assert!(s.usb_errors >= 50 && s.replies > 2500, "{s:?}");
    // Reads and writes all failing: one streak of both ends the link.
    let broken = FailingWrites {
        inner: emulator(EmulatorSection::default()),
        failing: false,
        writes: 0,
        every: 2,
        reads: true,
    };
    let config = FalconConfig {
        read_error_streak: 10,
        ..FalconConfig::default()
    };
    let mut dev = FalconDevice::open(broken, config, &mut |_| {}).unwrap();
    dev.transport_mut().failing = true;
    let mut err = None;
    for k in 1..100 {
        let t = f64::from(k) * 0.001;
        if let Err(e) = dev.read(t).and_then(|_| dev.command([0.0; 3])) {
            err = Some(e.to_string());
            break;
        }
    }
    let err = err.expect("the streak ends the link");
    assert!(err.contains("10 USB transfers in a row failed"), "{err}");
    assert!(dev.stats().usb_errors == 10, "{:?}", dev.stats());
}

#[test]
fn firmware_that_keeps_the_last_force_holds_it_until_a_zero_packet_comes() {
    for keeps in [false, true] {
        let e = emulator(EmulatorSection {
            keeps_last_force: keeps,
            ..EmulatorSection::default()
        });
        let mut dev = FalconDevice::open(e, FalconConfig::default(), &mut |_| {}).unwrap();
        let t = home_then_push(&mut dev, [0.0, 1.5, 0.0]);
        let held = dev.transport().motor();
        assert_ne!(held, [0; 3]);
        // Commands stop; time goes on (the host is stuck, say).
        dev.transport_mut().advance_to(t + 0.5);
        let still = dev.transport().motor();
        if keeps {
            assert_eq!(still, held, "the force was not kept");
            // Only the zero packet stops it.
            dev.make_safe();
            assert_eq!(dev.transport().motor(), [0; 3]);
        } else {
            assert_eq!(still, [0; 3], "the firmware did not stop on silence");
            assert_eq!(dev.transport().counters.silence_stops, 1);
        }
    }
}
