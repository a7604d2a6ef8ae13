//! The real trigger backend: hidapi with its pure-Rust Linux backend
//! (`linux-native-basic-udev`: hidraw and sysfs, no libudev, no C), and the
//! listing of HID devices for `hapticlab devices`.

use std::time::Duration;

use hidapi::HidApi;

use super::{OpenFailure, TriggerBackend, TriggerSource, TriggerSpec};

/// One HID device, as `hapticlab devices` lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct HidInfo {
    pub vendor_id: u16,
    pub product_id: u16,
    pub manufacturer: Option<String>,
    pub product: Option<String>,
    pub path: String,
}

/// Every HID device the system shows (deduplicated per device path).
pub fn list() -> Result<Vec<HidInfo>, String> {
    let api = HidApi::new().map_err(|e| format!("cannot list HID devices: {e}"))?;
    let mut out: Vec<HidInfo> = api
        .device_list()
        .map(|d| HidInfo {
            vendor_id: d.vendor_id(),
            product_id: d.product_id(),
            manufacturer: d.manufacturer_string().map(str::to_string),
            product: d.product_string().map(str::to_string),
            path: d.path().to_string_lossy().into_owned(),
        })
        .collect();
    out.sort_by(|a, b| a.path.cmp(&b.path));
    out.dedup_by(|a, b| a.path == b.path);
    Ok(out)
}

/// Opens triggers through hidapi.
pub struct HidBackend {
    api: Option<HidApi>,
}

impl HidBackend {
    pub fn new() -> HidBackend {
        HidBackend { api: None }
    }
}

impl Default for HidBackend {
    fn default() -> Self {
        Self::new()
    }
}

impl TriggerBackend for HidBackend {
    fn open(&mut self, spec: &TriggerSpec) -> Result<Box<dyn TriggerSource>, OpenFailure> {
        if self.api.is_none() {
            self.api = Some(HidApi::new().map_err(|e| OpenFailure::Other(e.to_string()))?);
        }
        let api = self.api.as_mut().expect("made above");
        api.refresh_devices()
            .map_err(|e| OpenFailure::Other(e.to_string()))?;
        let present = api
            .device_list()
            .any(|d| d.vendor_id() == spec.vendor_id && d.product_id() == spec.product_id);
        if !present {
            return Err(OpenFailure::Absent);
        }
        match api.open(spec.vendor_id, spec.product_id) {
            Ok(d) => Ok(Box::new(HidSource(d))),
            Err(e) => {
                let m = e.to_string();
                if m.to_lowercase().contains("permission") {
                    Err(OpenFailure::Permission(m))
                } else {
                    Err(OpenFailure::Other(m))
                }
            }
        }
    }
}

struct HidSource(hidapi::HidDevice);

impl TriggerSource for HidSource {
    fn read(&mut self, buf: &mut [u8], timeout: Duration) -> Result<usize, String> {
        let ms = i32::try_from(timeout.as_millis()).unwrap_or(i32::MAX);
        self.0.read_timeout(buf, ms).map_err(|e| e.to_string())
    }
}
