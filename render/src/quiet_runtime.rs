//! Headless runs without a desktop session kept free of a spurious Wayland error.

/// Where `XDG_RUNTIME_DIR` is unset (or not an absolute path), it names an empty directory of this process's own for the
/// process's life.
///
/// wgpu enables every window-system instance extension the Vulkan loader offers, even for a
/// headless instance, and has no way to leave them out. Seeing `VK_KHR_wayland_surface`
/// enabled, Mesa's device-select layer (an implicit layer of mesa-vulkan-drivers) asks the
/// Wayland compositor which GPU it runs on at every device enumeration, and libwayland-client
/// prints "error: XDG_RUNTIME_DIR is invalid or not set in the environment." when the variable
/// is unset — on every headless render on a machine without a session (CI, ssh, containers),
/// though nothing is wrong. With the variable naming an empty directory the connection attempt
/// finds no socket and fails silently; the device is chosen as before, and a window falls back
/// to X11 exactly as it does without the variable (a Wayland socket lives in that directory).
/// The directory is private (0700), so no one else can put a socket there, and removed at exit
/// (or, after a kill, by the next start).
#[derive(Debug)]
pub struct QuietRuntimeDir {
    dir: std::path::PathBuf,
}

impl QuietRuntimeDir {
    /// Sets the variable when needed; dropping the value removes the directory.
    ///
    /// # Safety
    /// It writes the process environment: call it first thing in `main`, before any other
    /// thread exists, since another thread reading the environment meanwhile is undefined
    /// behaviour.
    #[cfg(unix)]
    pub unsafe fn install() -> Option<Self> {
        use std::os::unix::fs::DirBuilderExt;

        const VAR: &str = "XDG_RUNTIME_DIR";
        // libwayland takes only an absolute path; anything else it reports as invalid.
        if std::env::var_os(VAR).is_some_and(|v| std::path::Path::new(&v).is_absolute()) {
            return None;
        }
        let base = std::env::temp_dir();
        // `mkdir` fails on any existing entry, symlinks included, so a name someone else got to
        // first is never used.
        let dir = (0..8).find_map(|n| {
            let dir = base.join(format!("{RUNTIME_DIR_PREFIX}{}-{n}", std::process::id()));
            std::fs::DirBuilder::new()
                .mode(0o700)
                .create(&dir)
                .ok()
                .map(|()| dir)
        })?;
        // SAFETY: the caller promises no other thread exists, so nothing can read the
        // environment while it is written.
        unsafe { std::env::set_var(VAR, &dir) };
        remove_stale(&base);
        Some(Self { dir })
    }

    /// See the Unix version: elsewhere there is no Wayland to quieten.
    ///
    /// # Safety
    /// None needed; `unsafe` only to match the Unix version.
    #[cfg(not(unix))]
    pub unsafe fn install() -> Option<Self> {
        None
    }
}

/// Each directory is this, the process id, `-` and a number.
#[cfg(unix)]
const RUNTIME_DIR_PREFIX: &str = "palpus-runtime-";

/// A process ended by a signal (Ctrl-C, a kill) never reaches [`Drop`], so its directory stays:
/// each start removes those of processes that no longer exist. Only empty directories go, and
/// the temporary folder's sticky bit keeps other users' out of reach. Where `/proc` is missing a
/// live process cannot be told from a dead one, and nothing is removed.
#[cfg(unix)]
fn remove_stale(base: &std::path::Path) {
    let proc = std::path::Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(base) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(RUNTIME_DIR_PREFIX))
            .and_then(|rest| rest.split_once('-'))
            .and_then(|(pid, _)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !proc.join(pid.to_string()).exists() {
            let _ = std::fs::remove_dir(entry.path());
        }
    }
}

impl Drop for QuietRuntimeDir {
    fn drop(&mut self) {
        // Only failed connection attempts looked inside, so it is still empty.
        let _ = std::fs::remove_dir(&self.dir);
    }
}
