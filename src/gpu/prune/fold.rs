//! Folding what the constants decide: 32-bit integer and boolean operations
//! on known ids, and phis whose live incoming values agree.

use super::module::*;
use std::collections::{HashMap, HashSet};

/// What is known of an id: its 32-bit pattern (booleans 0 or 1).
pub(super) type Known = HashMap<u32, u32>;

/// A phi's value when every incoming value from a live edge is known and
/// the same.
pub(super) fn phi_value(inst: &Inst, block: u32, edges: &HashSet<(u32, u32)>, known: &Known) -> Option<u32> {
    let mut value = None;
    for pair in inst.0.get(3..)?.chunks(2) {
        let [v, parent] = *pair else { return None };
        if !edges.contains(&(parent, block)) {
            continue;
        }
        let v = *known.get(&v)?;
        if value.is_some_and(|w| w != v) {
            return None;
        }
        value = Some(v);
    }
    value
}

/// `op` on `operands` (ids), when every one is known and `op` is one of the
/// 32-bit integer or boolean operations folded here.
pub(super) fn evaluate(op: u32, operands: &[u32], known: &Known) -> Option<u32> {
    let arg = |i: usize| operands.get(i).and_then(|id| known.get(id)).copied();
    let b = |x: bool| x as u32;
    Some(match op {
        OP_COPY_OBJECT | OP_BITCAST => arg(0)?,
        OP_LOGICAL_NOT => b(arg(0)? == 0),
        OP_NOT => !arg(0)?,
        OP_SNEGATE => (arg(0)? as i32).wrapping_neg() as u32,
        OP_SELECT => {
            if arg(0)? != 0 {
                arg(1)?
            } else {
                arg(2)?
            }
        }
        _ => {
            let (x, y) = (arg(0)?, arg(1)?);
            let (sx, sy) = (x as i32, y as i32);
            match op {
                OP_IADD => x.wrapping_add(y),
                OP_ISUB => x.wrapping_sub(y),
                OP_IMUL => x.wrapping_mul(y),
                OP_UDIV => x.checked_div(y)?,
                OP_UMOD => x.checked_rem(y)?,
                OP_LOGICAL_EQUAL => b((x != 0) == (y != 0)),
                OP_LOGICAL_NOT_EQUAL => b((x != 0) != (y != 0)),
                OP_LOGICAL_OR => b(x != 0 || y != 0),
                OP_LOGICAL_AND => b(x != 0 && y != 0),
                OP_IEQUAL => b(x == y),
                OP_INOT_EQUAL => b(x != y),
                OP_UGREATER_THAN => b(x > y),
                OP_SGREATER_THAN => b(sx > sy),
                OP_UGREATER_THAN_EQUAL => b(x >= y),
                OP_SGREATER_THAN_EQUAL => b(sx >= sy),
                OP_ULESS_THAN => b(x < y),
                OP_SLESS_THAN => b(sx < sy),
                OP_ULESS_THAN_EQUAL => b(x <= y),
                OP_SLESS_THAN_EQUAL => b(sx <= sy),
                OP_SHIFT_RIGHT_LOGICAL => x.checked_shr(y)?,
                OP_SHIFT_RIGHT_ARITHMETIC => sx.checked_shr(y)? as u32,
                OP_SHIFT_LEFT_LOGICAL => x.checked_shl(y)?,
                OP_BITWISE_OR => x | y,
                OP_BITWISE_XOR => x ^ y,
                OP_BITWISE_AND => x & y,
                _ => return None,
            }
        }
    })
}
