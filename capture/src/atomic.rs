//! All-or-nothing file writes: write to a temporary file beside the target,
//! then rename it over the target.

use std::ffi::OsString;
use std::fs::File;
use std::io::{self, BufWriter};
use std::path::Path;

/// Writes `path` atomically: `write` fills a temporary file in the same
/// directory (so the final rename stays on one filesystem), which is then
/// flushed, synced and renamed over `path`.
///
/// Readers therefore see either the old file or the complete new one, never
/// a half-written file. If `write` (or flushing, syncing, renaming) fails,
/// or panics, the temporary file is removed and `path` is untouched. The
/// temporary file is named `.<file name>.<random>.tmp`.
///
/// Any error type that can absorb an `io::Error` works, so plain
/// `io::Result` closures (e.g. writing a JSON manifest) need no wrapper.
/// On Unix the new file gets mode `0o666` minus the umask, like
/// `File::create`.
pub fn write_atomically<E: From<io::Error>>(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), E>,
) -> Result<(), E> {
    let file_name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("`{}` does not name a file", path.display()),
        )
    })?;
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    let mut prefix = OsString::from(".");
    prefix.push(file_name);
    prefix.push(".");

    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    // `temp_path` deletes the file when dropped, on every early return below.
    let (file, temp_path) = builder.tempfile_in(dir)?.into_parts();
    let mut out = BufWriter::new(file);
    write(&mut out)?;
    let file = out.into_inner().map_err(io::IntoInnerError::into_error)?;
    file.sync_all()?;
    drop(file);
    temp_path.persist(path).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::io::Write;

    /// The names in `dir`, sorted.
    pub(crate) fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn writes_and_replaces() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        write_atomically(&path, |w| w.write_all(b"one")).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"one");
        write_atomically(&path, |w| w.write_all(b"two")).unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        assert_eq!(entries(dir.path()), ["m.json"]);
    }

    #[test]
    fn failure_leaves_nothing_behind_and_keeps_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.json");
        let e = write_atomically(&path, |w| {
            w.write_all(&[b'x'; 100_000])?;
            Err(io::Error::other("generator failed"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "generator failed");
        assert!(entries(dir.path()).is_empty());

        std::fs::write(&path, b"old").unwrap();
        let e = write_atomically(&path, |w| {
            w.write_all(b"new")?;
            Err(io::Error::other("late failure"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "late failure");
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(dir.path()), ["m.json"]);
    }

    #[test]
    fn missing_directory_and_bad_targets_error_cleanly() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_atomically(&dir.path().join("nope/m.json"), |w| w.write_all(b"x")).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);

        // Renaming onto an existing directory fails at the last step.
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        std::fs::write(dir.path().join("sub/keep"), b"k").unwrap();
        write_atomically(&dir.path().join("sub"), |w| w.write_all(b"x")).unwrap_err();
        assert_eq!(entries(dir.path()), ["sub"]);
        assert_eq!(entries(&dir.path().join("sub")), ["keep"]);

        let e = write_atomically(Path::new("/"), |w| w.write_all(b"x")).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
    }
}
