//! The haptic device as the servo loop sees it: read a position, command a
//! force. The simulator, the emulated Falcon and the real Falcon implement
//! [`HapticDevice`]; the servo loop is generic over it, so tests never need
//! hardware. A device never decides forces: it applies what it is told.

pub mod falcon;
pub mod sim;
pub mod surface;

/// One reading of the end effector.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Reading {
    /// Position of the probe's centre in the profile frame, metres.
    pub pos_m: [f64; 3],
    /// Grip buttons, one bit each.
    pub buttons: u8,
    /// Whether the device is homed (forces are only applied once it is).
    pub homed: bool,
}

/// Counters of a device's link to the host (packet-based devices only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct LinkStats {
    pub packets: u64,
    pub replies: u64,
    /// Garbled or partial packets thrown away.
    pub bad_packets: u64,
    /// Ticks on which no reply came in time.
    pub missed_replies: u64,
    /// USB reads that failed and were ridden out (stalls, overflows, timeouts).
    pub usb_errors: u64,
    /// Ticks on which the motor commands saturated (scaled together).
    pub saturated_ticks: u64,
}

impl LinkStats {
    /// The counts since `earlier`.
    pub fn since(&self, earlier: &LinkStats) -> LinkStats {
        LinkStats {
            packets: self.packets.saturating_sub(earlier.packets),
            replies: self.replies.saturating_sub(earlier.replies),
            bad_packets: self.bad_packets.saturating_sub(earlier.bad_packets),
            missed_replies: self.missed_replies.saturating_sub(earlier.missed_replies),
            usb_errors: self.usb_errors.saturating_sub(earlier.usb_errors),
            saturated_ticks: self.saturated_ticks.saturating_sub(earlier.saturated_ticks),
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeviceError {
    #[error("the device is gone: {0}")]
    Disconnected(String),
    #[error("device I/O failed: {0}")]
    Io(String),
    #[error("the device returned an invalid reading: {0}")]
    BadReading(String),
}

pub trait HapticDevice: Send {
    /// The backend's name, as recorded in `device = "…"`.
    fn kind(&self) -> &'static str;
    /// Read the end effector at time `t_s` (seconds since the loop started).
    /// A simulated device advances its physics to `t_s` under the force
    /// last commanded.
    fn read(&mut self, t_s: f64) -> Result<Reading, DeviceError>;
    /// Command a force (newtons, profile frame). The caller guarantees it is
    /// finite and within limits; it holds until the next command.
    fn command(&mut self, force_n: [f64; 3]) -> Result<(), DeviceError>;
    /// Zero the forces, best effort; must not panic. Called on every exit path.
    fn make_safe(&mut self);
    /// Link counters, for devices that talk in packets (the Falcon).
    fn link_stats(&self) -> Option<LinkStats> {
        None
    }
    /// How long the last read stalled, for simulated devices with an injected
    /// stall (`stall_after_s`): the servo loop's clock then sits the stall
    /// out — really in real time, virtually in virtual time — as it would a
    /// USB read that blocked. Devices never sleep themselves. Taken once.
    fn take_stall(&mut self) -> Option<std::time::Duration> {
        None
    }
}

impl<D: HapticDevice + ?Sized> HapticDevice for Box<D> {
    fn kind(&self) -> &'static str {
        (**self).kind()
    }
    fn read(&mut self, t_s: f64) -> Result<Reading, DeviceError> {
        (**self).read(t_s)
    }
    fn command(&mut self, force_n: [f64; 3]) -> Result<(), DeviceError> {
        (**self).command(force_n)
    }
    fn make_safe(&mut self) {
        (**self).make_safe()
    }
    fn link_stats(&self) -> Option<LinkStats> {
        (**self).link_stats()
    }
    fn take_stall(&mut self) -> Option<std::time::Duration> {
        (**self).take_stall()
    }
}
