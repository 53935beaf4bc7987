//! Several inputs: which input each `--map` entry reads, and their clock offsets.

use super::*;
use crate::InputColumns;

/// Splits the map among the inputs: for each input, the spec it is read with, its map holding
/// its time entry and the entries it provides, in map order and without input numbers.
///
/// An entry `N:name` goes to input `N`; an unqualified one, with several inputs, to the one
/// input whose columns (with the virtual `--unroll` column where a file has the packed ones)
/// include it. `time_s=N:column` is input `N`'s time, an unqualified `time_s` every other
/// input's. Errors: an input number beyond the inputs, a column in no input or in several
/// (naming them), an input without a time or without anything else to read.
pub(super) fn resolve(paths: &[&Path], spec: &ImportSpec) -> Result<Vec<ImportSpec>, CaptureError> {
    let n = paths.len();
    let entries = spec.map.entries();
    let files = || {
        let list: Vec<String> = paths
            .iter()
            .enumerate()
            .map(|(i, p)| format!("{}: {}", i + 1, p.display()))
            .collect();
        list.join(", ")
    };
    let bad_map = |entry: &MapEntry, reason: String| {
        let error = CaptureError::without_file(CaptureErrorKind::BadMap {
            entry: entry.text.clone(),
            reason,
        });
        CaptureError {
            file: (n == 1).then(|| paths[0].to_path_buf()),
            ..error
        }
    };
    if let Some(entry) = entries.iter().find(|e| e.input.is_some_and(|k| k > n)) {
        let k = entry.input.unwrap_or_default();
        return Err(bad_map(
            entry,
            format!("there is no input {k}: the inputs are {}", files()),
        ));
    }
    // Column names are only needed to place unqualified columns among several inputs.
    let place = n > 1 && entries.iter().any(|e| e.target != TIME_S && e.input.is_none());
    let available: Vec<Vec<String>> = if place {
        paths
            .iter()
            .map(|path| {
                let mut names = read_table(path, spec, true)?.header;
                if let Some(unroll) = &spec.unroll
                    && unroll.columns.iter().any(|c| names.contains(c))
                {
                    names.push(unroll.name.clone());
                }
                Ok(names)
            })
            .collect::<Result<_, CaptureError>>()?
    } else {
        Vec::new()
    };
    let mut owner: Vec<Option<usize>> = Vec::with_capacity(entries.len());
    for entry in entries {
        if entry.target == TIME_S {
            owner.push(None);
            continue;
        }
        let input = match entry.input {
            Some(k) => k - 1,
            None if n == 1 => 0,
            None => {
                let having: Vec<usize> = (0..n).filter(|&i| available[i].contains(&entry.source)).collect();
                match having.as_slice() {
                    [i] => *i,
                    [] => {
                        return Err(CaptureError::without_file(CaptureErrorKind::SourceInNoInput {
                            entry: entry.text.as_str().into(),
                            column: entry.source.as_str().into(),
                            inputs: paths
                                .iter()
                                .zip(&available)
                                .map(|(path, columns)| InputColumns {
                                    file: path.to_path_buf(),
                                    columns: columns.clone(),
                                })
                                .collect(),
                        }));
                    }
                    _ => {
                        return Err(CaptureError::without_file(
                            CaptureErrorKind::SourceInSeveralInputs {
                                entry: entry.text.as_str().into(),
                                column: entry.source.as_str().into(),
                                files: having.iter().map(|&i| (i + 1, paths[i].to_path_buf())).collect(),
                            },
                        ));
                    }
                }
            }
        };
        owner.push(Some(input));
    }
    let mut specs = Vec::with_capacity(n);
    for (i, path) in paths.iter().enumerate() {
        // Its own time column if it has one, else the one every input shares.
        let time = entries
            .iter()
            .position(|e| e.target == TIME_S && e.input == Some(i + 1))
            .or_else(|| {
                entries
                    .iter()
                    .position(|e| e.target == TIME_S && e.input.is_none())
            });
        let input_error = |reason: String| {
            CaptureError::new(
                *path,
                CaptureErrorKind::BadSpec(format!("input {}: {reason}", i + 1)),
            )
        };
        if n > 1 && time.is_none() {
            return Err(input_error(format!(
                "no time column; map `time_s=<column>` for every input or `time_s={}:<column>` \
                 for this one",
                i + 1
            )));
        }
        let mine: Vec<MapEntry> = entries
            .iter()
            .zip(&owner)
            .enumerate()
            .filter(|&(e, (_, owner))| *owner == Some(i) || Some(e) == time)
            .map(|(_, (entry, _))| MapEntry {
                input: None,
                ..entry.clone()
            })
            .collect();
        if n > 1 && mine.iter().all(|e| e.target == TIME_S) {
            return Err(input_error(format!(
                "no --map entry reads it but its time; map one of its columns (`target={}:column`) \
                 or leave the file out",
                i + 1
            )));
        }
        let text: Vec<&str> = mine.iter().map(|e| e.text.as_str()).collect();
        let mut file_spec = spec.clone();
        // With one input the map is the whole map; its `spec` stays as given.
        if n > 1 {
            file_spec.map = ColumnMap {
                spec: text.join(",").chars().filter(|c| !c.is_whitespace()).collect(),
                entries: mine,
            };
            let unrolled = spec
                .unroll
                .as_ref()
                .filter(|u| file_spec.map.entries.iter().any(|e| e.source == u.name));
            file_spec.unroll = unrolled.cloned();
        } else {
            file_spec.map.entries = mine;
        }
        specs.push(file_spec);
    }
    if n > 1
        && let Some(unroll) = &spec.unroll
        && specs.iter().all(|s| s.unroll.is_none())
    {
        return Err(CaptureError::without_file(CaptureErrorKind::BadSpec(format!(
            "--unroll `{}`: no --map entry reads `{}`",
            unroll.text(),
            unroll.name
        ))));
    }
    Ok(specs)
}

/// Each input's clock offset, s, from [`ImportSpec::clock_offsets_s`] (0 where none is
/// given); an input number beyond the inputs, a number given twice or an offset that is not
/// finite or beyond the time limit is an error.
pub(super) fn clock_offsets(paths: &[&Path], spec: &ImportSpec) -> Result<Vec<f64>, String> {
    let mut offsets: Vec<Option<f64>> = vec![None; paths.len()];
    let limit = magnitude_limit(TIME_S);
    for &(input, offset_s) in &spec.clock_offsets_s {
        let what = format!("--clock-offset-s {input}={offset_s}");
        let Some(slot) = input.checked_sub(1).and_then(|i| offsets.get_mut(i)) else {
            return Err(format!(
                "{what}: there is no input {input} (inputs are numbered 1 to {})",
                paths.len()
            ));
        };
        if slot.is_some() {
            return Err(format!("{what}: input {input} has an offset already"));
        }
        if !(offset_s.is_finite() && offset_s.abs() <= limit) {
            return Err(format!("{what}: must be finite and within ±{limit} s"));
        }
        *slot = Some(offset_s);
    }
    Ok(offsets.into_iter().map(|o| o.unwrap_or(0.0)).collect())
}

/// Metadata keys the import writes per input with several inputs (`source_2`,
/// `source_2_sha256`, ...); the caller's extra metadata may not use them.
pub(super) fn is_stream_key(key: &str) -> bool {
    key.strip_prefix("source_").is_some_and(|rest| {
        let number = rest.split('_').next().unwrap_or_default();
        !number.is_empty() && number.chars().all(|c| c.is_ascii_digit())
    })
}
