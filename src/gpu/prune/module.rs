//! A SPIR-V module read into what pruning works on: the instructions before
//! the functions, and each function's blocks (label, body, merge
//! instruction, terminator). Opcodes are those of the SPIR-V 1.6 unified
//! specification (section 3.52).

// Opcodes (SPIR-V 1.6 unified specification, section 3.52).
pub(super) const OP_NAME: u32 = 5;
pub(super) const OP_ENTRY_POINT: u32 = 15;
pub(super) const OP_TYPE_BOOL: u32 = 20;
pub(super) const OP_TYPE_INT: u32 = 21;
pub(super) const OP_CONSTANT_TRUE: u32 = 41;
pub(super) const OP_CONSTANT_FALSE: u32 = 42;
pub(super) const OP_CONSTANT: u32 = 43;
pub(super) const OP_SPEC_CONSTANT_TRUE: u32 = 48;
pub(super) const OP_SPEC_CONSTANT_FALSE: u32 = 49;
pub(super) const OP_SPEC_CONSTANT: u32 = 50;
pub(super) const OP_SPEC_CONSTANT_OP: u32 = 52;
pub(super) const OP_FUNCTION: u32 = 54;
pub(super) const OP_FUNCTION_END: u32 = 56;
pub(super) const OP_FUNCTION_CALL: u32 = 57;
pub(super) const OP_DECORATE: u32 = 71;
pub(super) const OP_DECORATE_ID: u32 = 332;
pub(super) const OP_DECORATE_STRING: u32 = 5632;
pub(super) const OP_COPY_OBJECT: u32 = 83;
pub(super) const OP_BITCAST: u32 = 124;
pub(super) const OP_SNEGATE: u32 = 126;
pub(super) const OP_IADD: u32 = 128;
pub(super) const OP_ISUB: u32 = 130;
pub(super) const OP_IMUL: u32 = 132;
pub(super) const OP_UDIV: u32 = 134;
pub(super) const OP_UMOD: u32 = 137;
pub(super) const OP_LOGICAL_EQUAL: u32 = 164;
pub(super) const OP_LOGICAL_NOT_EQUAL: u32 = 165;
pub(super) const OP_LOGICAL_OR: u32 = 166;
pub(super) const OP_LOGICAL_AND: u32 = 167;
pub(super) const OP_LOGICAL_NOT: u32 = 168;
pub(super) const OP_SELECT: u32 = 169;
pub(super) const OP_IEQUAL: u32 = 170;
pub(super) const OP_INOT_EQUAL: u32 = 171;
pub(super) const OP_UGREATER_THAN: u32 = 172;
pub(super) const OP_SGREATER_THAN: u32 = 173;
pub(super) const OP_UGREATER_THAN_EQUAL: u32 = 174;
pub(super) const OP_SGREATER_THAN_EQUAL: u32 = 175;
pub(super) const OP_ULESS_THAN: u32 = 176;
pub(super) const OP_SLESS_THAN: u32 = 177;
pub(super) const OP_ULESS_THAN_EQUAL: u32 = 178;
pub(super) const OP_SLESS_THAN_EQUAL: u32 = 179;
pub(super) const OP_SHIFT_RIGHT_LOGICAL: u32 = 194;
pub(super) const OP_SHIFT_RIGHT_ARITHMETIC: u32 = 195;
pub(super) const OP_SHIFT_LEFT_LOGICAL: u32 = 196;
pub(super) const OP_BITWISE_OR: u32 = 197;
pub(super) const OP_BITWISE_XOR: u32 = 198;
pub(super) const OP_BITWISE_AND: u32 = 199;
pub(super) const OP_NOT: u32 = 200;
pub(super) const OP_PHI: u32 = 245;
pub(super) const OP_LOOP_MERGE: u32 = 246;
pub(super) const OP_SELECTION_MERGE: u32 = 247;
pub(super) const OP_LABEL: u32 = 248;
pub(super) const OP_BRANCH: u32 = 249;
pub(super) const OP_BRANCH_CONDITIONAL: u32 = 250;
pub(super) const OP_SWITCH: u32 = 251;
pub(super) const OP_UNREACHABLE: u32 = 255;
pub(super) const DECORATION_SPEC_ID: u32 = 1;

/// One instruction: its words, opcode first.
#[derive(Clone, Copy)]
pub(super) struct Inst<'a>(pub(super) &'a [u32]);

impl<'a> Inst<'a> {
    pub(super) fn op(&self) -> u32 {
        self.0[0] & 0xffff
    }
    pub(super) fn arg(&self, i: usize) -> Option<u32> {
        self.0.get(1 + i).copied()
    }
    /// The result id of an instruction with a result type (ops in
    /// functions and constants alike).
    pub(super) fn result(&self) -> Option<u32> {
        self.arg(1)
    }
}

pub(super) struct Block<'a> {
    pub(super) label: u32,
    /// Everything after OpLabel up to the merge instruction and terminator.
    pub(super) body: Vec<Inst<'a>>,
    pub(super) merge: Option<Inst<'a>>,
    pub(super) terminator: Inst<'a>,
}

pub(super) struct Function<'a> {
    /// OpFunction and its OpFunctionParameters.
    pub(super) head: Vec<Inst<'a>>,
    pub(super) blocks: Vec<Block<'a>>,
    pub(super) end: Inst<'a>,
}

pub(super) struct Module<'a> {
    pub(super) header: &'a [u32],
    /// Every instruction before the first function.
    pub(super) globals: Vec<Inst<'a>>,
    pub(super) functions: Vec<Function<'a>>,
}

impl<'a> Module<'a> {
    pub(super) fn read(words: &'a [u32]) -> Option<Self> {
        if words.len() < 5 || words[0] != 0x0723_0203 {
            return None;
        }
        let mut insts = Vec::new();
        let mut at = 5;
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            if count == 0 || at + count > words.len() {
                return None;
            }
            insts.push(Inst(&words[at..at + count]));
            at += count;
        }
        let first = insts.iter().position(|i| i.op() == OP_FUNCTION).unwrap_or(insts.len());
        let globals = insts[..first].to_vec();
        let mut functions = Vec::new();
        let mut rest = insts[first..].iter().copied().peekable();
        while let Some(op) = rest.next() {
            if op.op() != OP_FUNCTION {
                return None;
            }
            let mut head = vec![op];
            while rest
                .peek()
                .is_some_and(|i| i.op() != OP_LABEL && i.op() != OP_FUNCTION_END)
            {
                head.push(rest.next()?);
            }
            let mut blocks = Vec::new();
            loop {
                let inst = rest.next()?;
                if inst.op() == OP_FUNCTION_END {
                    functions.push(Function {
                        head,
                        blocks,
                        end: inst,
                    });
                    break;
                }
                if inst.op() != OP_LABEL {
                    return None;
                }
                let label = inst.arg(0)?;
                let mut body = Vec::new();
                let mut merge = None;
                let terminator = loop {
                    let i = rest.next()?;
                    match i.op() {
                        OP_LOOP_MERGE | OP_SELECTION_MERGE => merge = Some(i),
                        op if is_terminator(op) => break i,
                        OP_LABEL | OP_FUNCTION_END => return None,
                        _ if merge.is_some() => return None,
                        _ => body.push(i),
                    }
                };
                blocks.push(Block {
                    label,
                    body,
                    merge,
                    terminator,
                });
            }
        }
        // What is left whole: phis without a result, group decorations (a
        // SpecId could hide in one), and switches where a literal may be
        // 64 bits wide (`Block::targets` reads pairs of 32-bit words).
        let wide = globals.iter().any(|i| i.op() == OP_TYPE_INT && i.arg(1) != Some(32));
        let blocks = || functions.iter().flat_map(|f: &Function| &f.blocks);
        if globals.iter().any(|i| matches!(i.op(), 73..=75))
            || blocks().any(|b| {
                b.body
                    .iter()
                    .any(|i| i.op() == OP_PHI && (i.0.len() < 3 || i.0.len() % 2 == 0))
            })
            || (wide && blocks().any(|b| b.terminator.op() == OP_SWITCH))
        {
            return None;
        }
        Some(Module {
            header: &words[..5],
            globals,
            functions,
        })
    }
}

impl Function<'_> {
    pub(super) fn for_each(&self, mut f: impl FnMut(Inst)) {
        self.head.iter().for_each(|&i| f(i));
        for b in &self.blocks {
            f(Inst(&[(2 << 16) | OP_LABEL, b.label]));
            b.body.iter().chain(&b.merge).for_each(|&i| f(i));
            f(b.terminator);
        }
    }
}

impl Block<'_> {
    /// Every label the terminator may branch to.
    pub(super) fn targets(&self) -> Vec<u32> {
        let t = self.terminator;
        match t.op() {
            OP_BRANCH => t.arg(0).into_iter().collect(),
            OP_BRANCH_CONDITIONAL => [t.arg(1), t.arg(2)].into_iter().flatten().collect(),
            // Selector, default, then (literal, label) pairs of 32-bit literals.
            OP_SWITCH => {
                let mut v: Vec<u32> = t.arg(1).into_iter().collect();
                v.extend(t.0.get(3..).unwrap_or(&[]).chunks(2).filter_map(|c| c.get(1).copied()));
                v
            }
            _ => Vec::new(),
        }
    }
}

pub(super) fn is_terminator(op: u32) -> bool {
    // Branch, conditional branch, switch, kill, return, return value,
    // unreachable; terminate invocation, ignore intersection, terminate ray.
    (OP_BRANCH..=OP_UNREACHABLE).contains(&op) || matches!(op, 4416 | 4448 | 4449)
}

/// Names and decorations of an id (its first operand).
pub(super) fn is_annotation(op: u32) -> bool {
    matches!(op, OP_NAME | OP_DECORATE | OP_DECORATE_ID | OP_DECORATE_STRING)
}

/// The id an instruction before the functions defines: strings, imports,
/// types and decoration groups their first operand; constants, variables
/// and undefs their second, after the result type.
pub(super) fn global_result(inst: Inst) -> Option<u32> {
    match inst.op() {
        // OpSourceContinued, OpSource, OpSourceExtension, OpName,
        // OpMemberName, OpLine, OpExtension, OpMemoryModel, OpEntryPoint,
        // OpExecutionMode, OpCapability, decorations, OpModuleProcessed,
        // OpExecutionModeId.
        2..=6 | 8 | 10 | 14..=17 | 71 | 72 | 74..=76 | 330..=332 | 5632 | 5633 => None,
        7 | 11 | 19..=39 | 73 => inst.arg(0),
        _ => inst.arg(1),
    }
}

/// Calls `f` on each instruction of `words` (a function section).
pub(super) fn for_each_in(words: &[u32], mut f: impl FnMut(Inst)) {
    let mut at = 0;
    while at < words.len() {
        let count = ((words[at] >> 16) as usize).max(1);
        f(Inst(&words[at..(at + count).min(words.len())]));
        at += count;
    }
}

/// The id an instruction in a function defines: a label its first operand,
/// the rest that define one (all but stores, barriers, writes, merges and
/// terminators) their second, after the result type.
pub(super) fn function_result(inst: Inst) -> Option<u32> {
    match inst.op() {
        OP_LABEL => inst.arg(0),
        // Nop, line, store, copy memory (sized), image write, emit and end
        // (stream) vertex and primitive, control and memory barrier, atomic
        // store, merges, terminators, lifetime start and stop, no line,
        // terminate invocation, demote to helper.
        0 | 8 | 62 | 63 | 64 | 99 | 218..=221 | 224 | 225 | 228 | OP_LOOP_MERGE | OP_SELECTION_MERGE => None,
        OP_BRANCH..=OP_UNREACHABLE | 256 | 257 | 317 | 4416 | 4448 | 4449 | 5380 => None,
        _ => inst.arg(1),
    }
}
