//! auto's contract, checked on a bench run's records: on every data set,
//! auto at least [`NAIVE_FLOOR`] of naive marching's speed and within
//! [`FASTEST_SLACK`] of the fastest exact structure's. Speeds are the
//! records' speed-ups over naive (medians of per-round ratios, each pair
//! timed back to back), so the machine's drift over the run cancels.

use super::record::Record;
use super::tables::{datasets, fastest_of};

/// auto's speed-up over naive may not fall below this.
pub const NAIVE_FLOOR: f64 = 0.95;
/// auto's speed-up may fall below the fastest exact structure's by at most
/// this fraction.
pub const FASTEST_SLACK: f64 = 0.10;

/// One data set's verdict.
#[derive(Clone, Debug)]
pub struct Verdict {
    pub dataset: String,
    /// What auto chose, and its speed-up over naive.
    pub chosen: String,
    pub auto: f64,
    pub fastest: String,
    pub fastest_speedup: f64,
    pub passed: bool,
}

/// Every data set's verdict (data sets without an auto record are left out).
pub fn verdicts(records: &[Record]) -> Vec<Verdict> {
    datasets(records)
        .iter()
        .filter_map(|d| {
            let auto = records.iter().find(|r| &r.dataset == d && r.accel == "auto")?;
            let fastest = fastest_of(records, d, |r| r.speedup)?;
            let passed = auto.error_vs_naive.differing == 0
                && auto.speedup >= NAIVE_FLOOR
                && auto.speedup >= (1.0 - FASTEST_SLACK) * fastest.speedup;
            Some(Verdict {
                dataset: d.clone(),
                chosen: auto.chosen.clone().unwrap_or_else(|| "?".into()),
                auto: auto.speedup,
                fastest: fastest.structure.clone(),
                fastest_speedup: fastest.speedup,
                passed,
            })
        })
        .collect()
}

/// The verdicts as a Markdown table, and whether all passed.
pub fn markdown(verdicts: &[Verdict]) -> (String, bool) {
    let mut out = format!(
        "auto's contract: at least {NAIVE_FLOOR}x naive, within {:.0} % of the fastest exact structure (speed-ups over naive, same rounds)\n\n\
         | data set | auto chose | auto x naive | fastest exact | its x naive | auto / fastest | |\n|---|---|---|---|---|---|---|\n",
        100.0 * FASTEST_SLACK
    );
    for v in verdicts {
        out += &format!(
            "| {} | {} | {:.2} | {} | {:.2} | {:.2} | {} |\n",
            v.dataset,
            v.chosen,
            v.auto,
            v.fastest,
            v.fastest_speedup,
            v.auto / v.fastest_speedup,
            if v.passed { "pass" } else { "**FAIL**" }
        );
    }
    let passed = verdicts.iter().all(|v| v.passed);
    (out, passed)
}
