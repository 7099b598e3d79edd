//! Two runs of the same config side by side: per record, the ratio of the
//! median frame times, and whether each data set's fastest structure is the
//! same. What `lacuna bench --compare A.json B.json` prints; it is how the
//! cold-shader-cache check in the README is made.

use super::record::Record;
use super::tables::fastest;

/// One record present in both runs.
pub struct Row {
    pub dataset: String,
    pub structure: String,
    pub a_ms: f64,
    pub b_ms: f64,
    /// Speed-up over naive in each run.
    pub a_speedup: f64,
    pub b_speedup: f64,
}

impl Row {
    /// |b - a| / a.
    pub fn change(&self) -> f64 {
        (self.b_ms - self.a_ms).abs() / self.a_ms
    }

    /// |b - a| / a of the speed-ups: free of drift that slows every
    /// structure of a run alike.
    pub fn speedup_change(&self) -> f64 {
        (self.b_speedup - self.a_speedup).abs() / self.a_speedup
    }
}

/// Names joined by commas, or `none`.
fn list(names: &[String]) -> String {
    match names.is_empty() {
        true => "none".into(),
        false => names.join(", "),
    }
}

/// One data set's fastest structure in each of two runs.
pub struct Fastest {
    pub dataset: String,
    pub a: String,
    pub b: String,
    /// B's median of A's fastest over B's fastest: 1 when they agree.
    pub b_ratio: f64,
}

/// Two structures within this fraction of each other are tied: a run
/// cannot rank them.
pub const TIE: f64 = 0.05;

impl Fastest {
    /// The same structure, or A's fastest within `TIE` of B's in B.
    pub fn agrees(&self) -> bool {
        self.a == self.b || self.b_ratio <= 1.0 + TIE
    }
}

/// Two bench runs' records side by side (`lacuna bench --compare A B`).
pub struct Comparison {
    pub rows: Vec<Row>,
    /// Per data set, the fastest structure of each run.
    pub fastest: Vec<Fastest>,
    /// Records (`data set / structure`) in A only: a structure or data set
    /// that B lost fails the comparison.
    pub only_a: Vec<String>,
    /// Records in B only.
    pub only_b: Vec<String>,
    /// Per record in both runs whose frames differ in what defines them
    /// (size, step, ERT, views, filter, transfer function, grid): the
    /// record and each such field with both values. Such runs measure
    /// different work and are not compared.
    pub mismatched: Vec<(String, Vec<String>)>,
    /// Differences that do not change the work (device, driver, config
    /// name): named, and compared anyway.
    pub notes: Vec<String>,
}

/// What defines a record's frames, by name, as text.
fn frame_fields(r: &Record) -> [(&'static str, String); 7] {
    let ert = r.setup.timed_ert.map_or("off".to_string(), |e| e.to_string());
    [
        ("size", format!("{}x{}", r.setup.width, r.setup.height)),
        ("step", r.setup.step.to_string()),
        ("ert", ert),
        ("camera", r.setup.camera.clone()),
        ("filter", r.filter.clone()),
        ("tf", r.tf.clone()),
        ("dims", format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2])),
    ]
}

/// The fields of `frame_fields` in which `a` and `b` differ, as `name A
/// against B`. The sample filter is each device's faster by default, so
/// on two devices it is named in a note, not refused.
fn differences(a: &Record, b: &Record, notes: &mut Vec<String>) -> Vec<String> {
    let devices = a.setup.device != b.setup.device;
    let mut refused = Vec::new();
    for ((name, x), (_, y)) in frame_fields(a).into_iter().zip(frame_fields(b)) {
        let text = format!("{name} {x} against {y}");
        match x == y {
            true => {}
            false if devices && name == "filter" => {
                let note = format!("sample filter: A {x}, B {y} (each device's faster unless the config names one)");
                if !notes.contains(&note) {
                    notes.push(note);
                }
            }
            false => refused.push(text),
        }
    }
    refused
}

/// Run-wide differences that leave the work alike: where each ran.
fn run_notes(a: &[Record], b: &[Record]) -> Vec<String> {
    let (Some(ra), Some(rb)) = (a.first(), b.first()) else {
        return Vec::new();
    };
    [
        ("device", &ra.setup.device, &rb.setup.device),
        ("driver", &ra.setup.driver, &rb.setup.driver),
        ("config", &ra.setup.config, &rb.setup.config),
    ]
    .into_iter()
    .filter(|(_, x, y)| x != y)
    .map(|(name, x, y)| format!("{name}: A {x}, B {y}"))
    .collect()
}

impl Comparison {
    pub fn new(a: &[Record], b: &[Record]) -> Self {
        let key = |r: &Record| (r.dataset.clone(), r.structure.clone());
        let rows: Vec<Row> = a
            .iter()
            .filter_map(|ra| {
                let rb = b.iter().find(|rb| key(rb) == key(ra))?;
                Some(Row {
                    dataset: ra.dataset.clone(),
                    structure: ra.structure.clone(),
                    a_ms: ra.frame.median_ms,
                    b_ms: rb.frame.median_ms,
                    a_speedup: ra.speedup,
                    b_speedup: rb.speedup,
                })
            })
            .collect();
        let name = |r: &Record| format!("{} / {}", r.dataset, r.structure);
        let only = |x: &[Record], y: &[Record]| -> Vec<String> {
            x.iter()
                .filter(|r| !y.iter().any(|o| key(o) == key(r)))
                .map(name)
                .collect()
        };
        let mut notes = run_notes(a, b);
        let mismatched = a
            .iter()
            .filter_map(|ra| {
                let rb = b.iter().find(|rb| key(rb) == key(ra))?;
                let d = differences(ra, rb, &mut notes);
                (!d.is_empty()).then(|| (name(ra), d))
            })
            .collect();
        let fb = fastest(b);
        let fastest = fastest(a)
            .into_iter()
            .filter_map(|ra| {
                let rb = fb.iter().find(|rb| rb.dataset == ra.dataset)?;
                let a_in_b = b.iter().find(|r| key(r) == key(ra))?;
                Some(Fastest {
                    dataset: ra.dataset.clone(),
                    a: ra.structure.clone(),
                    b: rb.structure.clone(),
                    b_ratio: a_in_b.frame.median_ms / rb.frame.median_ms,
                })
            })
            .collect();
        Comparison {
            rows,
            fastest,
            only_a: only(a, b),
            only_b: only(b, a),
            mismatched,
            notes,
        }
    }

    /// Every record of each run is in the other.
    pub fn complete(&self) -> bool {
        self.only_a.is_empty() && self.only_b.is_empty()
    }

    /// The largest relative change of a median.
    pub fn worst(&self) -> f64 {
        self.rows.iter().map(Row::change).fold(0.0, f64::max)
    }

    /// The largest relative change of a speed-up over naive.
    pub fn worst_speedup(&self) -> f64 {
        self.rows.iter().map(Row::speedup_change).fold(0.0, f64::max)
    }

    pub fn same_fastest(&self) -> bool {
        self.fastest.iter().all(Fastest::agrees)
    }

    /// Markdown: one row per record, then the fastest per data set.
    pub fn markdown(&self, a: &str, b: &str) -> String {
        let mut out = String::from(
            "| data set | structure | A ms | B ms | B / A | A speed-up | B speed-up |\n|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            out += &format!(
                "| {} | {} | {:.2} | {:.2} | {:.3} | {:.2}x | {:.2}x |\n",
                r.dataset,
                r.structure,
                r.a_ms,
                r.b_ms,
                r.b_ms / r.a_ms,
                r.a_speedup,
                r.b_speedup
            );
        }
        out += "\n| data set | fastest in A | fastest in B | A's fastest in B |\n|---|---|---|---|\n";
        for f in &self.fastest {
            let verdict = if f.a == f.b {
                "the same".to_string()
            } else if f.agrees() {
                format!("{:.1} % slower: tied", 100.0 * (f.b_ratio - 1.0))
            } else {
                format!("{:.1} % slower", 100.0 * (f.b_ratio - 1.0))
            };
            out += &format!("| {} | {} | {} | {verdict} |\n", f.dataset, f.a, f.b);
        }
        out + &format!(
            "\nA = {a}, B = {b}: largest change of a median {:.1} %, of a speed-up over naive {:.1} %; \
             fastest structure the same or tied (within {:.0} %) on {} of {} data sets{}\n",
            100.0 * self.worst(),
            100.0 * self.worst_speedup(),
            100.0 * TIE,
            self.fastest.iter().filter(|f| f.agrees()).count(),
            self.fastest.len(),
            if self.complete() {
                String::new()
            } else {
                format!(
                    "; records in A only: {}; in B only: {}",
                    list(&self.only_a),
                    list(&self.only_b)
                )
            }
        )
    }
}
