//! auto's cost model: what a frame costs a march kernel, from what it does
//! (`probe::Counts`, scaled to the whole frame):
//!
//! `ms = rays * ray_ns + samples * sample_ns + steps * step_ns + regions * region_ns`
//!
//! where samples, steps and regions are iterations of the kernel's loops
//! summed over SIMD groups (a group runs until its slowest lane is done, so
//! these, not the rays' own counts, are what the device pays). The
//! constants are per kernel and per set of frame constants (filter, mode,
//! shading, texel kind, cells copy: what changes a sample's cost), measured
//! on the device (`calibrate.rs`) and kept per device and driver
//! (`cache.rs`).

use super::super::method::March;
use crate::desc::{KernelConstants, SHININESS_CONSTANT_ID};
use crate::error::{Error, Result};

/// A kernel's cost per unit of work, in GPU nanoseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct KernelCost {
    pub ray_ns: f64,
    pub sample_ns: f64,
    pub step_ns: f64,
    pub region_ns: f64,
}

impl KernelCost {
    /// Constants for where measuring is not wanted (tests, the hard-case
    /// suite, whose checks do not depend on which exact structure auto
    /// marches): about what lavapipe measured for the distance kernel.
    pub const NOMINAL: KernelCost = KernelCost {
        ray_ns: 50.0,
        sample_ns: 30.0,
        step_ns: 40.0,
        region_ns: 150.0,
    };

    pub fn as_array(&self) -> [f64; 4] {
        [self.ray_ns, self.sample_ns, self.step_ns, self.region_ns]
    }

    pub fn from_array(c: [f64; 4]) -> Self {
        KernelCost {
            ray_ns: c[0],
            sample_ns: c[1],
            step_ns: c[2],
            region_ns: c[3],
        }
    }

    /// Predicted milliseconds for `work` (rays, samples, steps, regions).
    pub fn predict(&self, work: [f64; 4]) -> f64 {
        self.as_array().iter().zip(work).map(|(c, w)| c * w).sum::<f64>() * 1e-6
    }

    /// Every constant finite and not negative.
    pub fn is_valid(&self) -> bool {
        self.as_array().iter().all(|c| c.is_finite() && *c >= 0.0)
    }
}

/// Which constants apply: the kernel (shader and the structure's
/// constants) and the frame's constants.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct CostKey {
    pub shader: &'static str,
    pub constants: &'static [u32],
    pub frame: KernelConstants,
}

impl CostKey {
    pub fn new(march: March, mut frame: KernelConstants) -> Self {
        // Whole Phong exponents cost alike (a few multiplies): one model
        // for all of them, another for pow (0).
        for (id, v) in &mut frame {
            if *id == SHININESS_CONSTANT_ID {
                *v = (*v).min(1);
            }
        }
        CostKey {
            shader: march.shader.name,
            constants: march.constants,
            frame,
        }
    }

    /// One word for the cache file: `march/distance[1]|16=0,17=0,...`.
    pub fn text(&self) -> String {
        let own: Vec<String> = self.constants.iter().map(|c| c.to_string()).collect();
        let frame: Vec<String> = self.frame.iter().map(|(id, v)| format!("{id}={v}")).collect();
        format!("{}[{}]|{}", self.shader, own.join(","), frame.join(","))
    }
}

/// Non-negative least squares for a few unknowns: minimises
/// `sum_i w_i (a_i . x - b_i)^2` over `x >= 0`, by solving the normal
/// equations on every subset of free unknowns (2^n of them) and keeping the
/// best feasible solution. Unknowns whose column is all zero stay 0.
pub fn nnls(rows: &[([f64; 4], f64)], weights: &[f64]) -> Result<[f64; 4]> {
    let mut best: Option<([f64; 4], f64)> = None;
    for mask in 0u32..16 {
        let free: Vec<usize> = (0..4).filter(|i| mask & (1 << i) != 0).collect();
        let Some(x) = solve_subset(rows, weights, &free) else {
            continue;
        };
        if x.iter().any(|v| *v < 0.0 || !v.is_finite()) {
            continue;
        }
        let residual: f64 = rows
            .iter()
            .zip(weights)
            .map(|((a, b), w)| {
                let fit: f64 = a.iter().zip(&x).map(|(a, x)| a * x).sum();
                w * (fit - b) * (fit - b)
            })
            .sum();
        if best.is_none_or(|(_, r)| residual < r) {
            best = Some((x, residual));
        }
    }
    best.map(|(x, _)| x)
        .ok_or_else(|| Error::invalid("cost model", "calibration", "no non-negative fit of the measured times"))
}

/// Weighted least squares over the unknowns in `free` (the others 0);
/// None when the system is singular.
fn solve_subset(rows: &[([f64; 4], f64)], weights: &[f64], free: &[usize]) -> Option<[f64; 4]> {
    let n = free.len();
    let mut x = [0.0; 4];
    if n == 0 {
        return Some(x);
    }
    // Normal equations M y = v, scaled per column for conditioning.
    let scale: Vec<f64> = free
        .iter()
        .map(|&j| rows.iter().map(|(a, _)| a[j].abs()).fold(0.0, f64::max))
        .collect();
    if scale.contains(&0.0) {
        return None;
    }
    let mut m = vec![vec![0.0; n + 1]; n];
    for ((a, b), w) in rows.iter().zip(weights) {
        for r in 0..n {
            let ar = a[free[r]] / scale[r];
            for c in 0..n {
                m[r][c] += w * ar * a[free[c]] / scale[c];
            }
            m[r][n] += w * ar * b;
        }
    }
    // Gaussian elimination with partial pivoting; a pivot that is tiny
    // next to the matrix is a singular system.
    let norm = m.iter().flat_map(|r| r[..n].iter()).fold(0.0f64, |a, v| a.max(v.abs()));
    if norm == 0.0 {
        return None;
    }
    for col in 0..n {
        let pivot = (col..n).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[pivot][col].abs() < 1e-9 * norm {
            return None;
        }
        m.swap(col, pivot);
        let pivot_row = m[col].clone();
        for (r, row) in m.iter_mut().enumerate() {
            if r != col {
                let f = row[col] / pivot_row[col];
                for (v, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                    *v -= f * p;
                }
            }
        }
    }
    for (r, &j) in free.iter().enumerate() {
        x[j] = m[r][n] / m[r][r] / scale[r];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_recovers_exact_constants_and_keeps_them_non_negative() {
        let truth = [2.0, 0.5, 3.0, 7.0];
        let work = [
            [100.0, 1000.0, 10.0, 2.0],
            [100.0, 300.0, 50.0, 9.0],
            [100.0, 0.0, 80.0, 1.0],
            [100.0, 2000.0, 5.0, 30.0],
            [100.0, 700.0, 0.0, 0.0],
        ];
        let rows: Vec<([f64; 4], f64)> = work
            .iter()
            .map(|a| (*a, a.iter().zip(&truth).map(|(a, c)| a * c).sum()))
            .collect();
        // Relative weights, as calibration uses them, at the scale of its
        // times (ns of a frame: 1e6 to 1e8), so the weights are tiny.
        for scale in [1.0, 1e7] {
            let rows: Vec<([f64; 4], f64)> = rows.iter().map(|(a, b)| (*a, b * scale)).collect();
            let truth = truth.map(|c| c * scale);
            let w: Vec<f64> = rows.iter().map(|(_, b)| 1.0 / (b * b)).collect();
            let x = nnls(&rows, &w).unwrap();
            for (got, want) in x.iter().zip(truth) {
                assert!((got - want).abs() < 1e-6 * want, "{x:?}");
            }
        }
        // A column of zeros (naive has no steps or regions) stays 0, and a
        // fit that wants a negative constant gets 0 instead.
        let rows = [([10.0, 100.0, 0.0, 0.0], 50.0), ([10.0, 300.0, 0.0, 0.0], 40.0)];
        let x = nnls(&rows, &[1.0, 1.0]).unwrap();
        assert_eq!(x[2], 0.0);
        assert_eq!(x[3], 0.0);
        assert!(x.iter().all(|v| *v >= 0.0), "{x:?}");
    }

    #[test]
    fn a_prediction_is_the_work_times_the_constants() {
        let c = KernelCost::from_array([1.0, 2.0, 3.0, 4.0]);
        assert_eq!(c.predict([1e6, 1e6, 0.0, 1e6]), 7.0);
        assert!(c.is_valid());
        assert!(!KernelCost::from_array([1.0, -1.0, 0.0, 0.0]).is_valid());
    }
}
