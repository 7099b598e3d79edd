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
}

impl Row {
    /// |b - a| / a.
    pub fn change(&self) -> f64 {
        (self.b_ms - self.a_ms).abs() / self.a_ms
    }
}

pub struct Comparison {
    pub rows: Vec<Row>,
    /// Per data set: (data set, fastest in A, fastest in B).
    pub fastest: Vec<(String, String, String)>,
    /// Records in only one of the runs.
    pub unmatched: usize,
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
                })
            })
            .collect();
        let unmatched = a.len() + b.len() - 2 * rows.len();
        let fb = fastest(b);
        let fastest = fastest(a)
            .into_iter()
            .filter_map(|ra| {
                let rb = fb.iter().find(|rb| rb.dataset == ra.dataset)?;
                Some((ra.dataset.clone(), ra.structure.clone(), rb.structure.clone()))
            })
            .collect();
        Comparison {
            rows,
            fastest,
            unmatched,
        }
    }

    /// The largest relative change of a median.
    pub fn worst(&self) -> f64 {
        self.rows.iter().map(Row::change).fold(0.0, f64::max)
    }

    pub fn same_fastest(&self) -> bool {
        self.fastest.iter().all(|(_, a, b)| a == b)
    }

    /// Markdown: one row per record, then the fastest per data set.
    pub fn markdown(&self, a: &str, b: &str) -> String {
        let mut out = String::from("| data set | structure | A ms | B ms | B / A |\n|---|---|---|---|---|\n");
        for r in &self.rows {
            out += &format!(
                "| {} | {} | {:.2} | {:.2} | {:.3} |\n",
                r.dataset,
                r.structure,
                r.a_ms,
                r.b_ms,
                r.b_ms / r.a_ms
            );
        }
        out += "\n| data set | fastest in A | fastest in B |\n|---|---|---|\n";
        for (d, fa, fb) in &self.fastest {
            out += &format!("| {d} | {fa} | {fb} |\n");
        }
        out + &format!(
            "\nA = {a}, B = {b}: largest change of a median {:.1} %, fastest structure the same on {} of {} data sets{}\n",
            100.0 * self.worst(),
            self.fastest.iter().filter(|(_, x, y)| x == y).count(),
            self.fastest.len(),
            if self.unmatched > 0 {
                format!(", {} records in only one run", self.unmatched)
            } else {
                String::new()
            }
        )
    }
}
