//! The paper's tables from benchmark records: Table 1 (nodes and height per
//! structure), Table 2 (build seconds and fps), and the speed-against-error
//! table, as Markdown and CSV.

use super::record::{ErrorPoint, Record};

fn datasets(records: &[Record]) -> Vec<String> {
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

/// Table 2: build seconds (per TF change) / fps.
pub fn table2_md(records: &[Record]) -> String {
    markdown("Table 2: build s (per TF change) / fps (median frame)", records, |r| {
        if r.accel == "naive" {
            format!("- / {:.2}", r.fps)
        } else {
            format!("{:.4} / {:.2}", r.build_ms / 1000.0, r.fps)
        }
    })
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
        "dataset,structure,accel,params,device,width,height,frames,step,tf,visible_percent,active_brick_percent,ranges_ms,build_ms,nodes,leaves,tree_height,bytes,frame_median_ms,frame_min_ms,frame_max_ms,fps,error_max_abs,error_rmse,error_differing\n",
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
            r.setup.step.to_string(),
            csv_escape(&r.tf),
            format!("{:.4}", r.visible_percent),
            format!("{:.4}", r.active_brick_percent),
            format!("{:.4}", r.ranges_ms),
            format!("{:.4}", r.build_ms),
            r.nodes.to_string(),
            r.leaves.to_string(),
            r.tree_height.to_string(),
            r.bytes.to_string(),
            format!("{:.4}", r.frame.median_ms),
            format!("{:.4}", r.frame.min_ms),
            format!("{:.4}", r.frame.max_ms),
            format!("{:.4}", r.fps),
            format!("{:e}", r.error_vs_naive.max_abs),
            format!("{:e}", r.error_vs_naive.rmse),
            r.error_vs_naive.differing.to_string(),
        ];
        out += &fields.join(",");
        out.push('\n');
    }
    out
}

pub fn errors_md(points: &[ErrorPoint]) -> String {
    let mut out = String::from(
        "Speed against error: time per frame and error against a fine reference (naive, step = reference, no early termination)\n\n| data set | step | ERT | ms (median) | rmse | psnr dB | max_abs |\n|---|---|---|---|---|---|---|\n",
    );
    for p in points {
        out += &format!(
            "| {} | {} | {} | {:.2} | {:.3e} | {} | {:.3e} |\n",
            p.dataset,
            p.sweep_step,
            p.ert.map_or("off".into(), |e| e.to_string()),
            p.frame.median_ms,
            p.error.rmse,
            p.error.psnr.map_or("inf".into(), |v| format!("{v:.2}")),
            p.error.max_abs
        );
    }
    out
}

pub fn errors_csv(points: &[ErrorPoint]) -> String {
    let mut out = String::from(
        "dataset,accel,step,ert,frame_median_ms,frame_min_ms,frame_max_ms,reference_step,rmse,psnr,max_abs\n",
    );
    for p in points {
        out += &format!(
            "{},{},{},{},{:.4},{:.4},{:.4},{},{:e},{},{:e}\n",
            csv_escape(&p.dataset),
            p.accel,
            p.sweep_step,
            p.ert.map_or("off".into(), |e| e.to_string()),
            p.frame.median_ms,
            p.frame.min_ms,
            p.frame.max_ms,
            p.reference_step,
            p.error.rmse,
            p.error.psnr.map_or("inf".into(), |v| format!("{v:.3}")),
            p.error.max_abs
        );
    }
    out
}
