//! Data-parallel rendering across processes: `mpirun -np N lacuna render`.
//!
//! The volume's bricks are split into N blocks by a k-d decomposition
//! (`decompose.rs`); each rank stores its block and one layer of ghost
//! bricks (`GpuVolume::upload_bricks_kept`), builds its own structure and
//! renders the frame cropped to its block: the ray's segment inside the
//! block, on the global sample lattice, so every lattice sample of the
//! ray is taken by exactly one rank. The ranks' premultiplied frames are
//! blended front to back in the k-d tree's visibility order by IceT
//! (`mpi.rs`, feature `mpi`); MIP and MinIP frames keep, per pixel, the
//! colour of the rank with the largest (smallest) ray value, iso frames
//! that of the nearest surface (`pick`, by an MPI max-location
//! reduction), which is the one process's frame bit for bit. Rank 0 writes the frame. docs/parallel.md has the measurements and
//! how it scales.

mod decompose;
#[cfg(feature = "mpi")]
mod mpi;

pub use decompose::{Block, Decomposition};
#[cfg(feature = "mpi")]
pub use mpi::{Failed, World};

/// The ranks this process was launched with by `mpirun`/`mpiexec`
/// (OpenMPI's or MPICH's environment); None when not launched so.
pub fn launched_ranks() -> Option<u32> {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE"]
        .iter()
        .find_map(|k| std::env::var(k).ok())
        .and_then(|v| v.trim().parse().ok())
}

/// This process's rank when launched by `mpirun`/`mpiexec`.
pub fn launched_rank() -> Option<u32> {
    ["OMPI_COMM_WORLD_RANK", "PMI_RANK"]
        .iter()
        .find_map(|k| std::env::var(k).ok())
        .and_then(|v| v.trim().parse().ok())
}

/// Whether this build renders across ranks (feature `mpi`).
pub const ENABLED: bool = cfg!(feature = "mpi");

/// Whether a process `launched` with that many ranks renders across
/// them; an error where `enabled` (`ENABLED`) is false and there are
/// several: a build without MPI would render the whole frame once per rank.
pub fn across_ranks(launched: Option<u32>, enabled: bool) -> crate::Result<bool> {
    match launched {
        Some(n) if n > 1 && !enabled => Err(crate::Error::invalid(
            "launch",
            format!("mpirun with {n} ranks"),
            "this lacuna is built without the `mpi` feature: build it with `cargo build --release --features mpi` \
             (after `cargo xtask setup mpi`)",
        )),
        Some(n) => Ok(n > 1),
        None => Ok(false),
    }
}

/// Blends the ranks' premultiplied frames front to back, `order` listing
/// ranks front first: `acc + (1 - acc.a) * next`, IceT's blend done on one
/// machine (an engine that gathers the parts itself, and the tests' check
/// of IceT). `parts[r]` is rank r's frame; all of one size.
pub fn blend(parts: &[&[[f32; 4]]], order: &[u32]) -> Vec<[f32; 4]> {
    let n = parts.first().map_or(0, |p| p.len());
    let mut acc = vec![[0.0f32; 4]; n];
    for &rank in order {
        for (a, c) in acc.iter_mut().zip(parts[rank as usize]) {
            let transmit = 1.0 - a[3];
            for ch in 0..4 {
                a[ch] += transmit * c[ch];
            }
        }
    }
    acc
}

/// Per pixel, the colour of the part whose value is the largest
/// (`largest`) or the smallest, the first such part on ties: how ranks'
/// MIP (MinIP) frames composite by their ray values
/// (`FrameDesc::writes_ray_values`), and iso frames by their surface
/// depths (the smallest: the nearest surface). Each part's colour is that
/// of its own value or surface, so the pick is the one process's colour,
/// bit for bit. `parts[r]` and `values[r]` are rank r's (`Frame::depth`).
/// Iso depths are the smallest where nearest only as distances (an orbit
/// camera's) or standard NDC depth; with reverse-Z host matrices the
/// nearest is the largest (and a miss is 0): pick with `largest`.
pub fn pick(parts: &[&[[f32; 4]]], values: &[&[f32]], largest: bool) -> Vec<[f32; 4]> {
    let n = parts.first().map_or(0, |p| p.len());
    (0..n)
        .map(|i| {
            let better = |a: f32, b: f32| if largest { a > b } else { a < b };
            let mut won = 0;
            for r in 1..parts.len() {
                if better(values[r][i], values[won][i]) {
                    won = r;
                }
            }
            parts[won][i]
        })
        .collect()
}
