//! CPU reference LBVH: the same Morton order, the same Karras emit (ties
//! broken by index) and the same boxes, for testing the GPU builder.

use super::Node;
use crate::accel::cost::CostModel;
use crate::accel::morton::morton3;

fn delta(codes: &[u32], i: i64, j: i64) -> i64 {
    if j < 0 || j >= codes.len() as i64 {
        return -1;
    }
    let (a, b) = (codes[i as usize], codes[j as usize]);
    if a != b {
        (a ^ b).leading_zeros() as i64
    } else {
        32 + ((i ^ j) as u32).leading_zeros() as i64
    }
}

/// Karras 2012 topology over sorted `codes`: 2n - 1 nodes, internal nodes
/// first; leaves carry only their index in `hi[3]`.
pub fn emit(codes: &[u32]) -> Vec<Node> {
    let n = codes.len() as i64;
    if n == 0 {
        return Vec::new();
    }
    let mut nodes = vec![Node::default(); (2 * n - 1) as usize];
    for i in 0..n - 1 {
        let d = if delta(codes, i, i + 1) - delta(codes, i, i - 1) > 0 {
            1
        } else {
            -1
        };
        let dmin = delta(codes, i, i - d);
        let mut lmax = 2;
        while delta(codes, i, i + lmax * d) > dmin {
            lmax *= 2;
        }
        let mut l = 0;
        let mut t = lmax / 2;
        while t >= 1 {
            if delta(codes, i, i + (l + t) * d) > dmin {
                l += t;
            }
            t /= 2;
        }
        let j = i + l * d;
        let dnode = delta(codes, i, j);
        let (mut s, mut t) = (0, l);
        loop {
            t = (t + 1) / 2;
            if delta(codes, i, i + (s + t) * d) > dnode {
                s += t;
            }
            if t <= 1 {
                break;
            }
        }
        let split = i + s * d + d.min(0);
        let leaf0 = n - 1;
        let left = if i.min(j) == split { leaf0 + split } else { split };
        let right = if i.max(j) == split + 1 {
            leaf0 + split + 1
        } else {
            split + 1
        };
        nodes[i as usize].lo[3] = left as i32;
        nodes[i as usize].hi[3] = right as i32;
    }
    for k in 0..n {
        nodes[(n - 1 + k) as usize].lo[3] = -1;
        nodes[(n - 1 + k) as usize].hi[3] = k as i32;
    }
    nodes
}

/// The full LBVH over `active` brick indices (ascending, as compaction
/// yields them): stable sort by Morton code, emit, boxes bottom up.
pub fn build(active: &[u32], counts: [u32; 3], dims: [u32; 3], brick: u32) -> Vec<Node> {
    let coord = |b: u32| [b % counts[0], (b / counts[0]) % counts[1], b / (counts[0] * counts[1])];
    let mut keyed: Vec<(u32, u32)> = active.iter().map(|&b| (morton3(coord(b)), b)).collect();
    keyed.sort_by_key(|k| k.0);
    let codes: Vec<u32> = keyed.iter().map(|k| k.0).collect();
    let mut nodes = emit(&codes);
    let n = codes.len();
    for (k, &(_, b)) in keyed.iter().enumerate() {
        let c = coord(b);
        let lo = [0, 1, 2].map(|a| (c[a] * brick) as i32);
        let hi = [0, 1, 2].map(|a| ((c[a] + 1) * brick).min(dims[a]) as i32);
        nodes[n - 1 + k] = Node {
            lo: [lo[0], lo[1], lo[2], -1],
            hi: [hi[0], hi[1], hi[2], b as i32],
        };
    }
    fn fill(nodes: &mut [Node], i: usize) -> ([i32; 3], [i32; 3]) {
        let node = nodes[i];
        if node.is_leaf() {
            return (
                [node.lo[0], node.lo[1], node.lo[2]],
                [node.hi[0], node.hi[1], node.hi[2]],
            );
        }
        let (a_lo, a_hi) = fill(nodes, node.lo[3] as usize);
        let (b_lo, b_hi) = fill(nodes, node.hi[3] as usize);
        let lo = [0, 1, 2].map(|k| a_lo[k].min(b_lo[k]));
        let hi = [0, 1, 2].map(|k| a_hi[k].max(b_hi[k]));
        nodes[i].lo[..3].copy_from_slice(&lo);
        nodes[i].hi[..3].copy_from_slice(&hi);
        (lo, hi)
    }
    if n > 0 {
        fill(&mut nodes, 0);
    }
    nodes
}

/// Cost-driven leaves on a built tree, as `glsl/build/lbvh_collapse.comp`
/// decides them: bottom up, a node whose cost as one leaf is not above its
/// cost as an inner node becomes a leaf (`lo[3] = -1`).
pub fn collapse(nodes: &mut [Node], model: &CostModel) {
    // (cost, area) of node i after collapsing below it.
    fn walk(nodes: &mut [Node], i: usize, model: &CostModel) -> (f32, f32) {
        let (lo, hi) = nodes[i].bounds();
        let leaf = model.leaf(lo, hi);
        if nodes[i].is_leaf() {
            return leaf;
        }
        let l = walk(nodes, nodes[i].lo[3] as usize, model);
        let r = walk(nodes, nodes[i].hi[3] as usize, model);
        let inner = model.inner(leaf.1, l, r);
        if leaf.0 <= inner {
            nodes[i].lo[3] = -1;
            leaf
        } else {
            (inner, leaf.1)
        }
    }
    if !nodes.is_empty() {
        walk(nodes, 0, model);
    }
}
