//! A scan on the emulated Falcon stopped as a signal stops it: `scan` turns
//! SIGINT (once or twice), SIGTERM, SIGHUP and a lost terminal into one
//! `Command::Stop` to the servo loop (`src/commands/scan.rs`), and the loop
//! ends. On firmware that keeps the last force it was sent, only the
//! zero-force packet the driver sends as it closes stops the motors: the
//! emulated motors must be at zero when the device is closed, even when the
//! loop ends right after the stop, with a force still commanded.

use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use hapticlab::clock::VirtualClock;
use hapticlab::device::falcon::emulator::{EmulatedFalcon, EmulatorConfig};
use hapticlab::device::falcon::{self, FalconDevice, FalconTransport, TransportError};
use hapticlab::device::sim::SimDevice;
use hapticlab::profile::LoadedProfile;
use hapticlab::servo::{Command as Servo, Links, ServoLoop};

use crate::common::REPO;

/// The emulator, whose motor commands are noted as the device closes (the
/// transport is dropped last, after the driver has made the device safe).
struct NotesClosing {
    inner: EmulatedFalcon,
    at_close: Arc<Mutex<Option<[i16; 3]>>>,
}

impl Drop for NotesClosing {
    fn drop(&mut self) {
        *self.at_close.lock().unwrap() = Some(self.inner.motor());
    }
}

impl FalconTransport for NotesClosing {
    fn kind(&self) -> &'static str {
        self.inner.kind()
    }
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.inner.control(request, value)
    }
    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.inner.write(bytes)
    }
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.inner.read(buf, timeout)
    }
    fn now(&self) -> Instant {
        self.inner.now()
    }
    fn advance_to(&mut self, t_s: f64) {
        self.inner.advance_to(t_s)
    }
    fn applied_motor(&self) -> Option<[i16; 3]> {
        self.inner.applied_motor()
    }
    fn take_stall(&mut self) -> Option<Duration> {
        self.inner.take_stall()
    }
}

#[test]
fn a_scan_stopped_by_a_signal_leaves_the_motors_at_zero_on_firmware_that_keeps_its_force() {
    let mut lp =
        LoadedProfile::load(&Path::new(REPO).join("tests/data/profiles/quick-emulator.toml"))
            .unwrap();
    lp.profile
        .falcon
        .as_mut()
        .unwrap()
        .emulator
        .keeps_last_force = true;
    let config = falcon::config_from_profile(&lp).unwrap();
    let sim = SimDevice::new(&lp.profile, &lp.base_dir, Some("S2"), 5)
        .unwrap()
        .without_faults();
    let at_close = Arc::new(Mutex::new(None));
    let transport = NotesClosing {
        inner: EmulatedFalcon::new(
            sim,
            EmulatorConfig {
                device: lp.profile.falcon.clone().unwrap().emulator,
                frame: config.frame,
                encoder_offset_deg: config.encoder_offset_deg,
                position_noise_m: lp.profile.simulator.position_noise_m,
                seed: 5,
                ..EmulatorConfig::default()
            },
        ),
        at_close: at_close.clone(),
    };
    let dev = FalconDevice::open(transport, config, &mut |_| {}).unwrap();
    let rig = lp.profile.rig().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (recorder, sink) = hapticlab::recorder::start();
    let clock = VirtualClock::new(rig.device.rate_hz, 0.0, 0.0, 3);
    let mut servo = ServoLoop::new(dev, clock, rig, sink, Links::default());
    for _ in 0..30_000 {
        if servo.reading().homed {
            break;
        }
        servo.tick().expect("homes");
    }
    assert!(servo.reading().homed, "not homed");
    servo.apply(Servo::StartScan {
        path: dir.path().join("S2").join("S2_001.csv"),
        meta: vec![("label".into(), toml::Value::String("S2".into()))],
    });
    // On the stroke, pressing on the texture: a force is held.
    let mut held = [0; 3];
    for _ in 0..30_000 {
        servo.tick().expect("strokes");
        let motor = servo.device().transport().inner.motor();
        if servo.reading().pos_m[0] > -0.03 && motor != [0; 3] {
            held = motor;
            break;
        }
    }
    assert_ne!(held, [0; 3], "no force was held mid-stroke");
    // What every signal sends; the loop ends at once, no tick after it.
    servo.apply(Servo::Stop("interrupted by a signal".into()));
    drop(servo);
    drop(recorder.join());
    assert_eq!(
        *at_close.lock().unwrap(),
        Some([0; 3]),
        "the firmware kept {held:?} after the device closed"
    );
}
