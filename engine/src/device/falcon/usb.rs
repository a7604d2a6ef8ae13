//! The USB transport: a Falcon's FTDI chip driven directly through nusb
//! (pure Rust over Linux usbfs: no libusb, no libftdi, no system packages).
//!
//! It owns finding Falcons (vendor 0x0403, product 0xCB48), opening one
//! (detaching any kernel driver from interface 0 and claiming it), sending
//! the FTDI vendor control requests, writing bulk OUT (endpoint 0x02) from a
//! small pool of reused buffers, and keeping several bulk IN reads (0x81, one
//! 64-byte packet each) always pending so that replies stream in at ~1 kHz.
//! Every IN packet starts with two FTDI modem-status bytes, stripped here.
//! A failed IN transfer (stall, overflow or other fault, timeout) is handed
//! up as a transient error, the read resubmitted (after clearing the halt of
//! a stalled endpoint); only a vanished device is final. It closes and
//! reopens the same device on request (between firmware attempts). It says
//! plainly when permissions prevent access and how to fix it.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use nusb::MaybeFuture;
use nusb::transfer::{Buffer, Bulk, ControlOut, ControlType, In, Out, Recipient, TransferError};

use super::{FalconTransport, TransportError, ftdi};

const INTERFACE: u8 = 0;
const EP_OUT: u8 = 0x02;
const EP_IN: u8 = 0x81;
/// Reads kept pending, and bytes each (one full-speed packet).
const IN_TRANSFERS: usize = 4;
const IN_LEN: usize = 64;
/// FTDI modem-status bytes at the start of every IN packet.
const STATUS_BYTES: usize = 2;
const OUT_BUFFERS: usize = 4;
const OUT_LEN: usize = 64;
const CONTROL_TIMEOUT: Duration = Duration::from_millis(200);
const WRITE_TIMEOUT: Duration = Duration::from_millis(100);

/// The udev rule (`contrib/70-novint-falcon.rules`), carried by the binary
/// so that `hapticlab doctor --udev-rule` can print it without a checkout.
pub const UDEV_RULE: &str = include_str!("../../../../contrib/70-novint-falcon.rules");
/// Where the rule goes, and the group its fallback names.
pub const UDEV_RULE_FILE: &str = "/etc/udev/rules.d/70-novint-falcon.rules";
pub const UDEV_GROUP: &str = "users";

/// How to install the rule.
pub const UDEV_HINT: &str = "install hapticlab's udev rule: \
`hapticlab doctor --udev-rule | sudo tee /etc/udev/rules.d/70-novint-falcon.rules && sudo udevadm control --reload-rules && sudo udevadm trigger`, \
then unplug and replug the Falcon; when not logged in at the machine itself (ssh), also join the `users` group \
(`sudo usermod -aG users $USER`) and log out and in again";

/// Why a Falcon could not be opened.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum UsbError {
    #[error(
        "no Novint Falcon (USB 0403:cb48) is plugged in{0}; plug it in directly (not through a hub) with its power supply connected"
    )]
    NotFound(String),
    #[error("permission denied opening the Falcon at {at}: {UDEV_HINT}")]
    Permission { at: String },
    #[error("the Falcon at {at} is in use by another program ({detail}); close it and try again")]
    Busy { at: String, detail: String },
    #[error("cannot open the Falcon at {at}: {detail}")]
    Other { at: String, detail: String },
    #[error(
        "cannot list USB devices ({0}): this system shows no USB bus (a container, or a VM without USB passthrough?), so no Falcon can be reached"
    )]
    List(String),
}

/// One attached Falcon, as `hapticlab devices` shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct FalconInfo {
    pub location: String,
    pub serial: Option<String>,
    pub product: Option<String>,
    /// `Ok` when it can be opened; the reason when not.
    pub access: Result<(), UsbError>,
}

fn location(d: &nusb::DeviceInfo) -> String {
    format!("USB bus {} device {}", d.busnum(), d.device_address())
}

fn falcons() -> Result<Vec<nusb::DeviceInfo>, UsbError> {
    let list = nusb::list_devices()
        .wait()
        .map_err(|e| UsbError::List(e.to_string()))?;
    Ok(list
        .filter(|d| d.vendor_id() == ftdi::VENDOR_ID && d.product_id() == ftdi::PRODUCT_ID)
        .collect())
}

fn open_error(at: String, e: nusb::Error) -> UsbError {
    match e.kind() {
        nusb::ErrorKind::PermissionDenied => UsbError::Permission { at },
        nusb::ErrorKind::Busy => UsbError::Busy {
            at,
            detail: e.to_string(),
        },
        nusb::ErrorKind::Disconnected | nusb::ErrorKind::NotFound => {
            UsbError::NotFound(format!(" (it vanished from {at})"))
        }
        _ => UsbError::Other {
            at,
            detail: e.to_string(),
        },
    }
}

/// Every attached Falcon, each tried for access (opened and closed again).
pub fn list_falcons() -> Result<Vec<FalconInfo>, UsbError> {
    Ok(falcons()?
        .into_iter()
        .map(|d| {
            let at = location(&d);
            let access = d
                .open()
                .wait()
                .map(|_| ())
                .map_err(|e| open_error(at.clone(), e));
            FalconInfo {
                location: at,
                serial: d.serial_number().map(str::to_string),
                product: d.product_string().map(str::to_string),
                access,
            }
        })
        .collect())
}

/// Drop the two modem-status bytes at the start of each `max_packet`-sized
/// piece of an IN transfer, passing the payload on.
pub fn strip_modem_status(data: &[u8], max_packet: usize, mut out: impl FnMut(&[u8])) {
    for packet in data.chunks(max_packet.max(STATUS_BYTES + 1)) {
        if packet.len() > STATUS_BYTES {
            out(&packet[STATUS_BYTES..]);
        }
    }
}

fn transfer_error(e: TransferError) -> TransportError {
    match e {
        TransferError::Disconnected => TransportError::Disconnected("USB device gone".into()),
        other => TransportError::Io(other.to_string()),
    }
}

/// What a failed bulk IN transfer means for the link: a vanished device is
/// final; anything else (a stall, an overflow or CRC fault, a timeout, an
/// error the OS has no name for) may pass, as libnifalcon treats it.
fn in_transfer_error(e: TransferError) -> TransportError {
    match e {
        TransferError::Disconnected => TransportError::Disconnected("USB device gone".into()),
        TransferError::Stall => TransportError::Transient("bulk IN endpoint stalled".into()),
        TransferError::Cancelled => TransportError::Transient("bulk IN transfer timed out".into()),
        other => TransportError::Transient(format!("bulk IN transfer failed: {other}")),
    }
}

/// A failed bulk OUT transfer: like a failed IN one, final only when the
/// device vanished (a single failed write must not end a session).
fn out_transfer_error(e: TransferError) -> TransportError {
    match e {
        TransferError::Disconnected => TransportError::Disconnected("USB device gone".into()),
        other => TransportError::Transient(format!("bulk OUT transfer failed: {other}")),
    }
}

/// An open Falcon: its handle, claimed interface, endpoints and buffers.
struct Handle {
    device: nusb::Device,
    _interface: nusb::Interface,
    ep_in: nusb::Endpoint<Bulk, In>,
    ep_out: nusb::Endpoint<Bulk, Out>,
    max_packet: usize,
    rx: VecDeque<u8>,
    free_out: Vec<Buffer>,
}

pub struct UsbTransport {
    /// `None` only between closing and reopening.
    handle: Option<Handle>,
    at: String,
    /// To find the same device again on reopening.
    bus: u8,
    address: u8,
}

impl UsbTransport {
    /// Open the `index`-th attached Falcon (0 = the first).
    pub fn open(index: usize) -> Result<UsbTransport, UsbError> {
        let all = falcons()?;
        let count = all.len();
        let info = all.into_iter().nth(index).ok_or_else(|| {
            UsbError::NotFound(if count == 0 {
                String::new()
            } else {
                format!(" at index {index} ({count} attached; `[falcon] index` counts from 0)")
            })
        })?;
        Self::open_info(&info)
    }

    fn open_info(info: &nusb::DeviceInfo) -> Result<UsbTransport, UsbError> {
        Ok(UsbTransport {
            handle: Some(Handle::open(info)?),
            at: location(info),
            bus: info.busnum(),
            address: info.device_address(),
        })
    }

    pub fn describe(&self) -> String {
        format!("the Novint Falcon at {}", self.at)
    }

    fn handle(&mut self) -> Result<&mut Handle, TransportError> {
        self.handle.as_mut().ok_or_else(|| {
            TransportError::Disconnected(format!("{} could not be reopened", self.at))
        })
    }
}

impl Handle {
    fn open(info: &nusb::DeviceInfo) -> Result<Handle, UsbError> {
        let at = location(info);
        let device = info.open().wait().map_err(|e| open_error(at.clone(), e))?;
        // 0403:cb48 is normally left alone by ftdi_sio; detach it if not.
        let interface = device
            .detach_and_claim_interface(INTERFACE)
            .wait()
            .map_err(|e| open_error(at.clone(), e))?;
        let other = |e: nusb::Error| UsbError::Other {
            at: at.clone(),
            detail: e.to_string(),
        };
        let mut ep_in = interface.endpoint::<Bulk, In>(EP_IN).map_err(other)?;
        let ep_out = interface.endpoint::<Bulk, Out>(EP_OUT).map_err(other)?;
        let max_packet = ep_in.max_packet_size().max(IN_LEN);
        for _ in 0..IN_TRANSFERS {
            ep_in.submit(ep_in.allocate(max_packet));
        }
        let free_out = (0..OUT_BUFFERS).map(|_| ep_out.allocate(OUT_LEN)).collect();
        Ok(Handle {
            device,
            _interface: interface,
            ep_in,
            ep_out,
            max_packet,
            rx: VecDeque::with_capacity(4096),
            free_out,
        })
    }

    /// A stalled IN endpoint fails every transfer until its halt is
    /// cleared: take back the pending reads, clear it, submit them again.
    fn recover_from_stall(&mut self) {
        self.ep_in.cancel_all();
        while self.ep_in.pending() > 0 {
            if self.ep_in.wait_next_complete(CONTROL_TIMEOUT).is_none() {
                break;
            }
        }
        let _ = self.ep_in.clear_halt().wait();
        while self.ep_in.pending() < IN_TRANSFERS {
            self.ep_in.submit(self.ep_in.allocate(self.max_packet));
        }
    }

    /// Take back finished OUT buffers; wait up to `wait` for one when none is free.
    fn reclaim(&mut self, wait: Duration) -> Result<(), TransportError> {
        let mut wait = wait;
        while self.ep_out.pending() > 0 {
            match self.ep_out.wait_next_complete(wait) {
                Some(c) => {
                    let status = c.status;
                    let mut b = c.buffer;
                    b.clear();
                    self.free_out.push(b);
                    status.map_err(out_transfer_error)?;
                    wait = Duration::ZERO;
                }
                None => break,
            }
        }
        Ok(())
    }

    /// Wait until every OUT transfer has completed, at most `timeout`.
    fn flush(&mut self, timeout: Duration) -> Result<(), TransportError> {
        let deadline = Instant::now() + timeout;
        let mut failed = Ok(());
        while self.ep_out.pending() > 0 {
            let left = deadline.saturating_duration_since(Instant::now());
            let Some(c) = self.ep_out.wait_next_complete(left) else {
                return Err(TransportError::Io(format!(
                    "{} USB write(s) still queued after {} ms",
                    self.ep_out.pending(),
                    timeout.as_millis()
                )));
            };
            let mut b = c.buffer;
            b.clear();
            self.free_out.push(b);
            if let Err(e) = c.status {
                failed = Err(out_transfer_error(e));
            }
        }
        failed
    }
}

impl Handle {
    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        if request == ftdi::PURGE && value & ftdi::PURGE_RX != 0 {
            self.rx.clear();
        }
        self.device
            .control_out(
                ControlOut {
                    control_type: ControlType::Vendor,
                    recipient: Recipient::Device,
                    request,
                    value,
                    index: 0,
                    data: &[],
                },
                CONTROL_TIMEOUT,
            )
            .wait()
            .map_err(transfer_error)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        for piece in bytes.chunks(OUT_LEN) {
            self.reclaim(Duration::ZERO)?;
            if self.free_out.is_empty() {
                self.reclaim(WRITE_TIMEOUT)?;
            }
            let Some(mut b) = self.free_out.pop() else {
                return Err(TransportError::Transient(
                    "USB writes are not completing (the Falcon stopped reading)".into(),
                ));
            };
            b.clear();
            b.extend_from_slice(piece);
            self.ep_out.submit(b);
        }
        Ok(())
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        let deadline = Instant::now() + timeout;
        loop {
            if !self.rx.is_empty() {
                let n = buf.len().min(self.rx.len());
                for (slot, b) in buf.iter_mut().zip(self.rx.drain(..n)) {
                    *slot = b;
                }
                return Ok(n);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            let Some(c) = self.ep_in.wait_next_complete(left) else {
                return Ok(0);
            };
            let status = c.status;
            let mut b = c.buffer;
            if status.is_ok() {
                let rx = &mut self.rx;
                strip_modem_status(&b, self.max_packet, |p| rx.extend(p));
            }
            // Keep the read pending whatever happened to this one.
            b.clear();
            b.set_requested_len(self.max_packet);
            self.ep_in.submit(b);
            if let Err(e) = status {
                if e == TransferError::Stall {
                    self.recover_from_stall();
                }
                return Err(in_transfer_error(e));
            }
            if self.rx.is_empty() && Instant::now() >= deadline {
                return Ok(0);
            }
        }
    }
}

impl FalconTransport for UsbTransport {
    fn kind(&self) -> &'static str {
        "falcon"
    }

    fn control(&mut self, request: u8, value: u16) -> Result<(), TransportError> {
        self.handle()?.control(request, value)
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), TransportError> {
        self.handle()?.write(bytes)
    }

    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, TransportError> {
        self.handle()?.read(buf, timeout)
    }

    fn flush(&mut self, timeout: Duration) -> Result<(), TransportError> {
        self.handle()?.flush(timeout)
    }

    fn reopen(&mut self) -> Result<(), TransportError> {
        // Close first: the interface can be claimed by one handle at a time.
        self.handle = None;
        let at = self.at.clone();
        let info = falcons()
            .map_err(|e| {
                TransportError::Disconnected(format!("{at} could not be found again: {e}"))
            })?
            .into_iter()
            .find(|d| d.busnum() == self.bus && d.device_address() == self.address)
            .ok_or_else(|| {
                TransportError::Disconnected(format!("{at} vanished while it was reopened"))
            })?;
        let handle = Handle::open(&info).map_err(|e| match e {
            UsbError::NotFound(m) => TransportError::Disconnected(m),
            other => TransportError::Io(other.to_string()),
        })?;
        self.handle = Some(handle);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modem_status_bytes_are_stripped_per_packet() {
        // Two 64-byte packets and a short one: 62 + 62 + 3 payload bytes.
        let mut raw = Vec::new();
        for (k, n) in [(0u8, 62usize), (1, 62), (2, 3)] {
            raw.extend([0x01, 0x60]);
            raw.extend(std::iter::repeat_n(b'a' + k, n));
        }
        let mut out = Vec::new();
        strip_modem_status(&raw, 64, |p| out.extend_from_slice(p));
        assert_eq!(out.len(), 127);
        assert!(out[..62].iter().all(|&b| b == b'a'));
        assert!(out[62..124].iter().all(|&b| b == b'b'));
        assert_eq!(&out[124..], b"ccc");
        // A status-only packet carries nothing.
        let mut n = 0;
        strip_modem_status(&[0x01, 0x60], 64, |p| n += p.len());
        assert_eq!(n, 0);
    }

    #[test]
    fn errors_say_how_to_fix_permissions() {
        let e = UsbError::Permission {
            at: "USB bus 1 device 7".into(),
        }
        .to_string();
        assert!(
            e.contains("hapticlab doctor --udev-rule") && e.contains("log out and in"),
            "{e}"
        );
        // The hint's file and group are the rule's own.
        assert!(e.contains(UDEV_RULE_FILE) && e.contains(UDEV_GROUP), "{e}");
        assert!(UDEV_RULE.contains(&format!("GROUP=\"{UDEV_GROUP}\"")));
        assert!(UDEV_RULE.contains("TAG+=\"uaccess\""));
        assert!(
            UsbError::NotFound(String::new())
                .to_string()
                .contains("0403:cb48")
        );
    }
}
