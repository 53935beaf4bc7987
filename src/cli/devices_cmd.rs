//! `palpus devices`.

use std::path::PathBuf;

use clap::Args;
use haptics::device::hid::list_hid_devices;
use haptics::device::omega7::{DhdLibrary, FORCE_DIMENSION_VENDOR_ID, Omega7, usb_devices};

/// List input devices: HID devices (foot pedals, clutches) and whether the Omega.7's SDK and
/// the device itself are found.
///
/// The Omega.7 is raw USB, not HID: it is looked for on the USB bus (vendor 0x1451) and
/// through the Force Dimension SDK (libdhd). Finding nothing is not an error.
#[derive(Debug, Args)]
pub(crate) struct DevicesArgs {
    /// The SDK library to try (default: $PALPUS_DHD_LIBRARY, then libdhd.so).
    #[arg(long, value_name = "PATH")]
    dhd_library: Option<PathBuf>,
}

pub(crate) fn run(args: &DevicesArgs) -> anyhow::Result<()> {
    println!("HID devices:");
    match list_hid_devices() {
        Ok(list) if list.is_empty() => println!("  none found"),
        Ok(list) => {
            for d in list {
                println!(
                    "  {:04x}:{:04x}  {} {}  (usage {:04x}:{:04x})  {}",
                    d.vendor_id,
                    d.product_id,
                    d.manufacturer.as_deref().unwrap_or("?"),
                    d.product.as_deref().unwrap_or("?"),
                    d.usage_page,
                    d.usage,
                    d.path
                );
            }
        }
        Err(e) => println!("  none found ({e})"),
    }

    println!("Force Dimension devices on USB (vendor {FORCE_DIMENSION_VENDOR_ID:04x}):");
    let usb = usb_devices();
    if usb.is_empty() {
        println!("  none found");
    }
    for d in &usb {
        println!(
            "  {:04x}:{:04x}  {}  {}",
            FORCE_DIMENSION_VENDOR_ID,
            d.product_id,
            d.product.as_deref().unwrap_or("?"),
            d.path.display()
        );
    }

    println!("Omega.7 SDK (libdhd):");
    match DhdLibrary::load(args.dhd_library.as_deref()) {
        Err(e) => {
            println!("  not found: {e}");
            println!("Omega.7: not available; use --device sim");
        }
        Ok(lib) => {
            let version = lib.sdk_version().map_or("unknown".into(), |v| v.to_string());
            println!("  {} (SDK {version})", lib.path().display());
            let missing: Vec<&str> = lib
                .available()
                .into_iter()
                .filter(|(_, present)| !present)
                .map(|(name, _)| name)
                .collect();
            if !missing.is_empty() {
                println!("  optional functions missing: {}", missing.join(", "));
            }
            match Omega7::open_with(std::sync::Arc::new(lib)) {
                Ok(device) => println!("Omega.7: connected ({})", device.system_name()),
                Err(e) => println!("Omega.7: none found ({e})"),
            }
        }
    }
    Ok(())
}
