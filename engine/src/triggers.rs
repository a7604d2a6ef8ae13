//! Hands-free triggers: a HID foot switch or button box whose buttons start
//! a measurement, store it, or abort it, so that the experimenter's hands
//! can stay on the texture and the grip.
//!
//! This module owns the mapping from input reports to actions (press edges
//! of the profile's `[[triggers]]` buttons) and a watcher thread that keeps
//! each configured device open, reports it absent or unplugged (never
//! fatal) and reopens it when it comes back. The HID access itself sits
//! behind [`TriggerBackend`], so tests drive the mapping with a fake device;
//! [`hid`] is the real backend (hidapi's pure-Rust Linux hidraw backend).

pub mod hid;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, bounded};

pub use crate::profile::hardware::{TriggerAction, TriggerSpec};

/// What the watcher reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TriggerEvent {
    /// A mapped button was pressed.
    Action {
        action: TriggerAction,
        source: String,
    },
    Connected(String),
    /// Not found when looked for (reported once until it appears).
    Absent {
        source: String,
        why: String,
    },
    /// It was open and went away.
    Unplugged {
        source: String,
        why: String,
    },
}

/// Turns input reports into actions: a button fires when its bit goes from
/// 0 to 1 (held buttons do not repeat).
pub struct ButtonDecoder {
    spec: TriggerSpec,
    prev: [u8; 64],
}

impl ButtonDecoder {
    pub fn new(spec: TriggerSpec) -> ButtonDecoder {
        ButtonDecoder {
            spec,
            prev: [0; 64],
        }
    }

    pub fn spec(&self) -> &TriggerSpec {
        &self.spec
    }

    /// Forget the held buttons (after a reconnect).
    pub fn reset(&mut self) {
        self.prev = [0; 64];
    }

    /// The actions this report's new presses fire.
    pub fn feed(&mut self, report: &[u8], mut fire: impl FnMut(TriggerAction)) {
        let bits = report.get(self.spec.report_offset..).unwrap_or(&[]);
        let mut now = [0u8; 64];
        let n = bits.len().min(now.len());
        now[..n].copy_from_slice(&bits[..n]);
        for b in &self.spec.buttons {
            let i = (b.button - 1) as usize;
            let (byte, mask) = (i / 8, 1u8 << (i % 8));
            if byte < now.len() && now[byte] & mask != 0 && self.prev[byte] & mask == 0 {
                fire(b.action);
            }
        }
        self.prev = now;
    }
}

/// Why a trigger device could not be opened.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum OpenFailure {
    Absent,
    Permission(String),
    Other(String),
}

impl std::fmt::Display for OpenFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OpenFailure::Absent => write!(f, "not plugged in"),
            OpenFailure::Permission(m) => write!(
                f,
                "permission denied ({m}); add a hidraw line for it to the udev rule (`hapticlab doctor --udev-rule`) and install the rule"
            ),
            OpenFailure::Other(m) => write!(f, "{m}"),
        }
    }
}

/// An open trigger device: input reports, waiting up to `timeout`.
pub trait TriggerSource: Send {
    /// `Ok(0)` when no report came in time; `Err` when the device is gone.
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, String>;
}

/// Opens trigger devices (hidapi, or a fake in tests).
pub trait TriggerBackend {
    fn open(&mut self, spec: &TriggerSpec) -> Result<Box<dyn TriggerSource>, OpenFailure>;
}

/// A thread that watches the configured triggers and sends [`TriggerEvent`]s.
pub struct TriggerWatcher {
    pub events: Receiver<TriggerEvent>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

/// How often an absent trigger is looked for again.
const RETRY: Duration = Duration::from_secs(1);
const POLL: Duration = Duration::from_millis(10);

impl TriggerWatcher {
    /// Watch `specs`; the backend is made on the watcher's thread.
    pub fn start<F>(specs: Vec<TriggerSpec>, make_backend: F) -> std::io::Result<TriggerWatcher>
    where
        F: FnOnce() -> Box<dyn TriggerBackend> + Send + 'static,
    {
        let (tx, rx) = bounded(64);
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::Builder::new()
            .name("triggers".into())
            .spawn(move || run(specs, make_backend(), &tx, &flag))?;
        Ok(TriggerWatcher {
            events: rx,
            stop,
            thread: Some(thread),
        })
    }
}

impl Drop for TriggerWatcher {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

struct Watched {
    decoder: ButtonDecoder,
    name: String,
    source: Option<Box<dyn TriggerSource>>,
    next_try: Instant,
    reported_absent: bool,
}

fn run(
    specs: Vec<TriggerSpec>,
    mut backend: Box<dyn TriggerBackend>,
    tx: &Sender<TriggerEvent>,
    stop: &AtomicBool,
) {
    let mut watched: Vec<Watched> = specs
        .into_iter()
        .map(|s| Watched {
            name: s.display_name(),
            decoder: ButtonDecoder::new(s),
            source: None,
            next_try: Instant::now(),
            reported_absent: false,
        })
        .collect();
    let mut buf = [0u8; 64];
    // A closed receiver ends the watch too.
    let send = |e: TriggerEvent| tx.send(e).is_ok();
    while !stop.load(Ordering::Relaxed) {
        let mut any_open = false;
        for w in &mut watched {
            if w.source.is_none() && Instant::now() >= w.next_try {
                match backend.open(w.decoder.spec()) {
                    Ok(s) => {
                        w.source = Some(s);
                        w.decoder.reset();
                        w.reported_absent = false;
                        if !send(TriggerEvent::Connected(w.name.clone())) {
                            return;
                        }
                    }
                    Err(why) => {
                        w.next_try = Instant::now() + RETRY;
                        if !w.reported_absent {
                            w.reported_absent = true;
                            let e = TriggerEvent::Absent {
                                source: w.name.clone(),
                                why: why.to_string(),
                            };
                            if !send(e) {
                                return;
                            }
                        }
                    }
                }
            }
            let Some(src) = w.source.as_mut() else {
                continue;
            };
            any_open = true;
            match src.read(&mut buf, POLL) {
                Ok(0) => {}
                Ok(n) => {
                    let mut fired = Vec::new();
                    w.decoder.feed(&buf[..n], |a| fired.push(a));
                    for action in fired {
                        let e = TriggerEvent::Action {
                            action,
                            source: w.name.clone(),
                        };
                        if !send(e) {
                            return;
                        }
                    }
                }
                Err(why) => {
                    w.source = None;
                    w.next_try = Instant::now() + RETRY;
                    let e = TriggerEvent::Unplugged {
                        source: w.name.clone(),
                        why,
                    };
                    if !send(e) {
                        return;
                    }
                }
            }
        }
        if !any_open {
            std::thread::sleep(POLL);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::hardware::ButtonAction;
    use std::collections::VecDeque;
    use std::sync::Mutex;

    fn spec() -> TriggerSpec {
        TriggerSpec {
            name: "pedal".into(),
            vendor_id: 0x05f3,
            product_id: 0x00ff,
            report_offset: 1,
            buttons: vec![
                ButtonAction {
                    button: 1,
                    action: TriggerAction::Start,
                },
                ButtonAction {
                    button: 2,
                    action: TriggerAction::Store,
                },
                ButtonAction {
                    button: 11,
                    action: TriggerAction::Abort,
                },
            ],
        }
    }

    #[test]
    fn press_edges_fire_their_actions_once() {
        let mut d = ButtonDecoder::new(spec());
        let mut got = Vec::new();
        // Report id 0x01 first, then the button bytes.
        for r in [
            &[1u8, 0b01, 0][..],
            &[1, 0b01, 0],
            &[1, 0b11, 0],
            &[1, 0, 0b100],
            &[1, 0, 0],
            &[1, 0b01],
        ] {
            d.feed(r, |a| got.push(a));
        }
        use TriggerAction::*;
        assert_eq!(got, vec![Start, Store, Abort, Start]);
    }

    /// A fake HID device: scripted reports, then unplugged.
    struct Fake {
        plugged: Arc<Mutex<bool>>,
        reports: Arc<Mutex<VecDeque<Vec<u8>>>>,
    }
    struct FakeSource(Arc<Mutex<bool>>, Arc<Mutex<VecDeque<Vec<u8>>>>);
    impl TriggerSource for FakeSource {
        fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, String> {
            if !*self.0.lock().unwrap() {
                return Err("device disconnected".into());
            }
            match self.1.lock().unwrap().pop_front() {
                Some(r) => {
                    buf[..r.len()].copy_from_slice(&r);
                    Ok(r.len())
                }
                None => {
                    std::thread::sleep(timeout);
                    Ok(0)
                }
            }
        }
    }
    impl TriggerBackend for Fake {
        fn open(&mut self, _: &TriggerSpec) -> Result<Box<dyn TriggerSource>, OpenFailure> {
            if *self.plugged.lock().unwrap() {
                Ok(Box::new(FakeSource(
                    self.plugged.clone(),
                    self.reports.clone(),
                )))
            } else {
                Err(OpenFailure::Absent)
            }
        }
    }

    fn next(w: &TriggerWatcher) -> TriggerEvent {
        w.events
            .recv_timeout(Duration::from_secs(5))
            .expect("an event")
    }

    #[test]
    fn the_watcher_maps_buttons_and_reports_unplugging_and_absence() {
        let plugged = Arc::new(Mutex::new(true));
        let reports = Arc::new(Mutex::new(VecDeque::from(vec![
            vec![1, 0b01, 0],
            vec![1, 0, 0],
            vec![1, 0, 0b100],
        ])));
        let (p, r) = (plugged.clone(), reports.clone());
        let w = TriggerWatcher::start(vec![spec()], move || {
            Box::new(Fake {
                plugged: p,
                reports: r,
            })
        })
        .unwrap();
        let name = "pedal (05f3:00ff)".to_string();
        assert_eq!(next(&w), TriggerEvent::Connected(name.clone()));
        let action = |action| TriggerEvent::Action {
            action,
            source: name.clone(),
        };
        assert_eq!(next(&w), action(TriggerAction::Start));
        assert_eq!(next(&w), action(TriggerAction::Abort));
        *plugged.lock().unwrap() = false;
        assert!(matches!(next(&w), TriggerEvent::Unplugged { .. }));
        assert!(matches!(next(&w), TriggerEvent::Absent { why, .. } if why == "not plugged in"));
        // Plugged back in: found again within the retry period.
        *plugged.lock().unwrap() = true;
        reports.lock().unwrap().push_back(vec![1, 0b10, 0]);
        assert_eq!(next(&w), TriggerEvent::Connected(name.clone()));
        assert_eq!(next(&w), action(TriggerAction::Store));
    }

    #[test]
    fn an_absent_trigger_is_reported_once_and_is_not_fatal() {
        let w = TriggerWatcher::start(vec![spec()], || {
            Box::new(Fake {
                plugged: Arc::new(Mutex::new(false)),
                reports: Arc::new(Mutex::new(VecDeque::new())),
            })
        })
        .unwrap();
        assert!(matches!(next(&w), TriggerEvent::Absent { .. }));
        assert!(w.events.recv_timeout(Duration::from_millis(1500)).is_err());
        drop(w);
    }
}
