//! HID input devices: discovery for `palpus devices`, and a foot pedal or clutch read on its
//! own thread.
//!
//! hidapi is built with its pure-Rust Linux backend (`linux-native-basic-udev`), so no libudev
//! or libusb is needed. The Omega.7 is raw USB, not HID, and never shows up here (see
//! [`super::omega7::usb_devices`]).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::JoinHandle;
use std::time::Duration;

use crate::error::HapticsError;

/// One HID device.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HidInfo {
    /// USB vendor id.
    pub vendor_id: u16,
    /// USB product id.
    pub product_id: u16,
    /// Manufacturer string.
    pub manufacturer: Option<String>,
    /// Product string.
    pub product: Option<String>,
    /// HID usage page.
    pub usage_page: u16,
    /// HID usage.
    pub usage: u16,
    /// OS path (hidraw node).
    pub path: String,
}

/// Every HID device the system shows (empty when there are none).
pub fn list_hid_devices() -> Result<Vec<HidInfo>, HapticsError> {
    let api = hidapi::HidApi::new()?;
    let mut list: Vec<HidInfo> = api
        .device_list()
        .map(|d| HidInfo {
            vendor_id: d.vendor_id(),
            product_id: d.product_id(),
            manufacturer: d.manufacturer_string().map(str::to_owned),
            product: d.product_string().map(str::to_owned),
            usage_page: d.usage_page(),
            usage: d.usage(),
            path: d.path().to_string_lossy().into_owned(),
        })
        .collect();
    list.sort_by(|a, b| a.path.cmp(&b.path));
    list.dedup();
    Ok(list)
}

/// Where in an input report the pedal's switch is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PedalMapping {
    /// Byte index in the report.
    pub byte: usize,
    /// Bits that mean "pressed".
    pub mask: u8,
}

impl PedalMapping {
    /// Whether `report` says pressed (a short report says not pressed).
    pub fn pressed(&self, report: &[u8]) -> bool {
        report.get(self.byte).is_some_and(|b| b & self.mask != 0)
    }
}

/// A pedal's state, shared lock-free with the haptic thread.
#[derive(Debug, Default)]
pub struct PedalState {
    pressed: AtomicBool,
    reports: AtomicU64,
}

impl PedalState {
    /// Whether the pedal is down now.
    pub fn pressed(&self) -> bool {
        self.pressed.load(Ordering::Acquire)
    }

    /// Reports read so far.
    pub fn reports(&self) -> u64 {
        self.reports.load(Ordering::Relaxed)
    }

    /// Records one input report.
    pub fn update(&self, mapping: PedalMapping, report: &[u8]) {
        self.pressed.store(mapping.pressed(report), Ordering::Release);
        self.reports.fetch_add(1, Ordering::Relaxed);
    }
}

/// A HID foot pedal (or hand clutch) read on a thread of its own; the haptic thread reads
/// [`PedalState::pressed`], an atomic.
#[derive(Debug)]
pub struct Pedal {
    state: Arc<PedalState>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Pedal {
    /// Opens the first HID device with `vendor_id:product_id` and starts reading it.
    pub fn open(vendor_id: u16, product_id: u16, mapping: PedalMapping) -> Result<Self, HapticsError> {
        let api = hidapi::HidApi::new()?;
        let device = api.open(vendor_id, product_id)?;
        let state = Arc::new(PedalState::default());
        let stop = Arc::new(AtomicBool::new(false));
        let (s, st) = (state.clone(), stop.clone());
        let thread = std::thread::Builder::new()
            .name("hid-pedal".into())
            .spawn(move || {
                let mut report = [0u8; 64];
                while !st.load(Ordering::Acquire) {
                    match device.read_timeout(&mut report, 50) {
                        Ok(0) => {}
                        Ok(n) => s.update(mapping, &report[..n]),
                        Err(_) => {
                            // Unplugged: a released pedal is the safe reading.
                            s.pressed.store(false, Ordering::Release);
                            std::thread::sleep(Duration::from_millis(200));
                        }
                    }
                }
            })
            .map_err(|source| HapticsError::Spawn {
                thread: "pedal",
                source,
            })?;
        Ok(Self {
            state,
            stop,
            thread: Some(thread),
        })
    }

    /// The shared state.
    pub fn state(&self) -> &Arc<PedalState> {
        &self.state
    }
}

impl Drop for Pedal {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pedal_mapping_reads_the_switch_bit() {
        let m = PedalMapping { byte: 1, mask: 0b100 };
        assert!(m.pressed(&[0, 0b101]));
        assert!(!m.pressed(&[0xff, 0b011]));
        assert!(!m.pressed(&[0b100]));
        let s = PedalState::default();
        s.update(m, &[0, 4]);
        assert!(s.pressed() && s.reports() == 1);
    }

    #[test]
    fn listing_never_panics_without_devices() {
        // No HID hardware here: an empty list or an error, both fine.
        match list_hid_devices() {
            Ok(list) => assert!(list.iter().all(|d| !d.path.is_empty())),
            Err(e) => assert!(!e.to_string().is_empty()),
        }
    }
}
