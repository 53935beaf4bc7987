//! With no Vulkan driver and no EGL vendor library reachable, opening a renderer fails with a
//! message that names the packages to install and the backends tried. The environment must be set
//! before the Vulkan loader starts, so the check runs in a child process of this test binary.

#![allow(clippy::unwrap_used)] // A failed unwrap is a failed test.

use std::process::Command;

use render::{Backend, GpuOptions, RenderError, Renderer};

const CHILD_ENV: &str = "PALPUS_NO_ADAPTER_CHILD";

/// `name`, a test of this module, as the harness names it: the module path less the binary's.
fn own_test(name: &str) -> String {
    let path = module_path!();
    format!(
        "{}::{name}",
        path.split_once("::").map_or(path, |(_, module)| module)
    )
}

#[test]
fn missing_driver_reports_packages_and_backends() {
    let exe = std::env::current_exe().unwrap();
    let out = Command::new(exe)
        .args([
            "--exact",
            &own_test("child_opens_renderer"),
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD_ENV, "1")
        // Old and new names of the Vulkan loader's driver list, and glvnd's EGL vendor list.
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/egl.json")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "child failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("NO_ADAPTER_MESSAGE:"),
        "child did not run:\n{stdout}"
    );
    assert!(stdout.contains("mesa-vulkan-drivers"), "{stdout}");
    assert!(stdout.contains("libvulkan1"), "{stdout}");
    assert!(stdout.contains("Vulkan, then GL"), "{stdout}");
}

#[test]
fn child_opens_renderer() {
    if std::env::var(CHILD_ENV).is_err() {
        return;
    }
    let options = GpuOptions {
        backends: vec![Backend::Vulkan, Backend::Gl],
    };
    match Renderer::headless_with(64, 64, 1, &options) {
        Err(e @ RenderError::NoAdapter { .. }) => println!("NO_ADAPTER_MESSAGE: {e}"),
        Err(e) => panic!("expected NoAdapter, got {e}"),
        Ok(r) => panic!(
            "expected NoAdapter, got a renderer on {}",
            r.adapter_description()
        ),
    }
}
