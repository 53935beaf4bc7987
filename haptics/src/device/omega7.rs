//! The real Omega.7 through Force Dimension's SDK (`libdhd`), loaded at run time.
//!
//! As in CHAI3D's `CDeltaDevices.cpp`, the library is opened with the dynamic loader and each
//! function is looked up by name; every lookup has an availability flag, so a library that
//! lacks an optional function (the gripper on an omega.3, the button mask) still works and a
//! missing required one is a typed error naming it. Forces are off until
//! [`HapticDevice::enable_forces`] turns them on.
//!
//! The functions are the SDK's C API (`dhdc.h`), called with the C calling convention; the
//! trailing `char ID` argument is the id `dhdOpen` returned.

use std::ffi::{CStr, c_char, c_int, c_uchar};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use glam::DVec3;

use super::backend::{Backend, BackendOption, Motion, OpenRequest, OpenedDevice};
use super::{
    DeviceSpecs, DeviceState, ForceCommand, ForceOverride, HapticDevice, HardwareWatchdog, InternalForces,
};
use crate::error::HapticsError;

/// Environment variable naming the library file to load instead of the default search.
pub const LIBRARY_ENV: &str = "PALPUS_DHD_LIBRARY";

/// File names tried, in order, through the dynamic loader's search path.
pub const LIBRARY_NAMES: [&str; 2] = ["libdhd.so", "libdhd.so.3"];

/// Force Dimension's USB vendor id.
pub const FORCE_DIMENSION_VENDOR_ID: u16 = 0x1451;

/// The library this backend needs, as its errors name it.
const SDK: &str = "the Force Dimension SDK (libdhd, version 3 or newer)";

/// The device, as its errors name it.
const DEVICE: &str = "Omega.7";

/// The friction of a simulated or real Omega.7's own mechanism, as the RFOB models it.
pub const OMEGA7_INTERNAL: InternalForces = InternalForces {
    viscous_nspm: 0.2,
    coulomb_n: 0.02,
    coulomb_band_mps: 1e-3,
    gravity_n: 0.0,
};

impl DeviceSpecs {
    /// Force Dimension Omega.7, from the data sheet and CHAI3D's device table: 12 N, active
    /// gripper 8 N, a workspace of Ø 160 mm, 5000 N/m, 30 N·s/m; its mechanism's friction
    /// [`OMEGA7_INTERNAL`].
    pub const OMEGA7: DeviceSpecs = DeviceSpecs {
        model: "omega.7",
        max_force_n: 12.0,
        max_gripper_force_n: 8.0,
        workspace_radius_m: 0.08,
        max_gripper_gap_m: 0.03,
        max_stiffness_npm: 5000.0,
        max_damping_nspm: 30.0,
        internal: OMEGA7_INTERNAL,
    };
}

type GetDeviceCount = unsafe extern "C" fn() -> c_int;
type Open = unsafe extern "C" fn() -> c_int;
type Close = unsafe extern "C" fn(c_char) -> c_int;
type GetVec3 = unsafe extern "C" fn(*mut f64, *mut f64, *mut f64, c_char) -> c_int;
type GetGripperGap = unsafe extern "C" fn(*mut f64, c_char) -> c_int;
type SetForceTorqueGripper = unsafe extern "C" fn(f64, f64, f64, f64, f64, f64, f64, c_char) -> c_int;
type EnableForce = unsafe extern "C" fn(c_uchar, c_char) -> c_int;
type GetSdkVersion = unsafe extern "C" fn(*mut c_int, *mut c_int, *mut c_int, *mut c_int);
type GetButtonMask = unsafe extern "C" fn(c_char) -> c_int;
type GetTime = unsafe extern "C" fn() -> f64;
type ErrorGetLastStr = unsafe extern "C" fn() -> *const c_char;
type GetSystemName = unsafe extern "C" fn(c_char) -> *const c_char;
type SetWatchdog = unsafe extern "C" fn(c_uchar, c_char) -> c_int;

/// The SDK's functions palpus uses, each written once: the field that holds it, its C type,
/// its symbol and whether a library without it is refused. The macro makes of this one table
/// the `Functions` struct, its lookup, [`SYMBOLS`] and [`DhdLibrary::has`]: a new function
/// is one line here.
macro_rules! dhd_functions {
    ($($field:ident: $ty:ty = $symbol:literal, $required:literal;)*) => {
        /// The SDK's functions, each present or not.
        #[derive(Debug, Clone, Copy, Default)]
        struct Functions {
            $($field: Option<$ty>,)*
        }

        /// The SDK's functions palpus looks up, and whether each is required.
        pub const SYMBOLS: &[(&str, bool)] = &[$(($symbol, $required),)*];

        impl Functions {
            /// Looks each function up by name.
            ///
            /// # Safety
            /// Each type in the table must be the C prototype of its symbol in Force Dimension's
            /// `dhdc.h` (SDK 3.x), with `char ID` as `c_char` and `uchar` as `c_uchar`.
            unsafe fn look_up(library: &libloading::Library) -> Self {
                // SAFETY: the caller guarantees each type matches its symbol.
                unsafe { Self { $($field: lookup(library, $symbol),)* } }
            }

            fn has(&self, symbol: &str) -> bool {
                match symbol {
                    $($symbol => self.$field.is_some(),)*
                    _ => false,
                }
            }
        }
    };
}

dhd_functions! {
    get_device_count: GetDeviceCount = "dhdGetDeviceCount", false;
    open: Open = "dhdOpen", true;
    close: Close = "dhdClose", true;
    get_position: GetVec3 = "dhdGetPosition", true;
    get_linear_velocity: GetVec3 = "dhdGetLinearVelocity", true;
    get_gripper_gap: GetGripperGap = "dhdGetGripperGap", false;
    set_force_torque_gripper: SetForceTorqueGripper = "dhdSetForceAndTorqueAndGripperForce", true;
    enable_force: EnableForce = "dhdEnableForce", true;
    get_sdk_version: GetSdkVersion = "dhdGetSDKVersion", false;
    get_button_mask: GetButtonMask = "dhdGetButtonMask", false;
    get_time: GetTime = "dhdGetTime", false;
    error_get_last_str: ErrorGetLastStr = "dhdErrorGetLastStr", false;
    get_system_name: GetSystemName = "dhdGetSystemName", false;
    set_watchdog: SetWatchdog = "dhdSetWatchdog", false;
}

/// The loaded SDK.
pub struct DhdLibrary {
    path: PathBuf,
    functions: Functions,
    // Keeps the code behind `functions` mapped; declared last so it is dropped last.
    _library: libloading::Library,
}

impl std::fmt::Debug for DhdLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DhdLibrary")
            .field("path", &self.path)
            .field("available", &self.available())
            .finish_non_exhaustive()
    }
}

/// The SDK's version.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdkVersion {
    /// Major.
    pub major: i32,
    /// Minor.
    pub minor: i32,
    /// Release.
    pub release: i32,
    /// Revision.
    pub revision: i32,
}

impl std::fmt::Display for SdkVersion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}.{}.{}.{}",
            self.major, self.minor, self.release, self.revision
        )
    }
}

/// Reads a symbol of type `T` if the library has it.
///
/// # Safety
/// `T` must be the exact function-pointer type of the C function named `name`.
unsafe fn lookup<T: Copy>(library: &libloading::Library, name: &str) -> Option<T> {
    // SAFETY: the caller guarantees `T` matches the symbol's type; the copied pointer stays
    // valid while `library` is loaded, which `DhdLibrary` guarantees by owning it.
    unsafe { library.get::<T>(name.as_bytes()).ok().map(|s| *s) }
}

impl DhdLibrary {
    /// Loads the SDK: `explicit` if given, else the file named by `PALPUS_DHD_LIBRARY`, else
    /// `libdhd.so` and `libdhd.so.3` through the loader's search path.
    pub fn load(explicit: Option<&Path>) -> Result<Self, HapticsError> {
        let env = std::env::var_os(LIBRARY_ENV).map(PathBuf::from);
        let candidates: Vec<PathBuf> = match explicit.map(Path::to_path_buf).or(env) {
            Some(path) => vec![path],
            None => LIBRARY_NAMES.iter().map(PathBuf::from).collect(),
        };
        let mut tried = Vec::new();
        for candidate in candidates {
            // SAFETY: loading a shared library runs its initialisers; libdhd's (or a library
            // the user pointed us to as libdhd) are trusted like any linked dependency.
            match unsafe { libloading::Library::new(&candidate) } {
                Ok(library) => return Self::from_library(library, candidate),
                Err(e) => tried.push(format!("{}: {e}", candidate.display())),
            }
        }
        Err(HapticsError::SdkMissing {
            sdk: SDK,
            tried: tried.join("; "),
        })
    }

    fn from_library(library: libloading::Library, path: PathBuf) -> Result<Self, HapticsError> {
        // SAFETY: each type in the table above is the C prototype of its function in Force
        // Dimension's dhdc.h (SDK 3.x).
        let functions = unsafe { Functions::look_up(&library) };
        let lib = Self {
            path,
            functions,
            _library: library,
        };
        for &(name, required) in SYMBOLS {
            if required && !lib.has(name) {
                return Err(HapticsError::SymbolMissing {
                    sdk: SDK,
                    library: lib.path.display().to_string(),
                    symbol: name,
                });
            }
        }
        Ok(lib)
    }

    /// The file loaded.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Sends `c` (no torque) to device `id`: the SDK's return code, or `None` without the
    /// function. The one path a force takes to the device, from the haptic thread and from the
    /// watchdog's.
    fn send_force(&self, c: &ForceCommand, id: c_char) -> Option<c_int> {
        let f = self.functions.set_force_torque_gripper?;
        let [x, y, z] = c.force_n.to_array();
        // SAFETY: plain doubles and the device id, per dhdc.h.
        Some(unsafe { f(x, y, z, 0.0, 0.0, 0.0, c.gripper_force_n, id) })
    }

    /// Whether the library exports `symbol` (one of [`SYMBOLS`]).
    pub fn has(&self, symbol: &str) -> bool {
        self.functions.has(symbol)
    }

    /// Every looked-up symbol with its availability.
    pub fn available(&self) -> Vec<(&'static str, bool)> {
        SYMBOLS.iter().map(|&(name, _)| (name, self.has(name))).collect()
    }

    /// The SDK version, if the library reports it.
    pub fn sdk_version(&self) -> Option<SdkVersion> {
        let f = self.functions.get_sdk_version?;
        let (mut major, mut minor, mut release, mut revision) = (0, 0, 0, 0);
        // SAFETY: four valid, writable c_int locations that outlive the call.
        unsafe { f(&mut major, &mut minor, &mut release, &mut revision) };
        Some(SdkVersion {
            major,
            minor,
            release,
            revision,
        })
    }

    /// Number of Force Dimension devices connected, if the library can tell.
    pub fn device_count(&self) -> Option<i32> {
        let f = self.functions.get_device_count?;
        // SAFETY: no arguments; the SDK returns a count or −1.
        Some(unsafe { f() })
    }

    /// The SDK's description of its last error.
    pub fn last_error(&self) -> Option<String> {
        let f = self.functions.error_get_last_str?;
        // SAFETY: the SDK returns null or a pointer to a NUL-terminated static string.
        unsafe {
            let p = f();
            (!p.is_null()).then(|| CStr::from_ptr(p).to_string_lossy().into_owned())
        }
    }
}

/// An open Omega.7.
#[derive(Debug)]
pub struct Omega7 {
    lib: Arc<DhdLibrary>,
    specs: DeviceSpecs,
    system: String,
    id: c_int,
    override_: Arc<DhdOverride>,
    clock_start_s: Option<f64>,
    open: bool,
    watchdog: Option<Duration>,
}

/// The watchdog's path to the device: scales the last command and sends it from the watchdog
/// thread. The SDK serialises calls per device internally, so this is safe beside the haptic
/// thread (which is stalled whenever this is used).
#[derive(Debug)]
pub struct DhdOverride {
    lib: Arc<DhdLibrary>,
    gate: super::ForceGate,
    id: AtomicU64,
}

impl ForceOverride for DhdOverride {
    fn set_force_scale(&self, scale: f64) {
        self.gate.set_force_scale(scale);
        let id = self.id.load(Ordering::Relaxed) as c_char;
        // Nothing to report to from the watchdog's thread: the haptic thread sees its own.
        let _ = self.lib.send_force(&self.gate.applied(), id);
    }

    fn force_scale(&self) -> f64 {
        self.gate.force_scale()
    }
}

impl Omega7 {
    /// Loads the SDK (see [`DhdLibrary::load`]) and opens the first device.
    pub fn open(library: Option<&Path>) -> Result<Self, HapticsError> {
        Self::open_with(Arc::new(DhdLibrary::load(library)?))
    }

    /// Opens the first device through an already loaded SDK.
    pub fn open_with(lib: Arc<DhdLibrary>) -> Result<Self, HapticsError> {
        if lib.device_count() == Some(0) {
            return Err(HapticsError::NoDevice {
                device: DEVICE,
                detail: "the SDK sees no Force Dimension device".into(),
            });
        }
        let open = lib.functions.open.ok_or(HapticsError::SymbolMissing {
            sdk: SDK,
            library: lib.path.display().to_string(),
            symbol: "dhdOpen",
        })?;
        // SAFETY: no arguments; returns a device id ≥ 0 or −1.
        let id = unsafe { open() };
        if id < 0 {
            return Err(HapticsError::NoDevice {
                device: DEVICE,
                detail: lib
                    .last_error()
                    .unwrap_or_else(|| format!("dhdOpen returned {id}")),
            });
        }
        let system = lib
            .functions
            .get_system_name
            .and_then(|f| {
                // SAFETY: returns null or a NUL-terminated static string.
                unsafe {
                    let p = f(id as c_char);
                    (!p.is_null()).then(|| CStr::from_ptr(p).to_string_lossy().into_owned())
                }
            })
            .unwrap_or_else(|| "omega.7".into());
        let override_ = Arc::new(DhdOverride {
            lib: lib.clone(),
            gate: super::ForceGate::new(),
            id: AtomicU64::new(id as u64),
        });
        let mut device = Self {
            lib,
            specs: DeviceSpecs::OMEGA7,
            system,
            id,
            override_,
            clock_start_s: None,
            open: true,
            watchdog: None,
        };
        // Forces stay off until the loop enables them.
        device.enable_forces(false)?;
        Ok(device)
    }

    /// The device's name as the SDK reports it.
    pub fn system_name(&self) -> &str {
        &self.system
    }

    /// The loaded SDK.
    pub fn library(&self) -> &Arc<DhdLibrary> {
        &self.lib
    }

    fn check(&self, call: &'static str, code: c_int) -> Result<(), HapticsError> {
        if code < 0 {
            Err(HapticsError::DeviceCall {
                call,
                code,
                tick: None,
            })
        } else {
            Ok(())
        }
    }

    fn id(&self) -> c_char {
        self.id as c_char
    }
}

impl HapticDevice for Omega7 {
    fn specs(&self) -> &DeviceSpecs {
        &self.specs
    }

    fn name(&self) -> &str {
        "omega7"
    }

    fn enable_forces(&mut self, enabled: bool) -> Result<(), HapticsError> {
        if !self.open {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let Some(f) = self.lib.functions.enable_force else {
            return Err(HapticsError::DeviceFault {
                what: "dhdEnableForce missing",
                tick: None,
            });
        };
        // SAFETY: a flag and the device id, per dhdc.h.
        let code = unsafe { f(c_uchar::from(enabled), self.id()) };
        self.check("dhdEnableForce", code)
    }

    fn read_state(&mut self) -> Result<DeviceState, HapticsError> {
        if !self.open {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let f = &self.lib.functions;
        let (mut px, mut py, mut pz) = (0.0, 0.0, 0.0);
        let (mut vx, mut vy, mut vz) = (0.0, 0.0, 0.0);
        let (Some(position), Some(velocity)) = (f.get_position, f.get_linear_velocity) else {
            return Err(HapticsError::DeviceFault {
                what: "position functions missing",
                tick: None,
            });
        };
        // SAFETY: three writable doubles each, and the device id, per dhdc.h.
        let code = unsafe { position(&mut px, &mut py, &mut pz, self.id()) };
        self.check("dhdGetPosition", code)?;
        // SAFETY: as above.
        let code = unsafe { velocity(&mut vx, &mut vy, &mut vz, self.id()) };
        self.check("dhdGetLinearVelocity", code)?;
        let mut gap = 0.0;
        if let Some(g) = f.get_gripper_gap {
            // SAFETY: one writable double and the device id.
            let code = unsafe { g(&mut gap, self.id()) };
            self.check("dhdGetGripperGap", code)?;
        }
        let buttons = f.get_button_mask.map_or(0, |b| {
            // SAFETY: the device id; returns the mask.
            let mask = unsafe { b(self.id()) };
            u32::try_from(mask).unwrap_or(0)
        });
        let time_s = match f.get_time {
            Some(t) => {
                // SAFETY: no arguments; returns seconds.
                let now = unsafe { t() };
                now - *self.clock_start_s.get_or_insert(now)
            }
            None => 0.0,
        };
        Ok(DeviceState {
            time_s,
            position_m: DVec3::new(px, py, pz),
            velocity_mps: DVec3::new(vx, vy, vz),
            gripper_gap_m: gap,
            buttons,
        })
    }

    fn command(&mut self, command: &ForceCommand) -> Result<(), HapticsError> {
        if !self.open {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let c = self.override_.gate.pass(command);
        let Some(code) = self.lib.send_force(&c, self.id()) else {
            return Err(HapticsError::DeviceFault {
                what: "dhdSetForceAndTorqueAndGripperForce missing",
                tick: None,
            });
        };
        self.check("dhdSetForceAndTorqueAndGripperForce", code)
    }

    fn force_override(&self) -> Arc<dyn ForceOverride> {
        self.override_.clone()
    }

    fn close(&mut self) -> Result<(), HapticsError> {
        if !self.open {
            return Ok(());
        }
        let zeroed = self.command(&ForceCommand::ZERO);
        let disabled = self.enable_forces(false);
        self.open = false;
        if let Some(close) = self.lib.functions.close {
            // SAFETY: the device id, per dhdc.h.
            let code = unsafe { close(self.id()) };
            self.check("dhdClose", code)?;
        }
        zeroed.and(disabled)
    }

    /// `dhdSetWatchdog` (SDK 3.3.2 and later) with the period in 125 µs steps; an older SDK
    /// has none (`None`), and the software watchdog alone guards a stall.
    fn arm_watchdog(&mut self, period: Duration) -> Result<Option<Duration>, HapticsError> {
        if !self.open {
            return Err(HapticsError::DeviceClosed { tick: None });
        }
        let Some(f) = self.lib.functions.set_watchdog else {
            return Ok(None);
        };
        let steps = super::watchdog_steps(period);
        // SAFETY: the period in steps and the device id, per dhdc.h.
        let code = unsafe { f(steps, self.id()) };
        self.check("dhdSetWatchdog", code)?;
        let armed = super::WATCHDOG_STEP * u32::from(steps);
        self.watchdog = Some(armed);
        Ok(Some(armed))
    }

    fn hardware_watchdog(&self) -> Option<HardwareWatchdog> {
        self.watchdog.map(|period| HardwareWatchdog {
            period,
            longest_gap: None,
            trips: None,
        })
    }
}

impl Drop for Omega7 {
    fn drop(&mut self) {
        // The device must never be left commanding a force.
        let _ = self.close();
    }
}

/// A Force Dimension device seen on the USB bus (Linux sysfs), whether or not the SDK is
/// installed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UsbDevice {
    /// The sysfs path.
    pub path: PathBuf,
    /// Product id.
    pub product_id: u16,
    /// Product string, if the device reports one.
    pub product: Option<String>,
}

/// Force Dimension devices on the USB bus, from `/sys/bus/usb/devices` (empty where that does
/// not exist).
pub fn usb_devices() -> Vec<UsbDevice> {
    usb_devices_under(Path::new("/sys/bus/usb/devices"))
}

fn usb_devices_under(root: &Path) -> Vec<UsbDevice> {
    let Ok(entries) = std::fs::read_dir(root) else {
        return Vec::new();
    };
    let read_hex = |p: PathBuf| {
        std::fs::read_to_string(p)
            .ok()
            .and_then(|s| u16::from_str_radix(s.trim(), 16).ok())
    };
    let mut found: Vec<UsbDevice> = entries
        .flatten()
        .filter(|e| read_hex(e.path().join("idVendor")) == Some(FORCE_DIMENSION_VENDOR_ID))
        .map(|e| UsbDevice {
            product_id: read_hex(e.path().join("idProduct")).unwrap_or(0),
            product: std::fs::read_to_string(e.path().join("product"))
                .ok()
                .map(|s| s.trim().to_owned()),
            path: e.path(),
        })
        .collect();
    found.sort_by(|a, b| a.path.cmp(&b.path));
    found
}

/// The Omega.7 in the device registry: `omega7` or `omega7:PATH` (the SDK library).
pub static BACKEND: Backend = Backend {
    name: "omega7",
    summary: "Force Dimension Omega.7",
    specs: DeviceSpecs::OMEGA7,
    option: Some(BackendOption {
        value_name: "PATH",
        help: "the Force Dimension SDK library (default: $PALPUS_DHD_LIBRARY, then libdhd.so)",
        required: false,
    }),
    simulated: false,
    motion: Motion::Operator,
    open,
    probe,
};

fn open(request: OpenRequest<'_>) -> Result<OpenedDevice, HapticsError> {
    Ok(OpenedDevice {
        device: Box::new(Omega7::open(request.option.map(Path::new))?),
        script_end_s: None,
    })
}

/// The Omega.7 on the USB bus (it is raw USB, not HID) and through its SDK.
fn probe(library: Option<&str>) -> Vec<String> {
    let mut lines = Vec::new();
    let usb = usb_devices();
    if usb.is_empty() {
        lines.push(format!(
            "USB (vendor {FORCE_DIMENSION_VENDOR_ID:04x}): none found"
        ));
    }
    for d in &usb {
        lines.push(format!(
            "USB: {FORCE_DIMENSION_VENDOR_ID:04x}:{:04x}  {}  {}",
            d.product_id,
            d.product.as_deref().unwrap_or("?"),
            d.path.display()
        ));
    }
    match DhdLibrary::load(library.map(Path::new)) {
        Err(e) => lines.push(format!("SDK: not found: {e}")),
        Ok(lib) => {
            let version = lib.sdk_version().map_or("unknown".into(), |v| v.to_string());
            lines.push(format!("SDK: {} (SDK {version})", lib.path().display()));
            let missing: Vec<&str> = lib
                .available()
                .into_iter()
                .filter(|(_, present)| !present)
                .map(|(name, _)| name)
                .collect();
            if !missing.is_empty() {
                lines.push(format!("SDK: optional functions missing: {}", missing.join(", ")));
            }
            match Omega7::open_with(Arc::new(lib)) {
                Ok(device) => lines.push(format!("connected ({})", device.system_name())),
                Err(e) => lines.push(format!("none found ({e})")),
            }
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_library_says_what_to_do() {
        let e = DhdLibrary::load(Some(Path::new("/nonexistent/libdhd.so"))).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, HapticsError::SdkMissing { .. }));
        assert!(
            text.starts_with("the Force Dimension SDK (libdhd, version 3 or newer) was not found")
                && text.contains("install it, or run on the simulated device"),
            "{text}"
        );
        assert!(text.contains("/nonexistent/libdhd.so"), "{text}");
    }

    #[test]
    fn usb_scan_finds_force_dimension_devices_only() {
        let dir = tempfile::tempdir().unwrap();
        for (name, vendor, product) in [("1-1", "1451", "0402"), ("1-2", "046d", "c52b")] {
            let d = dir.path().join(name);
            std::fs::create_dir(&d).unwrap();
            std::fs::write(d.join("idVendor"), format!("{vendor}\n")).unwrap();
            std::fs::write(d.join("idProduct"), format!("{product}\n")).unwrap();
        }
        let found = usb_devices_under(dir.path());
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].product_id, 0x0402);
        assert!(usb_devices_under(Path::new("/nonexistent")).is_empty());
    }
}
