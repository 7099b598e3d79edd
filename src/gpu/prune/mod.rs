//! Prunes from a kernel's SPIR-V the code its specialization constants rule
//! out, before the driver sees it. The march shaders hold every look, filter,
//! storage and output in one module and choose among them by specialization
//! constants; a driver that inlines and lowers the whole module before it
//! folds the constants (lavapipe does) spends most of a pipeline creation on
//! code no frame of that kernel runs. Here a branch whose condition the
//! constants decide becomes a plain branch, the blocks no longer reached go,
//! and so do the functions no longer called. Nothing else changes: the
//! constants stay specialization constants (the driver applies the same
//! values), and every instruction that computes a value is left as the
//! compiler emitted it (only branches, merge instructions and the parents a
//! phi lists change), so a pruned kernel computes what the whole one does,
//! bit for bit.
//!
//! What it decides is deliberately little: 32-bit integer and boolean
//! arithmetic on constants (comparisons, logic, bitwise ops, shifts, add,
//! sub, mul, div, select, phis whose live incoming values agree). A module it
//! cannot read is handed on whole.

mod fold;
mod module;

use fold::{evaluate, phi_value, Known};
use module::*;
use std::collections::{HashMap, HashSet};

/// `words` with what `constants` (`(constant_id, value)`, the others at
/// their defaults) rule out removed; `words` itself when it cannot be read.
pub(crate) fn prune(words: &[u32], constants: &[(u32, u32)]) -> Vec<u32> {
    Module::read(words)
        .and_then(|m| m.pruned(constants))
        .unwrap_or_else(|| words.to_vec())
}

impl Module<'_> {
    /// The constants the globals define, with `constants` applied, and the
    /// 32-bit integer and boolean types (the only values folded).
    fn known(&self, constants: &[(u32, u32)]) -> (Known, HashSet<u32>) {
        let spec_ids: HashMap<u32, u32> = self
            .globals
            .iter()
            .filter(|i| i.op() == OP_DECORATE && i.arg(1) == Some(DECORATION_SPEC_ID))
            .filter_map(|i| Some((i.arg(0)?, i.arg(2)?)))
            .collect();
        let value_of = |id: u32| {
            let spec = spec_ids.get(&id)?;
            // The first entry, as `Shader::local_size_for` reads them.
            constants.iter().find(|(c, _)| c == spec).map(|&(_, v)| v)
        };
        let mut scalar = HashSet::new();
        let mut known = Known::new();
        for inst in &self.globals {
            match inst.op() {
                OP_TYPE_BOOL => {
                    scalar.extend(inst.arg(0));
                }
                OP_TYPE_INT if inst.arg(1) == Some(32) => {
                    scalar.extend(inst.arg(0));
                }
                OP_CONSTANT_TRUE | OP_CONSTANT_FALSE => {
                    if let Some(id) = inst.result() {
                        known.insert(id, (inst.op() == OP_CONSTANT_TRUE) as u32);
                    }
                }
                OP_SPEC_CONSTANT_TRUE | OP_SPEC_CONSTANT_FALSE => {
                    if let Some(id) = inst.result() {
                        let default = (inst.op() == OP_SPEC_CONSTANT_TRUE) as u32;
                        known.insert(id, value_of(id).map_or(default, |v| (v != 0) as u32));
                    }
                }
                OP_CONSTANT | OP_SPEC_CONSTANT if inst.0.len() == 4 && scalar.contains(&inst.0[1]) => {
                    let id = inst.0[2];
                    let value = match inst.op() {
                        OP_SPEC_CONSTANT => value_of(id).unwrap_or(inst.0[3]),
                        _ => inst.0[3],
                    };
                    known.insert(id, value);
                }
                // Result type, result, opcode, operands: evaluated as the op.
                OP_SPEC_CONSTANT_OP if inst.0.len() >= 4 && scalar.contains(&inst.0[1]) => {
                    if let Some(v) = evaluate(inst.0[3], &inst.0[4..], &known) {
                        known.insert(inst.0[2], v);
                    }
                }
                _ => {}
            }
        }
        (known, scalar)
    }

    /// None where a loop would lose its continue target while its header
    /// has phis (glslang emits none there), which this does not rewrite.
    fn pruned(&self, constants: &[(u32, u32)]) -> Option<Vec<u32>> {
        let (known, scalar) = self.known(constants);
        let loop_headers: HashSet<u32> = self
            .functions
            .iter()
            .flat_map(|f| &f.blocks)
            .filter(|b| b.merge.is_some_and(|m| m.op() == OP_LOOP_MERGE))
            .map(|b| b.label)
            .collect();
        let live: Vec<LiveFunction> = self
            .functions
            .iter()
            .map(|f| f.live(&known, &scalar, &loop_headers))
            .collect();
        // Functions no live block calls (entry points always live).
        let ids: HashMap<u32, usize> = self
            .functions
            .iter()
            .enumerate()
            .filter_map(|(i, f)| Some((f.head[0].result()?, i)))
            .collect();
        let mut called = vec![false; self.functions.len()];
        let mut stack: Vec<usize> = self
            .globals
            .iter()
            .filter(|i| i.op() == OP_ENTRY_POINT)
            .filter_map(|i| ids.get(&i.arg(1)?).copied())
            .collect();
        while let Some(f) = stack.pop() {
            if std::mem::replace(&mut called[f], true) {
                continue;
            }
            for b in &self.functions[f].blocks {
                if !live[f].reached.contains(&b.label) {
                    continue;
                }
                for inst in b.body.iter().filter(|i| i.op() == OP_FUNCTION_CALL) {
                    if let Some(&callee) = inst.arg(2).and_then(|id| ids.get(&id)) {
                        stack.push(callee);
                    }
                }
            }
        }
        let mut body = Vec::new();
        for ((f, l), _) in self.functions.iter().zip(&live).zip(&called).filter(|(_, &c)| c) {
            f.write(l, &mut body)?;
        }
        // Names and decorations of the values that went with their code.
        let mut gone = HashSet::new();
        for f in &self.functions {
            f.for_each(|inst| gone.extend(function_result(inst)));
        }
        for_each_in(&body, |inst| {
            if let Some(id) = function_result(inst) {
                gone.remove(&id);
            }
        });
        // Never a global's: an opcode `function_result` does not know to have
        // no result would name an operand (a global, say) as its result.
        for inst in &self.globals {
            if let Some(id) = global_result(*inst) {
                gone.remove(&id);
            }
        }
        let mut out = self.header.to_vec();
        for inst in &self.globals {
            let target = is_annotation(inst.op()).then(|| inst.arg(0)).flatten();
            if !target.is_some_and(|t| gone.contains(&t)) {
                out.extend_from_slice(inst.0);
            }
        }
        out.extend(body);
        Some(out)
    }
}

/// What of a function is live: the blocks reached, the branches decided
/// and the edges taken.
struct LiveFunction {
    reached: HashSet<u32>,
    /// Blocks whose branch the constants decide: the one target taken.
    decided: HashMap<u32, u32>,
    /// The edges (from, to) taken out of reached blocks: the parents a
    /// phi keeps.
    edges: HashSet<(u32, u32)>,
}

impl Function<'_> {
    /// The blocks reached from the entry when branches the constants decide
    /// take their one way; to a fixed point, as a phi fed only by reached
    /// blocks may decide a branch further on.
    fn live(&self, globals: &Known, scalar: &HashSet<u32>, loop_headers: &HashSet<u32>) -> LiveFunction {
        let index: HashMap<u32, usize> = self.blocks.iter().enumerate().map(|(i, b)| (b.label, i)).collect();
        let mut known = globals.clone();
        loop {
            let mut decided = HashMap::new();
            let mut reached = HashSet::new();
            let mut stack: Vec<usize> = self.blocks.first().map(|_| 0).into_iter().collect();
            let mut edges: HashSet<(u32, u32)> = HashSet::new();
            while let Some(b) = stack.pop() {
                let block = &self.blocks[b];
                if !reached.insert(block.label) {
                    continue;
                }
                let targets = block.successors(&known, loop_headers);
                if let Some(&only) = targets.decided.as_ref() {
                    decided.insert(block.label, only);
                }
                for t in targets.all {
                    edges.insert((block.label, t));
                    if let Some(&i) = index.get(&t) {
                        stack.push(i);
                    }
                }
            }
            let before = known.len();
            for block in self.blocks.iter().filter(|b| reached.contains(&b.label)) {
                for inst in &block.body {
                    let Some(id) = inst.result() else { continue };
                    // 32-bit scalars only: a bitcast to a vector of halves,
                    // say, is no one 32-bit value to add or shift.
                    if known.contains_key(&id) || !inst.arg(0).is_some_and(|t| scalar.contains(&t)) {
                        continue;
                    }
                    let value = match inst.op() {
                        OP_PHI => phi_value(inst, block.label, &edges, &known),
                        op => inst.0.get(3..).and_then(|operands| evaluate(op, operands, &known)),
                    };
                    if let Some(v) = value {
                        known.insert(id, v);
                    }
                }
            }
            if known.len() == before {
                return LiveFunction {
                    reached,
                    decided,
                    edges,
                };
            }
        }
    }

    fn write(&self, live: &LiveFunction, out: &mut Vec<u32>) -> Option<()> {
        for inst in &self.head {
            out.extend_from_slice(inst.0);
        }
        // Merge and continue targets of live headers stay, reached or not:
        // a header names them. One not reached keeps only a terminator.
        let mut named: HashMap<u32, Option<u32>> = HashMap::new();
        for b in self.blocks.iter().filter(|b| live.reached.contains(&b.label)) {
            let Some(merge) = b.merge else { continue };
            if live.decided.contains_key(&b.label) && merge.op() == OP_SELECTION_MERGE {
                continue;
            }
            named.entry(merge.arg(0)?).or_insert(None);
            if merge.op() == OP_LOOP_MERGE {
                let target = merge.arg(1)?;
                // Its branch back would be a parent the header's phis lack.
                if !live.reached.contains(&target) && b.body.iter().any(|i| i.op() == OP_PHI) {
                    return None;
                }
                named.insert(target, Some(b.label));
            }
        }
        for b in &self.blocks {
            if live.reached.contains(&b.label) {
                out.extend([(2 << 16) | OP_LABEL, b.label]);
                for inst in &b.body {
                    if inst.op() == OP_PHI {
                        write_phi(inst, b.label, &live.edges, out);
                    } else {
                        out.extend_from_slice(inst.0);
                    }
                }
                match live.decided.get(&b.label) {
                    // A selection header decided (`successors`): its merge goes.
                    Some(&to) => out.extend([(2 << 16) | OP_BRANCH, to]),
                    None => {
                        if let Some(m) = b.merge {
                            out.extend_from_slice(m.0);
                        }
                        out.extend_from_slice(b.terminator.0);
                    }
                }
            } else if let Some(header) = named.get(&b.label) {
                out.extend([(2 << 16) | OP_LABEL, b.label]);
                match header {
                    // A continue target not reached branches back to its header.
                    Some(h) => out.extend([(2 << 16) | OP_BRANCH, *h]),
                    None => out.push((1 << 16) | OP_UNREACHABLE),
                }
            }
        }
        out.extend_from_slice(self.end.0);
        Some(())
    }
}

struct Successors {
    all: Vec<u32>,
    decided: Option<u32>,
}

impl Block<'_> {
    /// The labels this block may branch to given `known`, and the one it
    /// takes when the constants decide it. Left as they are: a loop header's
    /// branch (its merge instruction stays where it is), a branch that may
    /// be a loop's back edge unless it goes back (a loop keeps its one back
    /// edge), and a switch (a case's `break` branches to the switch's merge,
    /// a structured exit only while the switch stays a construct).
    fn successors(&self, known: &Known, loop_headers: &HashSet<u32>) -> Successors {
        let t = self.terminator;
        let is_header = self.merge.is_some_and(|m| m.op() == OP_LOOP_MERGE);
        let decided = match t.op() {
            OP_BRANCH_CONDITIONAL if !is_header => t
                .arg(0)
                .and_then(|c| known.get(&c))
                .and_then(|&c| if c != 0 { t.arg(1) } else { t.arg(2) })
                .filter(|to| loop_headers.contains(to) || !self.targets().iter().any(|t| loop_headers.contains(t))),
            _ => None,
        };
        match decided {
            Some(only) => Successors {
                all: vec![only],
                decided: Some(only),
            },
            None => Successors {
                all: self.targets(),
                decided: None,
            },
        }
    }
}

/// A phi with the pairs of parents that no longer branch here left out
/// (`Module::read` refused phis shorter than a result).
fn write_phi(inst: &Inst, block: u32, preds: &HashSet<(u32, u32)>, out: &mut Vec<u32>) {
    let pairs: Vec<&[u32]> = inst.0[3..]
        .chunks(2)
        .filter(|p| p.len() == 2 && preds.contains(&(p[1], block)))
        .collect();
    out.push(((3 + 2 * pairs.len() as u32) << 16) | OP_PHI);
    out.extend_from_slice(&inst.0[1..3]);
    for p in pairs {
        out.extend_from_slice(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders;

    fn names(words: &[u32]) -> HashSet<String> {
        let m = Module::read(words).expect("readable");
        m.globals
            .iter()
            .filter(|i| i.op() == OP_NAME)
            .map(|i| {
                let bytes: Vec<u8> = i.0[2..].iter().flat_map(|w| w.to_le_bytes()).collect();
                String::from_utf8_lossy(bytes.split(|&c| c == 0).next().unwrap_or(&[])).into_owned()
            })
            .collect()
    }

    fn functions(words: &[u32]) -> usize {
        Module::read(words).expect("readable").functions.len()
    }

    #[test]
    fn every_shader_reads_and_writes_back_whole_when_nothing_is_decided() {
        for s in shaders::ALL {
            let m = Module::read(s.words).unwrap_or_else(|| panic!("{} reads", s.name));
            let mut back = m.header.to_vec();
            for g in &m.globals {
                back.extend_from_slice(g.0);
            }
            for f in &m.functions {
                let all = LiveFunction {
                    reached: f.blocks.iter().map(|b| b.label).collect(),
                    decided: HashMap::new(),
                    edges: f
                        .blocks
                        .iter()
                        .flat_map(|b| b.targets().into_iter().map(move |t| (b.label, t)))
                        .collect(),
                };
                f.write(&all, &mut back);
            }
            assert_eq!(back, s.words, "{}", s.name);
        }
    }

    #[test]
    fn an_unlit_composite_march_loses_the_lighting_and_the_other_looks() {
        let naive = shaders::MARCH_NAIVE;
        // Defaults: composite, unlit, one channel, no counting.
        let pruned = prune(naive.words, &[]);
        assert!(
            pruned.len() * 10 < naive.words.len() * 8,
            "{} of {}",
            pruned.len(),
            naive.words.len()
        );
        assert!(functions(&pruned) < functions(naive.words));
        let kept = names(&pruned);
        for gone in ["iso_refine(struct-March", "light_sample(", "count_naive("] {
            assert!(!kept.iter().any(|n| n.starts_with(gone)), "{gone} kept");
        }
        assert!(kept.iter().any(|n| n.starts_with("take_sample(")));
        // Lit (MARCH_SHADE, id 18): the lighting stays.
        let lit = names(&prune(naive.words, &[(18, 1)]));
        assert!(lit.iter().any(|n| n.starts_with("light_sample(")));
    }

    #[test]
    fn a_module_it_cannot_read_is_handed_on_whole() {
        let bad = [0x0723_0203, 0x0001_0000, 0, 10, 0, 0x0005_0000];
        assert_eq!(prune(&bad, &[]), bad);
        assert_eq!(prune(&[1, 2, 3], &[]), vec![1, 2, 3]);
    }

    #[test]
    fn folds_integer_and_boolean_ops_on_known_ids() {
        let known: Known = [(1, 6), (2, 4), (3, 1), (4, 0)].into_iter().collect();
        assert_eq!(evaluate(OP_BITWISE_AND, &[1, 2], &known), Some(4));
        assert_eq!(evaluate(OP_INOT_EQUAL, &[1, 2], &known), Some(1));
        assert_eq!(evaluate(OP_LOGICAL_AND, &[3, 4], &known), Some(0));
        assert_eq!(evaluate(OP_SELECT, &[4, 1, 2], &known), Some(4));
        assert_eq!(evaluate(OP_UDIV, &[1, 4], &known), None);
        assert_eq!(evaluate(OP_IADD, &[1, 9], &known), None);
        assert_eq!(evaluate(5000, &[1, 2], &known), None);
    }
}
