//! CPU octree construction after Havran's setup: objects go to every child
//! their (closed) bounding box overlaps, a node is a leaf when it holds at
//! most `max_objects` objects or reaches `max_depth`, and all eight children
//! of an interior node are allocated. Subdivision is at the centre (mode C)
//! or adaptive (mode A: per axis the cheapest of 10 positions between the
//! spatial and the object median, after Whang et al.'s Octree-R).

use super::node::{axis_bit, Node};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::fmt;
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Where an octree node splits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mode {
    /// Centre subdivision.
    Center,
    /// Adaptive subdivision (cost-driven split positions).
    Adaptive,
}

impl Mode {
    pub fn letter(self) -> &'static str {
        match self {
            Mode::Center => "C",
            Mode::Adaptive => "A",
        }
    }
}

impl fmt::Display for Mode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.letter())
    }
}

impl FromStr for Mode {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s {
            "C" | "c" => Ok(Mode::Center),
            "A" | "a" => Ok(Mode::Adaptive),
            _ => Err(crate::Error::invalid(
                "octree mode",
                s,
                "expected C (centre) or A (adaptive)",
            )),
        }
    }
}

/// An axis-aligned box in f32 (the traversals' precision).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Box3 {
    pub lo: [f32; 3],
    pub hi: [f32; 3],
}

impl Box3 {
    fn overlaps(&self, o: &Box3) -> bool {
        (0..3).all(|a| o.lo[a] <= self.hi[a] && o.hi[a] >= self.lo[a])
    }
}

/// Build parameters. Havran's: `max_objects` 1, `max_depth` 4..7.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OctreeOptions {
    pub mode: Mode,
    pub max_depth: u32,
    pub max_objects: u32,
}

/// Havran's build statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// N_IN: interior nodes.
    pub interior: u64,
    /// N_V: leaves.
    pub leaves: u64,
    /// N_EV: empty leaves.
    pub empty_leaves: u64,
    /// N_OIV: object references in leaves.
    pub references: u64,
    /// T_B: build time, seconds.
    pub build_s: f64,
}

/// A built octree: nodes (root first, children contiguous) and the leaves'
/// object reference list.
#[derive(Clone, Debug)]
pub struct Octree {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    pub stats: BuildStats,
    pub options: OctreeOptions,
}

/// Deepest tree the GLSL traversal stacks hold.
pub const MAX_DEPTH_LIMIT: u32 = 14;

enum Tree {
    Leaf(Vec<u32>),
    Interior([f32; 3], Box<[Tree; 8]>),
}

fn child_box(b: &Box3, split: [f32; 3], i: u32) -> Box3 {
    let mut c = *b;
    for (a, &s) in split.iter().enumerate() {
        if i & axis_bit(a) != 0 {
            c.lo[a] = s;
        } else {
            c.hi[a] = s;
        }
    }
    c
}

/// What a build may spend: the bytes of its nodes, object references and
/// the object lists it holds while it splits. Deep trees grow like 8^depth
/// where objects overlap many cells, so the build stops once past it.
struct Budget {
    limit: u64,
    spent: AtomicU64,
    over: AtomicBool,
}

impl Budget {
    /// Spends `bytes`; false (and remembered) once past the limit.
    fn spend(&self, bytes: u64) -> bool {
        let spent = self.spent.fetch_add(bytes, Ordering::Relaxed) + bytes;
        if spent > self.limit {
            self.over.store(true, Ordering::Relaxed);
        }
        !self.over.load(Ordering::Relaxed)
    }
}

impl Octree {
    /// Builds over object boxes inside `root` (which must contain them).
    pub fn build(root: Box3, objects: &[Box3], options: OctreeOptions) -> Octree {
        let start = Instant::now();
        let (tree, _) = subdivide_all(root, objects, &options, u64::MAX);
        Self::flattened(tree, root, options, start)
    }

    /// As `build`, spending at most `max_bytes` on nodes, references and
    /// the lists held while splitting (checked as it goes, so a tree too
    /// deep to hold is an error before it takes the host's memory).
    pub fn build_within(root: Box3, objects: &[Box3], options: OctreeOptions, max_bytes: u64) -> Result<Octree> {
        let start = Instant::now();
        let (tree, over) = subdivide_all(root, objects, &options, max_bytes);
        // Checked before the tree is flattened: that would spend as much again.
        if over {
            return Err(Error::invalid(
                "max depth",
                options.max_depth.to_string(),
                format!(
                    "the octree of {} objects outgrew {max_bytes} bytes (nodes, references and lists) before depth {}: take a smaller max depth",
                    objects.len(),
                    options.max_depth
                ),
            ));
        }
        Ok(Self::flattened(tree, root, options, start))
    }

    fn flattened(tree: Tree, root: Box3, options: OctreeOptions, start: Instant) -> Octree {
        let mut octree = Octree {
            nodes: vec![Node::default()],
            refs: Vec::new(),
            stats: BuildStats::default(),
            options,
        };
        octree.flatten(tree, root);
        octree.stats.build_s = start.elapsed().as_secs_f64();
        octree
    }

    /// Breadth-first so that the eight children of a node are contiguous.
    fn flatten(&mut self, tree: Tree, root: Box3) {
        let mut queue = std::collections::VecDeque::new();
        queue.push_back((0u32, 0u32, 0u32, root, tree));
        while let Some((index, parent, depth, b, t)) = queue.pop_front() {
            let node = &mut self.nodes[index as usize];
            node.lo = [b.lo[0], b.lo[1], b.lo[2], 0.0];
            node.hi = [b.hi[0], b.hi[1], b.hi[2], 0.0];
            match t {
                Tree::Leaf(objs) => {
                    node.info = [self.refs.len() as u32, objs.len() as u32, parent, 1 | depth << 1];
                    self.stats.leaves += 1;
                    self.stats.empty_leaves += u64::from(objs.is_empty());
                    self.stats.references += objs.len() as u64;
                    self.refs.extend(objs);
                }
                Tree::Interior(split, children) => {
                    let first = self.nodes.len() as u32;
                    let node = &mut self.nodes[index as usize];
                    node.split = [split[0], split[1], split[2], 0.0];
                    node.info = [first, 0, parent, depth << 1];
                    self.stats.interior += 1;
                    self.nodes.extend([Node::default(); 8]);
                    for (i, c) in children.into_iter().enumerate() {
                        queue.push_back((first + i as u32, index, depth + 1, child_box(&b, split, i as u32), c));
                    }
                }
            }
        }
    }
}

/// The tree over every object, and whether it went past `limit` bytes
/// (then cut short: leaves where the budget ran out).
fn subdivide_all(root: Box3, objects: &[Box3], options: &OctreeOptions, limit: u64) -> (Tree, bool) {
    let budget = Budget {
        limit,
        spent: AtomicU64::new(0),
        over: AtomicBool::new(false),
    };
    let all: Vec<u32> = (0..objects.len() as u32).collect();
    let tree = subdivide(&root, all, objects, 0, options, &budget);
    (tree, budget.over.load(Ordering::Relaxed))
}

fn subdivide(b: &Box3, objs: Vec<u32>, boxes: &[Box3], depth: u32, o: &OctreeOptions, budget: &Budget) -> Tree {
    // A leaf's references, or an interior node's eight children (each a
    // `Tree` now and a `Node` when flattened, whose vector may double) and
    // their object lists (at most eight of this node's).
    let leaf = objs.len() as u32 <= o.max_objects || depth >= o.max_depth;
    let child = (std::mem::size_of::<Tree>() + 2 * std::mem::size_of::<Node>()) as u64;
    let bytes = match leaf {
        true => 4 * objs.len() as u64,
        false => 8 * (child + 4 * objs.len() as u64),
    };
    if !budget.spend(bytes) || leaf {
        return Tree::Leaf(objs);
    }
    let split = match o.mode {
        Mode::Center => [0, 1, 2].map(|a| (b.lo[a] + b.hi[a]) * 0.5),
        Mode::Adaptive => [0, 1, 2].map(|a| adaptive_split(b, a, &objs, boxes)),
    };
    let build_child = |i: u32| {
        let cb = child_box(b, split, i);
        let inside: Vec<u32> = objs
            .iter()
            .copied()
            .filter(|&k| cb.overlaps(&boxes[k as usize]))
            .collect();
        subdivide(&cb, inside, boxes, depth + 1, o, budget)
    };
    // Parallel where there is enough work per child to pay for it.
    let children: Vec<Tree> = if objs.len() > 2048 {
        (0..8u32).into_par_iter().map(build_child).collect()
    } else {
        (0..8u32).map(build_child).collect()
    };
    let children: [Tree; 8] = children.try_into().unwrap_or_else(|_| unreachable!("eight children"));
    Tree::Interior(split, Box::new(children))
}

/// Mode A: the cheapest of 10 positions from the spatial median to the
/// object median (median of the objects' box centres) by the Octree-R cost
/// C = (left+cut)(t*2(b+c)+bc) + (right+cut)((a-t)*2(b+c)+bc).
fn adaptive_split(b: &Box3, axis: usize, objs: &[u32], boxes: &[Box3]) -> f32 {
    let spatial = (b.lo[axis] + b.hi[axis]) * 0.5;
    let mut centres: Vec<f32> = objs
        .iter()
        .map(|&k| {
            let o = &boxes[k as usize];
            ((o.lo[axis] + o.hi[axis]) * 0.5).clamp(b.lo[axis], b.hi[axis])
        })
        .collect();
    let mid = centres.len() / 2;
    let object = *centres.select_nth_unstable_by(mid, f32::total_cmp).1;
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let ea = (b.hi[axis] - b.lo[axis]) as f64;
    let eb = (b.hi[u] - b.lo[u]) as f64;
    let ec = (b.hi[v] - b.lo[v]) as f64;
    let mut best = (f64::INFINITY, spatial);
    for i in 0..10 {
        let pos = spatial + (object - spatial) * (i as f32 / 9.0);
        if !(pos > b.lo[axis] && pos < b.hi[axis]) {
            continue;
        }
        let (mut left, mut right, mut cut) = (0u64, 0u64, 0u64);
        for &k in objs {
            let o = &boxes[k as usize];
            if o.hi[axis] < pos {
                left += 1;
            } else if o.lo[axis] > pos {
                right += 1;
            } else {
                cut += 1;
            }
        }
        let t = (pos - b.lo[axis]) as f64;
        let cost = (left + cut) as f64 * (t * 2.0 * (eb + ec) + eb * ec)
            + (right + cut) as f64 * ((ea - t) * 2.0 * (eb + ec) + eb * ec);
        if cost < best.0 {
            best = (cost, pos);
        }
    }
    best.1
}
