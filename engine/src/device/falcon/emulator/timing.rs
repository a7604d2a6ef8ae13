//! The emulated link's clock and the bytes on their way to the host.
//!
//! It owns the link's time (seconds, its own: the servo loop's time plus the
//! time spent before the loop started, such as loading firmware), and for
//! every byte the Falcon sends, the time the host can first read it. With a
//! timing model (`[falcon.emulator.timing]`) that time follows the path a
//! real byte takes: the host's packet crosses USB and the FTDI chip's serial
//! line at the baud the driver set; the firmware answers; the reply's bytes
//! come back over the serial line into the chip, which hands them to the
//! host only when its latency timer expires (the value the driver set: 1 ms
//! in normal mode, 16 ms while loading firmware) or when 62 bytes have piled
//! up; then USB again, with jitter, and now and then a reply that is late (a
//! slow host, a skipped USB frame). Without a timing model every byte is
//! there at once. Either way a read waits at most its timeout on this clock:
//! what is not there by then is not read. It never sleeps; it tells the
//! caller how long a read waited so that the servo loop's clock can sit the
//! wait out.

use std::collections::VecDeque;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use super::super::ftdi;
use crate::profile::hardware::EmulatorTiming;

/// Bytes the FTDI chip sends to the host in one USB packet at most (64 less
/// its two modem-status bytes): a full buffer goes at once.
const FTDI_PACKET: usize = 62;
/// The FTDI chip's latency timer until the driver sets one (its default).
const FTDI_DEFAULT_LATENCY_S: f64 = 0.016;
/// Bits on the serial line per byte: start, 8 data, stop.
const BITS_PER_BYTE: f64 = 10.0;
/// The chip's crystal and the host's clock disagree by up to this much, so
/// the latency timer's phase drifts against the servo loop's ticks.
const DRIFT_MAX: f64 = 50e-6;

/// Baud rate of an FTDI divisor on its 3 MHz base (the three the driver uses
/// exactly; others by their integer part).
pub fn baud_of_divisor(divisor: u16) -> f64 {
    match divisor {
        ftdi::BAUD_9600 => 9600.0,
        ftdi::BAUD_NORMAL => 1_500_000.0,
        d => 3.0e6 / f64::from((d & 0x3FFF).max(1)),
    }
}

/// What the link did, for tests and figures.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkCounters {
    /// Device messages (replies, echoes) held back as late.
    pub late: u64,
    /// Reads that found nothing by their timeout.
    pub empty_reads: u64,
    /// Link time the host spent waiting in reads, seconds.
    pub waited_s: f64,
}

pub struct Link {
    timing: Option<EmulatorTiming>,
    rng: ChaCha8Rng,
    jitter: Normal<f64>,
    /// The link's time, seconds.
    now: f64,
    /// Link time minus servo time, fixed at the loop's first tick.
    offset: Option<f64>,
    bytes: VecDeque<u8>,
    /// When the host can read each byte in `bytes` (never decreasing).
    visible: VecDeque<f64>,
    byte_s: f64,
    latency_s: f64,
    /// The latency timer expires at `timer_epoch + k * period`.
    timer_epoch: f64,
    drift: f64,
    /// Bytes in the chip not yet sent to the host, and when they will go.
    held: usize,
    held_flush: f64,
    /// The chip's serial line to the Falcon is busy until then.
    tx_free_at: f64,
    /// The host-side delay of the message being sent.
    extra_s: f64,
    /// How late the message being sent reaches the chip (a slow link).
    delay_s: f64,
    /// Link time spent waiting in reads since the last [`Link::take_waited`].
    waited: f64,
    pub counters: LinkCounters,
}

impl Link {
    pub fn new(timing: Option<EmulatorTiming>, seed: u64) -> Link {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x71AE_0000);
        let drift = rng.random_range(-DRIFT_MAX..=DRIFT_MAX);
        let sigma = timing.as_ref().map_or(0.0, |t| t.jitter_ms / 1000.0);
        Link {
            jitter: Normal::new(0.0, sigma.max(0.0)).expect("a finite sigma"),
            timing,
            rng,
            now: 0.0,
            offset: None,
            bytes: VecDeque::with_capacity(4096),
            visible: VecDeque::with_capacity(4096),
            byte_s: BITS_PER_BYTE / 9600.0,
            latency_s: FTDI_DEFAULT_LATENCY_S,
            timer_epoch: 0.0,
            drift,
            held: 0,
            held_flush: 0.0,
            tx_free_at: 0.0,
            extra_s: 0.0,
            delay_s: 0.0,
            waited: 0.0,
            counters: LinkCounters::default(),
        }
    }

    pub fn is_timed(&self) -> bool {
        self.timing.is_some()
    }

    /// The link's time, seconds.
    pub fn now(&self) -> f64 {
        self.now
    }

    /// The servo loop's time has reached `t_s`: the link's clock follows it
    /// (from the first tick on, shifted by the time spent before the loop).
    pub fn follow(&mut self, t_s: f64) {
        let offset = *self.offset.get_or_insert(self.now - t_s);
        self.now = self.now.max(t_s + offset);
    }

    /// The baud divisor the driver set.
    pub fn set_baud(&mut self, divisor: u16) {
        self.byte_s = BITS_PER_BYTE / baud_of_divisor(divisor);
    }

    /// The latency timer the driver set (ms); the timer restarts.
    pub fn set_latency_ms(&mut self, ms: u16) {
        self.latency_s = f64::from(ms.max(1)) / 1000.0;
        self.timer_epoch = self.now;
    }

    /// Throw away what the chip holds for the host (a receive purge).
    pub fn purge(&mut self) {
        self.bytes.clear();
        self.visible.clear();
        self.held = 0;
    }

    /// `n` bytes written by the host now: when the Falcon has the first of
    /// them, and the time each byte takes on the serial line.
    pub fn host_write(&mut self, n: usize) -> (f64, f64) {
        let Some(t) = &self.timing else {
            return (self.now, 0.0);
        };
        let start = (self.now + t.usb_latency_ms / 1000.0).max(self.tx_free_at);
        self.tx_free_at = start + n as f64 * self.byte_s;
        (start + self.byte_s, self.byte_s)
    }

    /// The firmware's time to answer a packet, seconds.
    pub fn firmware_s(&self) -> f64 {
        self.timing.as_ref().map_or(0.0, |t| t.firmware_ms / 1000.0)
    }

    /// The Falcon starts sending a message (a reply, an echo): its
    /// host-side delay is drawn once for all its bytes.
    pub fn begin_message(&mut self) {
        self.delay_s = 0.0;
        let Some(t) = &self.timing else {
            return;
        };
        let mut extra = t.usb_latency_ms / 1000.0 + self.jitter.sample(&mut self.rng).abs();
        if t.late_rate > 0.0 && self.rng.random_bool(t.late_rate.clamp(0.0, 1.0)) {
            extra += self.rng.random_range(0.0..=t.late_ms / 1000.0);
            self.counters.late += 1;
        }
        self.extra_s = extra;
    }

    /// [`Link::begin_message`] for a message that reaches the chip
    /// `delay_s` late (a slow link), with or without a timing model.
    pub fn begin_message_after(&mut self, delay_s: f64) {
        self.begin_message();
        self.delay_s = delay_s.max(0.0);
    }

    /// The Falcon sends byte `b`, which is in the chip at `at` (link time;
    /// ignored without a timing model, but for a message's delay).
    pub fn device_send(&mut self, b: u8, at: f64) {
        let seen = if self.timing.is_none() {
            self.now + self.delay_s
        } else {
            self.flush_time(at + self.delay_s) + self.extra_s
        };
        let last = self.visible.back().copied().unwrap_or(f64::NEG_INFINITY);
        self.bytes.push_back(b);
        self.visible.push_back(seen.max(last));
    }

    /// When the chip sends a byte arriving at `at` to the host: with the
    /// bytes it already holds, at the latency timer's next expiry, or at
    /// once when the buffer fills.
    fn flush_time(&mut self, at: f64) -> f64 {
        if self.held > 0 && at > self.held_flush {
            // The held bytes went at their timer expiry; the timer restarted.
            self.timer_epoch = self.held_flush;
            self.held = 0;
        }
        if self.held == 0 {
            let period = self.latency_s * (1.0 + self.drift);
            let k = ((at - self.timer_epoch) / period).ceil().max(0.0);
            self.held_flush = self.timer_epoch + k * period;
        }
        self.held += 1;
        if self.held == FTDI_PACKET {
            // A full packet goes now: the held bytes with it.
            let n = self.visible.len();
            let extra = self.extra_s;
            for v in self.visible.range_mut(n + 1 - FTDI_PACKET..n) {
                *v = v.min(at + extra);
            }
            self.held = 0;
            self.timer_epoch = at;
            return at;
        }
        self.held_flush
    }

    /// Wait up to `timeout_s` for a byte; the bytes readable then (the link's
    /// clock moves to the first byte's time, or on by the whole timeout).
    pub fn wait_for_bytes(&mut self, timeout_s: f64) -> usize {
        let deadline = self.now + timeout_s.max(0.0);
        match self.visible.front() {
            Some(&v) if v <= deadline => {
                if v > self.now {
                    self.waited += v - self.now;
                    self.counters.waited_s += v - self.now;
                    self.now = v;
                }
                self.visible.iter().take_while(|&&v| v <= self.now).count()
            }
            _ => {
                self.waited += deadline - self.now;
                self.counters.waited_s += deadline - self.now;
                self.counters.empty_reads += 1;
                self.now = deadline;
                0
            }
        }
    }

    /// Take `n` readable bytes into `buf`.
    pub fn take(&mut self, buf: &mut [u8], n: usize) {
        for (slot, b) in buf.iter_mut().zip(self.bytes.drain(..n)) {
            *slot = b;
        }
        self.visible.drain(..n);
    }

    /// The link time reads waited since last asked (timing model only: an
    /// instant link answers at once, so only its empty reads wait).
    pub fn take_waited(&mut self) -> Option<f64> {
        let w = std::mem::take(&mut self.waited);
        (self.is_timed() && w > 0.0).then_some(w)
    }

    /// Forget waits so far (those before the tick's read are not the tick's).
    pub fn clear_waited(&mut self) {
        self.waited = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timed() -> Link {
        let mut l = Link::new(
            Some(EmulatorTiming {
                jitter_ms: 0.0,
                late_rate: 0.0,
                ..EmulatorTiming::default()
            }),
            1,
        );
        l.drift = 0.0;
        l
    }

    #[test]
    fn small_replies_wait_for_the_latency_timer_and_full_packets_go_at_once() {
        let mut l = timed();
        l.set_latency_ms(16);
        // Four bytes at 1 ms: held until the 16 ms expiry.
        l.begin_message();
        for _ in 0..4 {
            l.device_send(1, 0.001);
        }
        assert_eq!(l.wait_for_bytes(0.010), 0, "read before the timer");
        assert!((l.now() - 0.010).abs() < 1e-12);
        assert_eq!(l.wait_for_bytes(0.010), 4);
        let usb = EmulatorTiming::default().usb_latency_ms / 1000.0;
        assert!((l.now() - (0.016 + usb)).abs() < 1e-9, "{}", l.now());
        let mut buf = [0; 64];
        l.take(&mut buf, 4);
        // 62 bytes fill the chip's packet: sent when the last arrives.
        l.begin_message();
        for i in 0..62 {
            l.device_send(2, 0.020 + i as f64 * 1e-5);
        }
        assert_eq!(l.wait_for_bytes(0.1), 62);
        assert!(
            (l.now() - (0.020 + 61e-5 + usb)).abs() < 1e-9,
            "{}",
            l.now()
        );
    }

    #[test]
    fn without_timing_bytes_are_there_at_once_and_empty_reads_take_their_timeout() {
        let mut l = Link::new(None, 1);
        l.device_send(7, 5.0);
        assert_eq!(l.wait_for_bytes(0.001), 1);
        assert_eq!(l.now(), 0.0);
        let mut buf = [0; 4];
        l.take(&mut buf, 1);
        assert_eq!(buf[0], 7);
        assert_eq!(l.wait_for_bytes(0.030), 0);
        assert!((l.now() - 0.030).abs() < 1e-12);
        assert_eq!(l.take_waited(), None, "an instant link reports no waits");
    }

    #[test]
    fn the_loop_clock_is_followed_from_its_first_tick() {
        let mut l = Link::new(None, 1);
        assert_eq!(l.wait_for_bytes(1.5), 0);
        l.follow(0.001);
        assert!((l.now() - 1.5).abs() < 1e-12);
        l.follow(0.002);
        assert!((l.now() - 1.501).abs() < 1e-12);
    }
}
