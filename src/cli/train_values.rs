//! Parsers of the training options' values that clap's own parsers do not cover.

#[derive(Debug, Clone, Copy)]
pub(super) enum CArg {
    Auto,
    Fixed(f64),
}

pub(super) fn parse_c(text: &str) -> Result<CArg, String> {
    if text == "auto" {
        return Ok(CArg::Auto);
    }
    match text.parse::<f64>() {
        Ok(c) if c.is_finite() && c > 0.0 => Ok(CArg::Fixed(c)),
        _ => Err(format!("`{text}` is neither `auto` nor a positive number")),
    }
}

/// `--nodes`: a positive count. The error names the old spelling too, since clap names the
/// option by its new one whichever was typed.
pub(super) fn parse_nodes(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "`{text}` is not a node count: a map needs at least one node (--som-nodes is the same option)"
        )),
    }
}
