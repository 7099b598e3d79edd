//! `lacuna bench`: the paper's comparison (Zellmann et al., EGPGV 2020)
//! reproduced on lacuna's structures, speed against error, and the
//! hard-case suite. Results go to JSON (one record per run), Markdown and CSV
//! tables, and SVG/PNG plots.

pub mod compare;
pub mod config;
pub mod contract;
mod dataset;
pub mod files;
mod frame_timer;
pub mod hard;
mod plots;
pub mod preflight;
mod progress;
pub mod record;
pub mod run;
pub mod schedule;
pub mod series;
pub mod tables;

pub use config::BenchConfig;
pub use record::{ErrorPoint, Record};
pub use run::{BenchOutput, RunOptions};
pub use schedule::{schedule, warm_up, Slot, WarmedUp};

use crate::error::{Error, Result};
use crate::frame::{check_parent, write_atomically};
use std::path::Path;

/// Writes `text` to `path` whole or not at all (through a temporary file).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, text).map_err(|e| Error::io(path, e)))
}

/// Writes every output of a run, and the `extra` files (name, text), into
/// `dir` (created if needed). Returns the paths written. All or nothing:
/// they are written into a staging folder inside `dir` and moved into
/// place once every one is whole, so a full disk leaves the last run's
/// files as they were, not half of a new set.
pub fn write_outputs(dir: &Path, out: &BenchOutput, extra: &[(&str, String)]) -> Result<Vec<String>> {
    let created = !dir.exists();
    // Only a folder an earlier run wrote holds its outputs to remove: any
    // other (`--out .`) may hold the user's own notes.txt.
    let earlier_run = dir.join("results.json").is_file();
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let stage = dir.join(format!(".lacuna-bench-{}.tmp", std::process::id()));
    // Left by a killed run whose process id this one reuses.
    let _ = std::fs::remove_dir_all(&stage);
    let staged = std::fs::create_dir(&stage)
        .map_err(|e| Error::io(&stage, e))
        .and_then(|_| write_into(&stage, out, extra));
    let moved = staged.and_then(|names| {
        // Every place checked before the first move: a folder where a file
        // goes is found while nothing has moved.
        for name in &names {
            let to = dir.join(name);
            if let Some(folder) = to.parent() {
                std::fs::create_dir_all(folder).map_err(|e| Error::io(folder, e))?;
            }
            check_parent(&to)?;
        }
        names
            .iter()
            .map(|name| {
                let to = dir.join(name);
                std::fs::rename(stage.join(name), &to).map_err(|e| Error::io(&to, e))?;
                Ok(to.display().to_string())
            })
            .collect::<Result<Vec<_>>>()
    });
    let _ = std::fs::remove_dir_all(&stage);
    if moved.is_err() && created {
        let _ = std::fs::remove_dir_all(dir);
    }
    if let (Ok(paths), true) = (&moved, earlier_run) {
        remove_stale(dir, paths);
    }
    moved
}

/// Files a run writes only sometimes: an earlier run's would read as this
/// one's (a sweep, steps or frames this config has not).
const SOMETIMES: [&str; 9] = [
    "error.json",
    "error.csv",
    "error.md",
    "error.svg",
    "error.png",
    "steps.json",
    "steps.md",
    "notes.txt",
    "contract.md",
];

/// Removes the outputs of an earlier run in `dir` (a folder that held a
/// results.json) that this one (which wrote `written`) did not replace:
/// the files above and frames/*.exr. Anything else there is the user's
/// and stays.
fn remove_stale(dir: &Path, written: &[String]) {
    let ours = |p: &Path| written.iter().any(|w| Path::new(w) == p);
    for name in SOMETIMES {
        let path = dir.join(name);
        if !ours(&path) {
            let _ = std::fs::remove_file(&path);
        }
    }
    // Its own frames folder, not one a link leads to.
    let folder = dir.join("frames");
    if !std::fs::symlink_metadata(&folder).is_ok_and(|m| m.is_dir()) {
        return;
    }
    let Ok(frames) = std::fs::read_dir(&folder) else {
        return;
    };
    for entry in frames.flatten() {
        let path = entry.path();
        let exr = path.extension().is_some_and(|e| e == "exr");
        if exr && !ours(&path) && entry.file_type().is_ok_and(|t| t.is_file()) {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Writes the outputs into `dir`; returns their names relative to it.
fn write_into(dir: &Path, out: &BenchOutput, extra: &[(&str, String)]) -> Result<Vec<String>> {
    let json = |v: &dyn erased::Json| v.to_json();
    let mut written = Vec::new();
    let mut put = |name: &str, text: String| -> Result<()> {
        write_text(&dir.join(name), &text)?;
        written.push(name.to_string());
        Ok(())
    };
    for (name, text) in extra {
        put(name, text.clone())?;
    }
    put("results.json", json(&out.records))?;
    put("results.csv", tables::records_csv(&out.records))?;
    put("table1.md", tables::table1_md(&out.records))?;
    put("table2.md", tables::table2_md(&out.records))?;
    put("frames.md", tables::frames_md(&out.records))?;
    put("exactness.md", tables::exactness_md(&out.records))?;
    if !out.errors.is_empty() {
        put("error.json", json(&out.errors))?;
        put("error.csv", tables::errors_csv(&out.errors))?;
        put("error.md", tables::errors_md(&out.errors))?;
    }
    if !out.steps.is_empty() {
        put("steps.json", json(&out.steps))?;
        put("steps.md", out.steps_md())?;
    }
    if !out.notes.is_empty() {
        put("notes.txt", out.notes.join("\n") + "\n")?;
    }
    plots::figure3(&out.records, &dir.join("fig3-fps"))?;
    plots::figure4(&out.records, &dir.join("fig4-build-rate"))?;
    written.extend(
        [
            "fig3-fps.svg",
            "fig3-fps.png",
            "fig4-build-rate.svg",
            "fig4-build-rate.png",
        ]
        .map(String::from),
    );
    if !out.errors.is_empty() {
        plots::error_figure(&out.errors, &dir.join("error"))?;
        written.extend(["error.svg", "error.png"].map(String::from));
    }
    if !out.frames.is_empty() {
        let frames = dir.join("frames");
        std::fs::create_dir_all(&frames).map_err(|e| Error::io(&frames, e))?;
        for (file, frame) in &out.frames {
            frame.write_exr(&dir.join(file))?;
            written.push(file.clone());
        }
    }
    Ok(written)
}

mod erased {
    /// Pretty JSON of any record list.
    pub trait Json {
        fn to_json(&self) -> String;
    }

    impl<T: serde::Serialize> Json for Vec<T> {
        // Records are plain structs of numbers and strings, which always serialise.
        #[allow(clippy::expect_used)]
        fn to_json(&self) -> String {
            serde_json::to_string_pretty(self).expect("records serialise") + "\n"
        }
    }
}
