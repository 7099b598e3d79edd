//! CPU reference of the four octree traversals, written to mirror
//! `glsl/common/octree_traverse.glsl` step for step: same float operations in
//! the same order, same tie rules, same counters. Leaves are handed to a
//! visitor in ray order with their t-span; it returns true to stop.
//!
//! Counters per ray (`Counters`):
//! - N_TS (`steps`): for `84`, interior nodes passed by each point location
//!   from the root; for `89`, nodes moved up to while looking for the nearest
//!   common ancestor plus interior nodes passed below it (the first location
//!   as in `84`); for `93` and `rev`, interior nodes whose children are
//!   enumerated.
//! - N_ETS (`leaves`) leaves visited, N_EETS (`empty_leaves`) empty ones.
//!
//! Geometry that all four share: a direction component below 1e-20 in
//! magnitude is replaced by +-1e-20 pointing to the root's centre (so plane
//! crossings are finite and rays in a root face stay inside), every
//! crossing is t = (plane - o) / d, and a point exactly on a split plane
//! belongs to the side the ray is heading to. Glassner and Samet step from a
//! leaf to the next by the exit point: its exit-face coordinates are set to
//! the face exactly (ties outwards) and the others clamped into the leaf
//! (ties inwards), so no epsilon nudge is needed and every step advances to a
//! true neighbour.
//!
//! Gargantini & Atkinson and Revelles are recursive algorithms; here they run
//! without a stack: returning from a child climbs the parent link and
//! recomputes the parent's t-values from its box (a child's bounds are its
//! parent's split values, so these are the values the recursion would have
//! passed down). Stacks in private arrays indexed at run time are what GPUs
//! and llvmpipe handle worst.

// Index loops and negated comparisons (NaN-aware) keep the code line for line
// with the GLSL it must match bit for bit.
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

use super::octree_node::{axis_bit, Node};
use std::fmt;
use std::str::FromStr;

/// The octree traversal algorithms compared.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Traversal {
    /// Glassner 1984: point location from the root for every leaf.
    O84,
    /// Samet 1989: neighbour finding through the nearest common ancestor.
    O89,
    /// Gargantini & Atkinson 1993: recursive, sorted split-plane crossings.
    O93,
    /// Revelles, Ureña & Lastra 2000: parametric, table driven.
    Rev,
}

impl Traversal {
    pub const ALL: [Traversal; 4] = [Traversal::O84, Traversal::O89, Traversal::O93, Traversal::Rev];

    pub fn name(self) -> &'static str {
        match self {
            Traversal::O84 => "84",
            Traversal::O89 => "89",
            Traversal::O93 => "93",
            Traversal::Rev => "rev",
        }
    }

    /// The specialization constant the GLSL traversal switches on.
    pub fn id(self) -> u32 {
        self as u32
    }
}

impl fmt::Display for Traversal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Traversal {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        Traversal::ALL
            .into_iter()
            .find(|t| t.name() == s)
            .ok_or_else(|| crate::Error::invalid("octree traversal", s, "expected 84, 89, 93 or rev"))
    }
}

/// What a traversal visited for one ray.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub steps: u32,
    pub leaves: u32,
    pub empty_leaves: u32,
}

/// The smallest direction component in magnitude a traversal divides by
/// (`safe_dir` raises smaller ones to it).
pub const TINY: f32 = 1e-20;
const BIG: f32 = 3.4e38;
/// Iteration guard for the point-stepping traversals.
const GUARD: u32 = 1 << 20;

/// Direction with no component smaller than TINY in magnitude. A vanishing
/// component points towards the root's centre, so a ray lying in a face of
/// the root (closed, as the renderers' box tests are) still runs inside it.
pub fn safe_dir(d: [f32; 3], o: [f32; 3], root: &Node) -> [f32; 3] {
    let mut r = d;
    for a in 0..3 {
        if d[a].abs() < TINY {
            r[a] = if o[a] >= (root.lo[a] + root.hi[a]) * 0.5 {
                -TINY
            } else {
                TINY
            };
        }
    }
    r
}

struct Walk<'a, V> {
    nodes: &'a [Node],
    o: [f32; 3],
    d: [f32; 3],
    tmin: f32,
    tmax: f32,
    c: Counters,
    visit: V,
}

/// Traverses `nodes` (root at 0) along o + t d for t in [tmin, tmax].
pub fn traverse<V: FnMut(&Node, f32, f32) -> bool>(
    nodes: &[Node],
    kind: Traversal,
    o: [f32; 3],
    d: [f32; 3],
    tmin: f32,
    tmax: f32,
    visit: V,
) -> Counters {
    let mut w = Walk {
        nodes,
        o,
        d: safe_dir(d, o, &nodes[0]),
        tmin,
        tmax,
        c: Counters::default(),
        visit,
    };
    match kind {
        Traversal::O84 => w.stepping(false),
        Traversal::O89 => w.stepping(true),
        Traversal::O93 => w.o93(),
        Traversal::Rev => w.rev(),
    }
    w.c
}

impl<V: FnMut(&Node, f32, f32) -> bool> Walk<'_, V> {
    fn cross(&self, plane: f32, a: usize) -> f32 {
        (plane - self.o[a]) / self.d[a]
    }

    /// A node's plane crossings (Revelles' parameters): per axis the t of
    /// its near plane (t0) and far plane (t1) along the ray. A child's box
    /// bounds are its parent's split values, so these equal the values the
    /// recursive formulation passes down.
    fn plane_params(&self, n: &Node) -> ([f32; 3], [f32; 3]) {
        let mut t0 = [0.0f32; 3];
        let mut t1 = [0.0f32; 3];
        for a in 0..3 {
            let ta = self.cross(n.lo[a], a);
            let tb = self.cross(n.hi[a], a);
            if self.d[a] > 0.0 {
                t0[a] = ta;
                t1[a] = tb;
            } else {
                t0[a] = tb;
                t1[a] = ta;
            }
        }
        (t0, t1)
    }

    /// The node's t-span: (largest near crossing, smallest far crossing).
    fn span(&self, n: &Node) -> (f32, f32) {
        let (t0, t1) = self.plane_params(n);
        (max3(t0), min3(t1))
    }

    /// Leaf visit with its counters; true to stop.
    fn leaf(&mut self, index: u32, t0: f32, t1: f32) -> bool {
        let n = &self.nodes[index as usize];
        self.c.leaves += 1;
        if n.count() == 0 {
            self.c.empty_leaves += 1;
        }
        (self.visit)(n, t0, t1)
    }

    /// Child of `n` holding `p`; a coordinate on a split plane goes to the
    /// side `high` names for its axis.
    fn child_at(&self, n: &Node, p: [f32; 3], high: [bool; 3]) -> u32 {
        let mut child = 0;
        for a in 0..3 {
            if p[a] > n.split[a] || (p[a] == n.split[a] && high[a]) {
                child |= axis_bit(a);
            }
        }
        n.first() + child
    }

    /// Point location downwards from `node`; `count_start` counts `node` itself.
    fn locate(&mut self, mut node: u32, p: [f32; 3], high: [bool; 3], count_start: bool) -> u32 {
        let mut first = true;
        while !self.nodes[node as usize].is_leaf() {
            if !first || count_start {
                self.c.steps += 1;
            }
            first = false;
            node = self.child_at(&self.nodes[node as usize], p, high);
        }
        node
    }

    /// Whether `n` holds `p` under the same tie rule as `child_at`.
    fn contains(n: &Node, p: [f32; 3], high: [bool; 3]) -> bool {
        (0..3).all(|a| {
            !(p[a] < n.lo[a] || p[a] > n.hi[a] || (p[a] == n.hi[a] && high[a]) || (p[a] == n.lo[a] && !high[a]))
        })
    }

    /// Glassner (`neighbours` false) and Samet (true). The next point lies on
    /// the leaf's exit faces (set exactly, ties towards the outside) and
    /// within the leaf's range on the other axes (clamped, ties towards the
    /// inside), so the next leaf is always a true neighbour beyond this one.
    fn stepping(&mut self, neighbours: bool) {
        let root = self.nodes[0];
        let (t_in, t_out) = self.span(&root);
        let mut t = t_in.max(self.tmin);
        let end = t_out.min(self.tmax);
        if !(t <= end) {
            return;
        }
        let mut p = [0.0f32; 3];
        let mut high = [false; 3];
        for a in 0..3 {
            p[a] = (self.o[a] + self.d[a] * t).clamp(root.lo[a], root.hi[a]);
            high[a] = self.d[a] > 0.0;
        }
        let mut node = self.locate(0, p, high, true);
        for _ in 0..GUARD {
            let n = self.nodes[node as usize];
            let mut far = [0.0f32; 3];
            let mut exit = BIG;
            for a in 0..3 {
                far[a] = if self.d[a] > 0.0 { n.hi[a] } else { n.lo[a] };
                exit = exit.min(self.cross(far[a], a));
            }
            let exit = exit.max(t);
            if self.leaf(node, t, exit.min(end)) || exit >= end {
                return;
            }
            for a in 0..3 {
                if self.cross(far[a], a) <= exit {
                    p[a] = far[a];
                    high[a] = self.d[a] > 0.0;
                } else {
                    let v = self.o[a] + self.d[a] * exit;
                    if v >= n.hi[a] {
                        p[a] = n.hi[a];
                        high[a] = false;
                    } else if v <= n.lo[a] {
                        p[a] = n.lo[a];
                        high[a] = true;
                    } else {
                        p[a] = v;
                        high[a] = self.d[a] > 0.0;
                    }
                }
            }
            t = exit;
            if neighbours {
                let mut up = node;
                loop {
                    if up == 0 {
                        return;
                    }
                    up = self.nodes[up as usize].parent();
                    self.c.steps += 1;
                    if Self::contains(&self.nodes[up as usize], p, high) {
                        break;
                    }
                }
                node = self.locate(up, p, high, false);
            } else {
                if !Self::contains(&root, p, high) {
                    return;
                }
                node = self.locate(0, p, high, true);
            }
        }
    }

    /// A node's t-span from its box, clipped to [tmin, tmax]: the interval
    /// the recursive formulation hands down (a child's bounds are its
    /// parent's split values, and every crossing is computed alike).
    fn clipped_span(&self, n: &Node) -> (f32, f32) {
        let (t0, t1) = self.span(n);
        (t0.max(self.tmin), t1.min(self.tmax))
    }

    /// Gargantini & Atkinson's step: the children of `n` pierced in
    /// (ta, tb) come in ray order from the sorted crossings of its split
    /// planes (zero-length pieces skipped; equal crossings in axis order).
    /// Returns the child (0..8) after `from`, or the first when `from` is
    /// NONE, or NONE after the last.
    fn o93_next(&self, n: &Node, ta: f32, tb: f32, from: u32) -> u32 {
        const NONE: u32 = u32::MAX;
        let mut child = 0u32;
        let mut tm = [0.0f32; 3];
        let mut pending = [false; 3];
        for a in 0..3 {
            tm[a] = self.cross(n.split[a], a);
            let high = if self.d[a] > 0.0 { tm[a] <= ta } else { tm[a] > ta };
            if high {
                child |= axis_bit(a);
            }
            pending[a] = tm[a] > ta && tm[a] < tb;
        }
        let mut take = from == NONE;
        let mut start = ta;
        for _ in 0..4 {
            let mut tc = tb;
            let mut axis = 3;
            for a in 0..3 {
                if pending[a] && (axis == 3 || tm[a] < tc) {
                    tc = tm[a];
                    axis = a;
                }
            }
            if axis == 3 || tc > start {
                if take {
                    return child;
                }
                take = child == from;
            }
            if axis == 3 {
                return NONE;
            }
            child ^= axis_bit(axis);
            pending[axis] = false;
            start = tc;
        }
        NONE
    }

    /// Gargantini & Atkinson 1993, without a stack: returning from a child
    /// climbs the parent link, recomputes the parent's pierced children and
    /// moves to the one after.
    fn o93(&mut self) {
        const NONE: u32 = u32::MAX;
        let (ta, tb) = self.clipped_span(&self.nodes[0]);
        if !(ta <= tb) {
            return;
        }
        let mut node = 0u32;
        let mut from = NONE;
        loop {
            let n = self.nodes[node as usize];
            let (ta, tb) = self.clipped_span(&n);
            let mut next = NONE;
            if from == NONE {
                if n.is_leaf() {
                    if self.leaf(node, ta, tb) {
                        return;
                    }
                } else {
                    self.c.steps += 1;
                    next = self.o93_next(&n, ta, tb, NONE);
                }
            } else {
                next = self.o93_next(&n, ta, tb, from);
            }
            if next != NONE {
                node = n.first() + next;
                from = NONE;
                continue;
            }
            if node == 0 {
                return;
            }
            let parent = n.parent();
            from = node - self.nodes[parent as usize].first();
            node = parent;
        }
    }

    /// Revelles et al.'s parametric traversal, without a stack: returning
    /// from a child climbs the parent link and recomputes the parent's
    /// parameters from its box, then new_node picks the next child.
    fn rev(&mut self) {
        const NONE: u32 = u32::MAX;
        let mut mask = 0u32;
        for a in 0..3 {
            if self.d[a] <= 0.0 {
                mask |= axis_bit(a);
            }
        }
        let (t0, t1) = self.plane_params(&self.nodes[0]);
        if max3(t0) > min3(t1) {
            return;
        }
        let mut node = 0u32;
        // The child (actual index) we return from, or NONE when entering.
        let mut from = NONE;
        loop {
            let n = self.nodes[node as usize];
            let (t0, t1) = self.plane_params(&n);
            let mut next = NONE;
            if from == NONE {
                let enter = max3(t0);
                let exit = min3(t1);
                if !(exit < self.tmin || enter > self.tmax) {
                    if n.is_leaf() {
                        if self.leaf(node, enter.max(self.tmin), exit.min(self.tmax)) {
                            return;
                        }
                    } else {
                        self.c.steps += 1;
                        let mut tm = [0.0f32; 3];
                        for (a, v) in tm.iter_mut().enumerate() {
                            *v = self.cross(n.split[a], a);
                        }
                        next = first_child(t0, tm);
                    }
                }
            } else {
                let c = from ^ mask;
                let mut t1c = [0.0f32; 3];
                for a in 0..3 {
                    t1c[a] = if c & axis_bit(a) != 0 {
                        t1[a]
                    } else {
                        self.cross(n.split[a], a)
                    };
                }
                let axis = exit_axis(t1c);
                if c & axis_bit(axis) == 0 {
                    next = c | axis_bit(axis);
                }
            }
            if next != NONE {
                node = n.first() + (next ^ mask);
                from = NONE;
                continue;
            }
            if node == 0 {
                return;
            }
            let parent = n.parent();
            from = node - self.nodes[parent as usize].first();
            node = parent;
        }
    }
}

fn max3(v: [f32; 3]) -> f32 {
    v[0].max(v[1]).max(v[2])
}

fn min3(v: [f32; 3]) -> f32 {
    v[0].min(v[1]).min(v[2])
}

/// Revelles' first_node: the entry plane is the largest t0 (ties to the
/// earlier axis); the child is on the far side of each other axis whose
/// mid-plane is crossed before entry.
fn first_child(t0: [f32; 3], tm: [f32; 3]) -> u32 {
    let mut plane = 0;
    let mut m = t0[0];
    if t0[1] > m {
        plane = 1;
        m = t0[1];
    }
    if t0[2] > m {
        plane = 2;
        m = t0[2];
    }
    let mut c = 0;
    for a in 0..3 {
        if a != plane && tm[a] < m {
            c |= axis_bit(a);
        }
    }
    c
}

/// Revelles' new_node exit plane: the smallest t1 (ties to the later axis).
fn exit_axis(t1: [f32; 3]) -> usize {
    if t1[0] < t1[1] {
        if t1[0] < t1[2] {
            return 0;
        }
    } else if t1[1] < t1[2] {
        return 1;
    }
    2
}
