//! A printf pattern of files (`run_%04d_128x128x128_float32.raw`): the
//! files of a time series, one step each, in number order.

#[cfg(feature = "loaders")]
use super::spec::is_nifti;
use super::spec::is_nrrd;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// A printf pattern: the text before and after one `%d` or `%0Nd`.
pub(super) struct Pattern {
    dir: PathBuf,
    prefix: String,
    width: usize,
    suffix: String,
    spec: String,
}

impl Pattern {
    /// The pattern in `spec`, None when it has no `%d` / `%0Nd`.
    pub(super) fn parse(spec: &str) -> Option<Pattern> {
        let path = Path::new(spec);
        let name = path.file_name()?.to_str()?;
        let at = name.find('%')?;
        let rest = &name[at + 1..];
        let digits = rest.chars().take_while(char::is_ascii_digit).count();
        if !rest[digits..].starts_with('d') {
            return None;
        }
        let width = match &rest[..digits] {
            "" => 0,
            w if w.starts_with('0') => w.parse().ok()?,
            _ => return None,
        };
        Some(Pattern {
            dir: path
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .unwrap_or(Path::new("."))
                .to_path_buf(),
            prefix: name[..at].to_string(),
            width,
            suffix: rest[digits + 1..].to_string(),
            spec: spec.to_string(),
        })
    }

    /// The number a file name carries, None when it does not match.
    fn number(&self, name: &str) -> Option<u64> {
        let digits = name.strip_prefix(&self.prefix)?.strip_suffix(&self.suffix)?;
        let printed = !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit());
        let n: u64 = digits.parse().ok().filter(|_| printed)?;
        // Exactly what printf writes for n: at least `width` digits.
        (format!("{n:0width$}", width = self.width) == digits).then_some(n)
    }

    /// The matching files in step order; an error when none match or the
    /// numbers have a gap.
    pub(super) fn files(&self) -> Result<Vec<PathBuf>> {
        let entries = std::fs::read_dir(&self.dir).map_err(|e| Error::io(&self.dir, e))?;
        let mut found: Vec<(u64, PathBuf)> = entries
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                Some((self.number(&name)?, e.path()))
            })
            .collect();
        found.sort();
        let Some(&(first, _)) = found.first() else {
            return Err(Error::invalid(
                "volume",
                self.spec.clone(),
                format!("the pattern matches no file in {}", self.dir.display()),
            ));
        };
        if let Some(missing) = found.iter().enumerate().find(|(i, (n, _))| *n != first + *i as u64) {
            let want = first + missing.0 as u64;
            return Err(Error::invalid(
                "volume",
                self.spec.clone(),
                format!(
                    "the steps have a gap: {}{want:0width$}{} is missing between {first} and {}",
                    self.prefix,
                    self.suffix,
                    found[found.len() - 1].0,
                    width = self.width
                ),
            ));
        }
        Ok(found.into_iter().map(|(_, p)| p).collect())
    }
}

/// `path`, a pattern's file, where it holds one time step: a NIfTI or
/// NRRD with a time axis would give its step 0 alone, its other steps
/// unseen. Its header only is read.
pub(super) fn one_step(path: &Path) -> Result<&Path> {
    let steps = match path {
        p if is_nrrd(p) => super::nrrd::steps(p)?,
        #[cfg(feature = "loaders")]
        p if is_nifti(p) => super::nifti::steps(p)?,
        _ => 1,
    };
    match steps {
        1 => Ok(path),
        n => Err(Error::invalid(
            "time step",
            path.display().to_string(),
            format!("holds {n} time steps: the files of a printf pattern hold one step each (give a file with a time axis alone)"),
        )),
    }
}
