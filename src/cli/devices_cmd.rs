//! `palpus devices`.

use clap::Args;
use haptics::list_hid_devices;
use haptics::{DeviceChoice, Registry};

use super::device_arg::parse_device;

/// List the haptic devices palpus can open and whether each is found, and the HID input
/// devices (foot pedals, clutches).
///
/// Every device of the registry is looked for without being opened: the Omega.7 on the USB bus
/// (vendor 0x1451; it is raw USB, not HID) and through the Force Dimension SDK (libdhd).
/// Finding nothing is not an error.
#[derive(Debug, Args)]
pub(crate) struct DevicesArgs {
    /// A device's option to look with, as `--device` takes it (omega7:PATH tries that SDK
    /// library instead of $PALPUS_DHD_LIBRARY, then libdhd.so). Repeatable.
    #[arg(long, value_name = "NAME:OPTION", value_parser = parse_device)]
    device: Vec<DeviceChoice>,
}

pub(crate) fn run(args: &DevicesArgs) -> anyhow::Result<()> {
    let registry = Registry::builtin();
    println!("Haptic devices (--device NAME[:OPTION]):");
    for backend in registry.backends() {
        let option = args
            .device
            .iter()
            .rev()
            .find(|d| d.backend() == *backend)
            .and_then(DeviceChoice::option);
        let specs = &backend.specs;
        println!(
            "  {:<8} {} (max {} N, workspace radius {} mm)",
            backend.name,
            backend.summary,
            specs.max_force_n,
            specs.workspace_radius_m * 1e3
        );
        for line in (backend.probe)(option) {
            println!("           {line}");
        }
    }
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
    Ok(())
}
