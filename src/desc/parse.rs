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

/// Parses `WxH` (both > 0).
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let bad = |why: &str| Error::invalid("size", s, why.to_string());
    let (w, h) = s.split_once('x').ok_or_else(|| bad("expected WxH"))?;
    let w: u32 = w.trim().parse().map_err(|_| bad("expected WxH with integers"))?;
    let h: u32 = h.trim().parse().map_err(|_| bad("expected WxH with integers"))?;
    if w == 0 || h == 0 {
        return Err(bad("width and height must be > 0"));
    }
    Ok((w, h))
}
