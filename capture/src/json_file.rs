//! The project's self-describing JSON files (identified models, surface recognizers): written
//! atomically, read strictly, and every failure naming the file and the line or field.

use std::io;
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::write_atomically;

/// Why a JSON file could not be written, read or used.
#[derive(Debug, thiserror::Error)]
pub enum JsonFileError {
    /// Reading or writing failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: io::Error,
    },
    /// Not valid JSON for this kind of file.
    #[error("{}:{line}: {reason}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line of the error.
        line: usize,
        /// What serde said.
        reason: String,
    },
    /// Parsed, but inconsistent.
    #[error("{}: field `{field}`: {reason}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The field.
        field: String,
        /// Why.
        reason: String,
    },
}

/// Writes `value` as pretty JSON to `path` atomically: a failure leaves any earlier file whole.
pub fn save_pretty<T: Serialize>(path: &Path, value: &T) -> Result<(), JsonFileError> {
    write_atomically(path, |w| {
        serde_json::to_writer_pretty(&mut *w, value).map_err(io::Error::other)
    })
    .map_err(|source| JsonFileError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Reads `path` and parses it with [`parse`].
pub fn load<T: DeserializeOwned>(
    path: &Path,
    validate: impl FnOnce(&T) -> Result<(), (String, String)>,
) -> Result<T, JsonFileError> {
    let bytes = std::fs::read(path).map_err(|source| JsonFileError::Io {
        path: path.to_owned(),
        source,
    })?;
    parse(&bytes, path, validate)
}

/// Parses `bytes` (named `path` in errors) and checks the value with `validate`, which names
/// the offending field and the reason.
pub fn parse<T: DeserializeOwned>(
    bytes: &[u8],
    path: &Path,
    validate: impl FnOnce(&T) -> Result<(), (String, String)>,
) -> Result<T, JsonFileError> {
    let value: T = serde_json::from_slice(bytes).map_err(|e| JsonFileError::Parse {
        path: path.to_owned(),
        line: e.line(),
        reason: e.to_string(),
    })?;
    validate(&value).map_err(|(field, reason)| JsonFileError::Invalid {
        path: path.to_owned(),
        field,
        reason,
    })?;
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
        assert!(matches!(e, JsonFileError::Parse { line: 2, .. }), "{e}");
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
        assert!(matches!(e, JsonFileError::Io { .. }), "{e}");
    }
}
