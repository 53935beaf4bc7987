//! The project's self-describing JSON files (identified models, surface recognizers): written
//! atomically, read strictly, and every failure naming the file and the line or field.

use std::io;
use std::path::Path;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::{CaptureError, CaptureErrorKind, write_atomically};

/// Writes `value` as pretty JSON to `path` atomically: a failure leaves any earlier file whole.
pub fn save_pretty<T: Serialize>(path: &Path, value: &T) -> Result<(), CaptureError> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(io::Error::other)
    })
    .map_err(|source| CaptureError::new(path, CaptureErrorKind::Io(source)))
}

/// Reads `path` and parses it with [`parse`].
pub fn load<T: DeserializeOwned>(
    path: &Path,
    validate: impl FnOnce(&T) -> Result<(), (String, String)>,
) -> Result<T, CaptureError> {
    let bytes =
        std::fs::read(path).map_err(|source| CaptureError::new(path, CaptureErrorKind::Io(source)))?;
    parse(&bytes, path, validate)
}

/// Parses `bytes` (named `path` in errors) and checks the value with `validate`, which names
/// the offending field and the reason.
pub fn parse<T: DeserializeOwned>(
    bytes: &[u8],
    path: &Path,
    validate: impl FnOnce(&T) -> Result<(), (String, String)>,
) -> Result<T, CaptureError> {
    let value: T = serde_json::from_slice(bytes)
        .map_err(|e| CaptureError::new(path, CaptureErrorKind::Json(e.to_string())).at_line(e.line()))?;
    validate(&value)
        .map_err(|(field, reason)| CaptureError::new(path, CaptureErrorKind::Invalid { field, reason }))?;
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Doc {
        version: u32,
    }

    fn version_one(d: &Doc) -> Result<(), (String, String)> {
        if d.version == 1 {
            Ok(())
        } else {
            Err(("version".into(), format!("{} is not 1", d.version)))
        }
    }

    #[test]
    fn round_trip_and_each_failure_names_file_and_place() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("doc.json");
        save_pretty(&path, &Doc { version: 1 }).expect("save");
        assert_eq!(load(&path, version_one).expect("load"), Doc { version: 1 });

        let e = parse::<Doc>(b"{\n\"version\": x}", &path, version_one).unwrap_err();
        assert!(
            matches!(e.kind, CaptureErrorKind::Json(_)) && e.line == Some(2),
            "{e}"
        );
        assert!(
            e.to_string().starts_with(&format!("{}:2: ", path.display())),
            "{e}"
        );

        let e = parse::<Doc>(b"{\"version\": 2}", &path, version_one).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("{}: field `version`: 2 is not 1", path.display())
        );

        let e = load::<Doc>(&dir.path().join("missing.json"), version_one).unwrap_err();
        assert!(matches!(e.kind, CaptureErrorKind::Io(_)), "{e}");
    }
}
