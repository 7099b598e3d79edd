//! A 3-D summed-area table (summed volume table) of active cells: the count
//! of active cells in any box in eight lookups. Used by the CPU k-d tree (per
//! 32^3 brick of voxel footprints, `u16`) and the brick octree (over the
//! brick grid, `u32`).

/// Inclusive prefix counts over a grid, with a zero border on the low side.
pub struct Sat3<T> {
    /// Table edge per axis: grid dims + 1.
    edge: [usize; 3],
    table: Vec<T>,
}

impl<T> Sat3<T>
where
    T: Copy + Default + std::ops::AddAssign + From<bool> + Into<i64>,
{
    /// The table of a `dims` grid whose cell (x, y, z) is active when
    /// `active(x, y, z)`. `T` must hold the total count.
    pub fn new(dims: [usize; 3], active: impl Fn(usize, usize, usize) -> bool) -> Self {
        let edge = dims.map(|d| d + 1);
        let mut table = vec![T::default(); edge[0] * edge[1] * edge[2]];
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    table[(x + 1) + edge[0] * ((y + 1) + edge[1] * (z + 1))] = T::from(active(x, y, z));
                }
            }
        }
        // Inclusive prefix sums along x, then y, then z.
        let strides = [1, edge[0], edge[0] * edge[1]];
        for (axis, stride) in strides.into_iter().enumerate() {
            for i in 0..table.len() {
                let c = [i % edge[0], (i / edge[0]) % edge[1], i / (edge[0] * edge[1])];
                if c[axis] >= 1 {
                    let prev = table[i - stride];
                    table[i] += prev;
                }
            }
        }
        Sat3 { edge, table }
    }

    fn at(&self, x: usize, y: usize, z: usize) -> i64 {
        self.table[x + self.edge[0] * (y + self.edge[1] * z)].into()
    }

    /// Active cells in `[lo, hi)` (cell coordinates within the grid).
    pub fn count(&self, lo: [usize; 3], hi: [usize; 3]) -> i64 {
        if (0..3).any(|a| lo[a] >= hi[a]) {
            return 0;
        }
        let ([lx, ly, lz], [hx, hy, hz]) = (lo, hi);
        self.at(hx, hy, hz) - self.at(lx, hy, hz) - self.at(hx, ly, hz) - self.at(hx, hy, lz)
            + self.at(lx, ly, hz)
            + self.at(lx, hy, lz)
            + self.at(hx, ly, lz)
            - self.at(lx, ly, lz)
    }

    /// Active cells in the whole grid.
    pub fn total(&self) -> i64 {
        self.table.last().map_or(0, |&t| t.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_counts_match_brute_force() {
        let dims = [5usize, 4, 3];
        let active = |x: usize, y: usize, z: usize| (x * 7 + y * 3 + z * 5).is_multiple_of(4);
        let sat = Sat3::<u32>::new(dims, active);
        for lo in [[0, 0, 0], [1, 2, 1], [4, 0, 2]] {
            for hi in [[5, 4, 3], [2, 3, 2], [5, 1, 3]] {
                let mut n = 0;
                for z in lo[2]..hi[2] {
                    for y in lo[1]..hi[1] {
                        for x in lo[0]..hi[0] {
                            n += active(x, y, z) as i64;
                        }
                    }
                }
                assert_eq!(sat.count(lo, hi), n, "{lo:?}..{hi:?}");
            }
        }
        assert_eq!(sat.total(), sat.count([0; 3], dims));
    }
}
