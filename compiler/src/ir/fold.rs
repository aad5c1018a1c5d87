//! Constant folding of operations whose operands are all literals, with the language's
//! semantics (docs/LANGUAGE.md: integers wrap, shift amounts are masked, `x / 0 == x`,
//! `x % 0 == 0`, `MIN / -1 == MIN`, `MIN % -1 == 0`). It keeps the emitted WGSL free of
//! constant expressions that WGSL would reject (overflowing shifts and arithmetic, division
//! by zero, `3.4e38f * 2f`), and keeps shaders small. Float results that are not finite
//! are written by the caller as bit casts (WGSL has no literal for them).

use naga::{BinaryOperator as B, Literal as L, UnaryOperator as U};

pub(crate) fn binary(op: B, a: L, b: L) -> Option<L> {
    Some(match (a, b) {
        (L::U32(x), L::U32(y)) => match op {
            B::Add => L::U32(x.wrapping_add(y)),
            B::Subtract => L::U32(x.wrapping_sub(y)),
            B::Multiply => L::U32(x.wrapping_mul(y)),
            B::Divide => L::U32(x.checked_div(y).unwrap_or(x)),
            B::Modulo => L::U32(if y == 0 { 0 } else { x % y }),
            B::And => L::U32(x & y),
            B::InclusiveOr => L::U32(x | y),
            B::ExclusiveOr => L::U32(x ^ y),
            B::ShiftLeft => L::U32(x.wrapping_shl(y)),
            B::ShiftRight => L::U32(x.wrapping_shr(y)),
            B::Equal => L::Bool(x == y),
            B::NotEqual => L::Bool(x != y),
            B::Less => L::Bool(x < y),
            B::LessEqual => L::Bool(x <= y),
            B::Greater => L::Bool(x > y),
            B::GreaterEqual => L::Bool(x >= y),
            _ => return None,
        },
        (L::I32(x), L::I32(y)) => match op {
            B::Add => L::I32(x.wrapping_add(y)),
            B::Subtract => L::I32(x.wrapping_sub(y)),
            B::Multiply => L::I32(x.wrapping_mul(y)),
            B::Divide => L::I32(if y == 0 { x } else { x.wrapping_div(y) }),
            B::Modulo => L::I32(if y == 0 { 0 } else { x.wrapping_rem(y) }),
            B::And => L::I32(x & y),
            B::InclusiveOr => L::I32(x | y),
            B::ExclusiveOr => L::I32(x ^ y),
            B::Equal => L::Bool(x == y),
            B::NotEqual => L::Bool(x != y),
            B::Less => L::Bool(x < y),
            B::LessEqual => L::Bool(x <= y),
            B::Greater => L::Bool(x > y),
            B::GreaterEqual => L::Bool(x >= y),
            _ => return None,
        },
        (L::I32(x), L::U32(y)) => match op {
            B::ShiftLeft => L::I32(x.wrapping_shl(y)),
            B::ShiftRight => L::I32(x.wrapping_shr(y)),
            _ => return None,
        },
        (L::F32(x), L::F32(y)) => {
            let v = match op {
                B::Add => x + y,
                B::Subtract => x - y,
                B::Multiply => x * y,
                B::Divide => x / y,
                B::Equal => return Some(L::Bool(x == y)),
                B::NotEqual => return Some(L::Bool(x != y)),
                B::Less => return Some(L::Bool(x < y)),
                B::LessEqual => return Some(L::Bool(x <= y)),
                B::Greater => return Some(L::Bool(x > y)),
                B::GreaterEqual => return Some(L::Bool(x >= y)),
                _ => return None,
            };
            // Non-finite results are kept: `ops::binary` writes them as bit casts.
            L::F32(v)
        }
        (L::Bool(x), L::Bool(y)) => match op {
            B::LogicalAnd | B::And => L::Bool(x && y),
            B::LogicalOr | B::InclusiveOr => L::Bool(x || y),
            B::Equal => L::Bool(x == y),
            B::NotEqual | B::ExclusiveOr => L::Bool(x != y),
            _ => return None,
        },
        _ => return None,
    })
}

pub(crate) fn unary(op: U, a: L) -> Option<L> {
    Some(match (op, a) {
        (U::Negate, L::I32(x)) => L::I32(x.wrapping_neg()),
        (U::Negate, L::F32(x)) => L::F32(-x),
        (U::BitwiseNot, L::U32(x)) => L::U32(!x),
        (U::BitwiseNot, L::I32(x)) => L::I32(!x),
        (U::LogicalNot, L::Bool(x)) => L::Bool(!x),
        _ => return None,
    })
}
