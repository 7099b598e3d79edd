//! The paper's tables from benchmark records: Table 1 (nodes and height per
//! structure), Table 2 (build seconds, fps and speed-up over naive), frame
//! times with their spread, and the speed-against-error table, as Markdown
//! and CSV. A record measured on a noisy machine carries a dagger.

use super::record::{ErrorPoint, Record};

pub(crate) fn datasets(records: &[Record]) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for r in records {
        if !v.contains(&r.dataset) {
            v.push(r.dataset.clone());
        }
    }
    v
}

fn structures(records: &[Record]) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for r in records {
        if !v.contains(&r.structure) {
            v.push(r.structure.clone());
        }
    }
    v
}

fn cell(records: &[Record], d: &str, s: &str, f: impl Fn(&Record) -> String) -> String {
    records
        .iter()
        .find(|r| r.dataset == d && r.structure == s)
        .map_or("-".into(), f)
}

fn markdown(title: &str, records: &[Record], f: impl Fn(&Record) -> String) -> String {
    let (ds, ss) = (datasets(records), structures(records));
    let mut out = format!(
        "{title}\n\n| data set | {} |\n|---|{}\n",
        ss.join(" | "),
        "---|".repeat(ss.len())
    );
    for d in &ds {
        let cells: Vec<String> = ss.iter().map(|s| cell(records, d, s, &f)).collect();
        out += &format!("| {d} | {} |\n", cells.join(" | "));
    }
    out
}

fn csv_escape(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Table 1: nodes / height.
pub fn table1_md(records: &[Record]) -> String {
    markdown("Table 1: nodes / height per structure", records, |r| {
        if r.accel == "naive" {
            "-".into()
        } else {
            format!("{} / {}", r.nodes, r.tree_height)
        }
    })
}

/// Marks a record whose times spread more than the noise bound.
fn dagger(r: &Record) -> &'static str {
    if r.unstable {
        " †"
    } else {
        ""
    }
}

/// The dagger's legend, under a table where a record has one.
fn unstable_note(records: &[Record]) -> String {
    match records.iter().any(|r| r.unstable) {
        true => format!("\n{UNSTABLE_NOTE}\n"),
        false => String::new(),
    }
}

/// Seconds to three significant digits (a grid's build is 0.0000123 s).
fn seconds(s: f64) -> String {
    match s {
        s if s >= 1.0 || s == 0.0 => format!("{s:.3}"),
        s => {
            let decimals = (2 - s.log10().floor() as i32).max(3) as usize;
            format!("{s:.decimals$}")
        }
    }
}

const UNSTABLE_NOTE: &str =
    "† unstable: a view's frame times (or the builds) spread more than 1.5x over the rounds; re-run on a quieter machine.";

/// Table 2: build seconds (per TF change) / fps (xspeed-up over naive).
pub fn table2_md(records: &[Record]) -> String {
    markdown(
        "Table 2: build s (per TF change) / fps (median frame) (speed-up over naive, same run)",
        records,
        |r| {
            let build = if r.accel == "naive" {
                "-".to_string()
            } else {
                seconds(r.build_ms / 1000.0)
            };
            format!("{build} / {:.2} ({:.2}x){}", r.fps, r.speedup, dagger(r))
        },
    ) + &unstable_note(records)
}

/// Frame times: median [min, max] ms over every view and round, and the
/// speed-up over naive.
pub fn frames_md(records: &[Record]) -> String {
    let rounds = records.first().map_or(0, |r| r.setup.rounds);
    markdown(
        &format!("Frame ms: median [min, max] over every view x {rounds} interleaved rounds; speed-up over naive"),
        records,
        |r| {
            format!(
                "{:.2} [{:.2}, {:.2}] {:.2}x{}",
                r.frame.median_ms,
                r.frame.min_ms,
                r.frame.max_ms,
                r.speedup,
                dagger(r)
            )
        },
    ) + &unstable_note(records)
}

/// The fastest exact structure per data set (by median frame; a structure
/// whose image differs from naive's, as the paper's classification can,
/// does not count), with its speed-up.
pub fn fastest(records: &[Record]) -> Vec<&Record> {
    datasets(records)
        .iter()
        .filter_map(|d| fastest_of(records, d, |r| -r.frame.median_ms))
        .collect()
}

/// The exact record of data set `d` with the largest `speed` (an image that
/// differs from naive's is never the fastest).
pub fn fastest_of<'a>(records: &'a [Record], d: &str, speed: impl Fn(&Record) -> f64) -> Option<&'a Record> {
    records
        .iter()
        .filter(|r| r.dataset == d && r.error_vs_naive.differing == 0)
        .max_by(|a, b| speed(a).total_cmp(&speed(b)))
}

/// Error of every structure against naive marching.
pub fn exactness_md(records: &[Record]) -> String {
    markdown(
        "Image error against naive marching (max_abs; 0 = bit-identical)",
        records,
        |r| {
            if r.error_vs_naive.differing == 0 {
                "0".into()
            } else {
                format!("{:.3e} ({} px)", r.error_vs_naive.max_abs, r.error_vs_naive.differing)
            }
        },
    )
}

/// One CSV row per record.
pub fn records_csv(records: &[Record]) -> String {
    let mut out = String::from(
        "dataset,structure,accel,params,device,width,height,frames,rounds,step,ert,tf,visible_percent,active_brick_percent,ranges_ms,build_ms,build_min_ms,build_max_ms,nodes,leaves,tree_height,bytes,frame_median_ms,frame_min_ms,frame_max_ms,fps,speedup,frame_spread,build_spread,unstable,warmup_builds,warmup_frames,warmup_capped,error_max_abs,error_rmse,error_differing,driver,camera,filter,chosen\n",
    );
    for r in records {
        let params: Vec<String> = r.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let fields = [
            csv_escape(&r.dataset),
            csv_escape(&r.structure),
            r.accel.clone(),
            csv_escape(&params.join("; ")),
            csv_escape(&r.setup.device),
            r.setup.width.to_string(),
            r.setup.height.to_string(),
            r.setup.frames.to_string(),
            r.setup.rounds.to_string(),
            r.setup.step.to_string(),
            r.setup.timed_ert.map_or("off".into(), |e| e.to_string()),
            csv_escape(&r.tf),
            format!("{:.4}", r.visible_percent),
            format!("{:.4}", r.active_brick_percent),
            format!("{:.4}", r.ranges_ms),
            format!("{:.4}", r.build_ms),
            format!("{:.4}", r.build_min_ms),
            format!("{:.4}", r.build_max_ms),
            r.nodes.to_string(),
            r.leaves.to_string(),
            r.tree_height.to_string(),
            r.bytes.to_string(),
            format!("{:.4}", r.frame.median_ms),
            format!("{:.4}", r.frame.min_ms),
            format!("{:.4}", r.frame.max_ms),
            format!("{:.4}", r.fps),
            format!("{:.4}", r.speedup),
            format!("{:.4}", r.frame_spread),
            format!("{:.4}", r.build_spread),
            r.unstable.to_string(),
            r.warmed_up.builds.to_string(),
            r.warmed_up.frames.to_string(),
            r.warmed_up.capped.to_string(),
            format!("{:e}", r.error_vs_naive.max_abs),
            format!("{:e}", r.error_vs_naive.rmse),
            r.error_vs_naive.differing.to_string(),
            csv_escape(&r.setup.driver),
            csv_escape(&r.setup.camera),
            r.filter.clone(),
            csv_escape(r.chosen.as_deref().unwrap_or("")),
        ];
        out += &fields.join(",");
        out.push('\n');
    }
    out
}

/// The speed-against-error sweep as a Markdown table.
pub fn errors_md(points: &[ErrorPoint]) -> String {
    let mut out = String::from(
        "Speed against error: time per frame and error against a fine reference (naive, step = reference, no early termination, manual filter, no jitter)\n\n| data set | filter | jitter | step | ERT | ms (median) | rmse | psnr dB | max_abs |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for p in points {
        out += &format!(
            "| {} | {} | {} | {} | {} | {:.2} | {:.3e} | {} | {:.3e} |\n",
            p.dataset,
            p.filter,
            if p.jitter { "on" } else { "off" },
            p.sweep_step,
            p.ert.map_or("off".into(), |e| e.to_string()),
            p.frame.median_ms,
            p.error.rmse,
            p.error.psnr_text(2),
            p.error.max_abs
        );
    }
    out
}

/// The speed-against-error sweep as CSV.
pub fn errors_csv(points: &[ErrorPoint]) -> String {
    let mut out = String::from(
        "dataset,accel,filter,jitter,step,ert,frame_median_ms,frame_min_ms,frame_max_ms,reference_step,rmse,psnr,max_abs\n",
    );
    for p in points {
        out += &format!(
            "{},{},{},{},{},{},{:.4},{:.4},{:.4},{},{:e},{},{:e}\n",
            csv_escape(&p.dataset),
            p.accel,
            p.filter,
            p.jitter,
            p.sweep_step,
            p.ert.map_or("off".into(), |e| e.to_string()),
            p.frame.median_ms,
            p.frame.min_ms,
            p.frame.max_ms,
            p.reference_step,
            p.error.rmse,
            p.error.psnr_text(3),
            p.error.max_abs
        );
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn build_seconds_keep_three_significant_digits() {
        let cases = [
            (0.0000123, "0.0000123"),
            (0.0039, "0.00390"),
            (0.5, "0.500"),
            (12.345, "12.345"),
            (0.0, "0.000"),
        ];
        for (s, text) in cases {
            assert_eq!(super::seconds(s), text, "{s}");
        }
    }
}
