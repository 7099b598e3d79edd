//! `lacuna bench`: the paper's comparison (Zellmann et al., EGPGV 2020)
//! reproduced on lacuna's structures, speed against error, and the
//! hard-case suite. Results go to JSON (one record per run), Markdown and CSV
//! tables, and SVG/PNG plots.

pub mod compare;
pub mod config;
pub mod contract;
mod dataset;
mod frame_timer;
pub mod hard;
mod plots;
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
use crate::frame::write_atomically;
use std::path::Path;

pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, text).map_err(|e| Error::io(path, e)))
}

/// Writes every output of a run into `dir` (created if needed). Returns the
/// paths written.
pub fn write_outputs(dir: &Path, out: &BenchOutput) -> Result<Vec<String>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let json = |v: &dyn erased::Json| v.to_json();
    let mut written = Vec::new();
    let mut put = |name: &str, text: String| -> Result<()> {
        let p = dir.join(name);
        write_text(&p, &text)?;
        written.push(p.display().to_string());
        Ok(())
    };
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
        .map(|f| dir.join(f).display().to_string()),
    );
    if !out.errors.is_empty() {
        plots::error_figure(&out.errors, &dir.join("error"))?;
        written.extend(["error.svg", "error.png"].map(|f| dir.join(f).display().to_string()));
    }
    if !out.frames.is_empty() {
        let frames = dir.join("frames");
        std::fs::create_dir_all(&frames).map_err(|e| Error::io(&frames, e))?;
        for (name, frame) in &out.frames {
            let p = frames.join(run::slug(name)).with_extension("exr");
            frame.write_exr(&p)?;
            written.push(p.display().to_string());
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
