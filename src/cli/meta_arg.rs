//! `--meta KEY=VALUE`, as `palpus import` and the recognizers' log readers take it.

/// One `KEY=VALUE` pair.
pub(crate) fn parse_meta(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((key, value)) if !key.is_empty() => Ok((key.to_owned(), value.to_owned())),
        _ => Err(format!("`{s}`: expected KEY=VALUE")),
    }
}
