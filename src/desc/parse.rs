//! Parsing the text forms of a frame's options (`--clip A,B,C,D`,
//! `--crop X0:X1,Y0:Y1,Z0:Z1`, ...), shared by the CLI and bench configs.

use crate::error::{Error, Result};

/// Exactly `n` finite numbers separated by any of `seps`; `usage` names the
/// expected form in the error.
pub(crate) fn numbers(what: &'static str, s: &str, n: usize, seps: &[char], usage: &str) -> Result<Vec<f32>> {
    let bad = || Error::invalid(what, s, format!("expected {usage}"));
    let values: Vec<f32> = s
        .split(|c| seps.contains(&c))
        .map(|v| v.trim().parse::<f32>().map_err(|_| bad()))
        .collect::<Result<_>>()?;
    if values.len() != n {
        return Err(bad());
    }
    if values.iter().any(|v| !v.is_finite()) {
        return Err(Error::invalid(what, s, format!("expected {usage} (finite numbers)")));
    }
    Ok(values)
}
