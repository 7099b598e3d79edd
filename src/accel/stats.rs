//! Structure statistics in the form of the paper's Table 1.

use std::fmt;

/// What a built structure holds: classified units, active ones, nodes,
/// leaves and height.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Stats {
    /// What is classified: "8^3 bricks", "voxel footprints", "16^3 cells".
    pub unit: &'static str,
    pub total_bricks: u64,
    pub active_bricks: u64,
    pub nodes: u64,
    pub leaves: u64,
    /// Nodes on the longest root-to-leaf path (a lone leaf has height 1).
    pub height: u32,
    /// GPU bytes of the structure the march kernel reads.
    pub bytes: u64,
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "active {} of {} {} ({:.2} %), nodes {}, leaves {}, height {}, {} bytes",
            self.active_bricks,
            self.total_bricks,
            self.unit,
            if self.total_bricks > 0 {
                100.0 * self.active_bricks as f64 / self.total_bricks as f64
            } else {
                0.0
            },
            self.nodes,
            self.leaves,
            self.height,
            self.bytes
        )
    }
}
