//! Named phase timings in milliseconds, GPU (timestamps) and CPU (`Instant`).

use std::fmt;
use std::time::Instant;

/// The median of `v` (the mean of the middle two for an even count; NaN
/// when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// Named phases and their milliseconds (GPU timestamps, or wall time for
/// host phases).
#[derive(Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Timings {
    /// (phase name, milliseconds), in the order the phases ran.
    pub phases: Vec<(String, f64)>,
}

impl Timings {
    pub fn push(&mut self, name: impl Into<String>, ms: f64) {
        self.phases.push((name.into(), ms));
    }

    /// Runs `f` and records its wall time as phase `name`.
    pub fn cpu<T>(&mut self, name: &str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let value = f();
        self.push(name, start.elapsed().as_secs_f64() * 1e3);
        value
    }

    pub fn get(&self, name: &str) -> Option<f64> {
        self.phases.iter().find(|(n, _)| n == name).map(|(_, ms)| *ms)
    }

    /// The phase `name`, or an error naming it: a misspelt phase must not
    /// read as zero.
    pub fn phase(&self, name: &str) -> crate::Result<f64> {
        self.get(name).ok_or_else(|| {
            let have: Vec<&str> = self.phases.iter().map(|(n, _)| n.as_str()).collect();
            crate::Error::invalid(
                "timing phase",
                name,
                format!("not measured (have: {})", have.join(", ")),
            )
        })
    }

    /// The phases' sum; 0 (not the -0 of an empty f64 sum) without any.
    pub fn total(&self) -> f64 {
        self.phases.iter().fold(0.0, |sum, (_, ms)| sum + ms)
    }

    pub fn extend(&mut self, other: Timings) {
        self.phases.extend(other.phases);
    }

    /// Per-phase median over several runs of the same phases (phases missing
    /// from some runs use the runs that have them).
    pub fn median(runs: &[Timings]) -> Timings {
        let mut out = Timings::default();
        let Some(first) = runs.first() else { return out };
        for (name, _) in &first.phases {
            out.push(name.clone(), median(runs.iter().filter_map(|r| r.get(name)).collect()));
        }
        out
    }
}

impl fmt::Display for Timings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let width = self.phases.iter().map(|(n, _)| n.len()).max().unwrap_or(0).max(5);
        for (name, ms) in &self.phases {
            writeln!(f, "  {name:<width$}  {ms:>10.3} ms")?;
        }
        write!(f, "  {:<width$}  {:>10.3} ms", "total", self.total())
    }
}

#[cfg(test)]
mod total_tests {
    #[test]
    fn no_phases_total_positive_zero() {
        let t = super::Timings::default().total();
        assert!(t == 0.0 && t.is_sign_positive(), "{t}");
    }
}
