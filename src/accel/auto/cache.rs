//! Where auto's kernel constants are kept: in memory per context, and, when
//! a cache folder is set (`Builder::use_cost_cache`; the command line sets
//! `$XDG_CACHE_HOME/lacuna`, else `~/.cache/lacuna`), in one text file per
//! device, driver and build of the march kernels, so a choice does not move
//! with a cold shader cache or a noisy minute: constants are measured once
//! and read back after. The file's name carries a hash of the device name,
//! driver, driver version, pipeline cache UUID and every march kernel's
//! SPIR-V, so a new driver or a changed kernel starts a new file; its first
//! line carries the format version. Writes go to a temporary name, then a
//! rename.

use super::model::{CostKey, KernelCost};
use crate::error::{Error, Result};
use crate::gpu::{shaders, DeviceInfo};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The first line of a cache file.
const HEADER: &str = "lacuna kernel cost model 1";

/// Where a key's constants came from.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Source {
    /// Measured in this run.
    Measured,
    /// Read from the cache file.
    Cached(PathBuf),
    /// Given by the caller (`Builder::set_kernel_costs`).
    Given,
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Source::Measured => f.write_str("measured now"),
            Source::Cached(p) => write!(f, "cached in {}", p.display()),
            Source::Given => f.write_str("given"),
        }
    }
}

/// The constants known so far on one context.
#[derive(Default)]
pub struct CostTable {
    inner: Mutex<Table>,
}

#[derive(Default)]
struct Table {
    known: HashMap<String, (KernelCost, Source)>,
    /// Constants for every key (tests, hosts that measured their own).
    given: Option<KernelCost>,
    folder: Option<PathBuf>,
    /// Measure again, whatever the file holds.
    recalibrate: bool,
}

impl CostTable {
    /// The constants of `key` if known (given, in memory, or in the cache
    /// file), and where they came from.
    pub fn get(&self, info: &DeviceInfo, key: &CostKey) -> Option<(KernelCost, Source)> {
        let mut t = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(c) = t.given {
            return Some((c, Source::Given));
        }
        let text = key.text();
        if let Some(k) = t.known.get(&text) {
            return Some(k.clone());
        }
        if t.recalibrate {
            return None;
        }
        let path = t.folder.as_ref().map(|f| file_for(f, info))?;
        let found = read(&path).ok()?.remove(&text)?;
        let entry = (found, Source::Cached(path));
        t.known.insert(text, entry.clone());
        Some(entry)
    }

    /// Keeps `cost` for `key` (measured now), in memory and in the cache
    /// file when there is one; a file that cannot be written is no error
    /// (the constants stay in memory), it is returned as a note.
    pub fn put(&self, info: &DeviceInfo, key: &CostKey, cost: KernelCost) -> Option<String> {
        let mut t = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        t.known.insert(key.text(), (cost, Source::Measured));
        let path = t.folder.as_ref().map(|f| file_for(f, info))?;
        let mut all = read(&path).unwrap_or_default();
        all.insert(key.text(), cost);
        write(&path, info, &all)
            .err()
            .map(|e| format!("the cost model is not cached: {e}"))
    }

    pub fn set_folder(&self, folder: Option<PathBuf>) {
        self.inner.lock().unwrap_or_else(|p| p.into_inner()).folder = folder;
    }

    pub fn set_recalibrate(&self, on: bool) {
        let mut t = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        t.recalibrate = on;
        if on {
            t.known.clear();
        }
    }

    pub fn set_given(&self, cost: Option<KernelCost>) {
        self.inner.lock().unwrap_or_else(|p| p.into_inner()).given = cost;
    }

    /// The cache file of this device, when a folder is set.
    pub fn file(&self, info: &DeviceInfo) -> Option<PathBuf> {
        let t = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        t.folder.as_ref().map(|f| file_for(f, info))
    }
}

/// The default cache folder: `$XDG_CACHE_HOME/lacuna`, else
/// `$HOME/.cache/lacuna`; None without either.
pub fn default_folder() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME")
                .filter(|v| !v.is_empty())
                .map(|h| PathBuf::from(h).join(".cache"))
        })?;
    Some(base.join("lacuna"))
}

/// FNV-1a, 64 bits: stable across runs and platforms (a file name).
fn fnv(bytes: impl IntoIterator<Item = u8>, mut h: u64) -> u64 {
    for b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

fn file_for(folder: &Path, info: &DeviceInfo) -> PathBuf {
    let mut h = 0xcbf2_9ce4_8422_2325;
    h = fnv(info.name.bytes(), h);
    h = fnv(info.driver.bytes(), h);
    h = fnv(info.driver_version.to_le_bytes(), h);
    h = fnv(info.pipeline_cache_uuid, h);
    for s in shaders::ALL.iter().filter(|s| s.name.starts_with("march/")) {
        h = fnv(s.name.bytes(), h);
        h = fnv(s.words.iter().flat_map(|w| w.to_le_bytes()), h);
    }
    folder.join(format!("cost-model-{h:016x}.txt"))
}

/// A cache file's most bytes: a few hundred lines of kernel costs are far
/// less; a longer file is not lacuna's, and is measured anew.
const MAX_CACHE_BYTES: u64 = 1 << 20;

fn read(path: &Path) -> Result<HashMap<String, KernelCost>> {
    let text = crate::limits::read_input_text(path, "cost model cache", MAX_CACHE_BYTES)?;
    let mut lines = text.lines();
    if lines.next() != Some(HEADER) {
        return Err(Error::invalid(
            "cost model cache",
            path.display().to_string(),
            "has another format",
        ));
    }
    let mut out = HashMap::new();
    for line in lines.filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
        let mut parts = line.split_whitespace();
        let (Some(key), Ok(values)) = (
            parts.next(),
            parts
                .map(str::parse::<f64>)
                .collect::<std::result::Result<Vec<f64>, _>>(),
        ) else {
            continue;
        };
        if let Ok(c) = <[f64; 4]>::try_from(values) {
            let cost = KernelCost::from_array(c);
            if cost.is_valid() {
                out.insert(key.to_string(), cost);
            }
        }
    }
    Ok(out)
}

fn write(path: &Path, info: &DeviceInfo, all: &HashMap<String, KernelCost>) -> Result<()> {
    let mut keys: Vec<&String> = all.keys().collect();
    keys.sort();
    let mut text = format!(
        "{HEADER}\n# {} ({}); ns per ray, sample, step, region (src/accel/auto/model.rs)\n",
        info.name, info.driver
    );
    for k in keys {
        let c = all[k].as_array();
        text.push_str(&format!("{k} {} {} {} {}\n", c[0], c[1], c[2], c[3]));
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}
