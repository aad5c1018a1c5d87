//! Which arms of a divergent `if` the vector form runs without first testing for a lane
//! that takes them. The test (a mask reduction and a branch) pays where an arm is costly and
//! often taken by no lane; for an arm of a few register operations (a `select` written as
//! an `if`, `c.y` or `c.x` by a bit of the slot) it costs more than the arm, and the branch
//! keeps LLVM from turning the arm's stores to locals into selects, so that the locals
//! stay in memory across it. An arm is *straight* when it only computes values from
//! registers and locals and stores into locals, in few operations: running it under its
//! mask with no lane in it changes nothing, as every store is masked.

use naga::{
    BinaryOperator, Block, Expression, Handle, MathFunction, ScalarKind, Statement, TypeInner,
};

use super::lower::Fx;

/// At most this many expressions and stores in a straight arm: about the cost of the
/// mask test and a mispredicted branch.
const MAX_OPS: usize = 24;

/// Whether `b`, a block of the function `fx` lowers, is straight (module doc).
pub fn straight(fx: &Fx<'_>, b: &Block) -> bool {
    let mut ops = 0;
    block(fx, b, &mut ops) && ops <= MAX_OPS
}

fn block(fx: &Fx<'_>, b: &Block, ops: &mut usize) -> bool {
    b.iter().all(|s| match *s {
        Statement::Emit(ref range) => range.clone().all(|h| {
            *ops += 1;
            expression(fx, h)
        }),
        Statement::Store { pointer, .. } => {
            *ops += 1;
            local(fx, pointer)
        }
        Statement::If {
            ref accept,
            ref reject,
            ..
        } => block(fx, accept, ops) && block(fx, reject, ops),
        Statement::Block(ref inner) => block(fx, inner, ops),
        // They only move lanes between masks.
        Statement::Break | Statement::Continue => true,
        _ => false,
    })
}

/// A pointer into a local variable (or a `&mut` argument, the caller's local) at a place
/// that is the same in every lane.
fn local(fx: &Fx<'_>, mut p: Handle<Expression>) -> bool {
    loop {
        match fx.fun.expressions[p] {
            Expression::LocalVariable(_) | Expression::FunctionArgument(_) => return true,
            Expression::AccessIndex { base, .. } => p = base,
            _ => return false,
        }
    }
}

/// Register operations: no memory but locals, no libm call, no integer division (which
/// LLVM makes one lane at a time). Float division stays: an arm that divides is mostly one
/// some lane takes (measured: skipping such arms when no lane does was slower).
fn expression(fx: &Fx<'_>, h: Handle<Expression>) -> bool {
    match fx.fun.expressions[h] {
        Expression::Literal(_)
        | Expression::Constant(_)
        | Expression::ZeroValue(_)
        | Expression::Compose { .. }
        | Expression::Splat { .. }
        | Expression::Swizzle { .. }
        | Expression::FunctionArgument(_)
        | Expression::LocalVariable(_)
        | Expression::AccessIndex { .. }
        | Expression::Unary { .. }
        | Expression::Select { .. }
        | Expression::Relational { .. }
        | Expression::As { .. } => true,
        Expression::Load { pointer } => local(fx, pointer),
        Expression::Binary { op, left, .. } => {
            !matches!(op, BinaryOperator::Divide | BinaryOperator::Modulo) || float(fx, left)
        }
        Expression::Math { fun, .. } => matches!(
            fun,
            MathFunction::Abs
                | MathFunction::Min
                | MathFunction::Max
                | MathFunction::Clamp
                | MathFunction::Saturate
                | MathFunction::Floor
                | MathFunction::Ceil
                | MathFunction::Trunc
                | MathFunction::Sign
                | MathFunction::Fma
                | MathFunction::Mix
                | MathFunction::Sqrt
                | MathFunction::Dot
                | MathFunction::Cross
                | MathFunction::CountTrailingZeros
                | MathFunction::CountLeadingZeros
                | MathFunction::CountOneBits
        ),
        _ => false,
    }
}

/// Whether expression `h` is a float scalar or vector.
fn float(fx: &Fx<'_>, h: Handle<Expression>) -> bool {
    matches!(
        *fx.ty_of(h),
        TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } if s.kind == ScalarKind::Float
    )
}
