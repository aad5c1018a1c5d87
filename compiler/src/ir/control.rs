//! Structured control flow: `if`, `loop`, `while`, `for` over ranges, `break`,
//! `continue`, `return` and short-circuit `&&`/`||`.
//!
//! The rewritten kernel passes each branch or loop body as a closure; it runs exactly
//! once, at build time, inside a fresh naga block, so that the statements it records
//! land in the right place.

use naga::{Block, Statement};

use super::builder::with;
use super::ops::{le, lt};
use super::types::GpuType;
use super::val::{lit, Val, Var};

/// The value of `cond` when the kernel is built: a literal (a constant, a specialisation
/// constant, or an operation on them that the builder folded).
fn known(cond: Val<bool>) -> Option<bool> {
    with(|c| match c.f().func.expressions[cond.h] {
        naga::Expression::Literal(naga::Literal::Bool(b)) => Some(b),
        _ => None,
    })
}

fn block(body: impl FnOnce()) -> Block {
    with(|c| c.push_block());
    body();
    with(|c| c.pop_block())
}

/// `if cond { then } else { otherwise }`. A condition known when the kernel is built (a
/// literal, or a constant such as a strategy's associated `const`) picks its branch at
/// build time and the other branch is not built at all: it may use what this
/// specialisation cannot lower (e.g. `group_any` in a grid-level kernel).
pub fn if_(cond: Val<bool>, then: impl FnOnce(), otherwise: impl FnOnce()) {
    match known(cond) {
        Some(true) => return then(),
        Some(false) => return otherwise(),
        None => {}
    }
    let accept = block(then);
    let reject = block(otherwise);
    with(|c| {
        c.stmt(Statement::If {
            condition: cond.h,
            accept,
            reject,
        })
    });
}

/// `if c { a } else { b }` used as a value.
pub fn if_value<T: GpuType>(
    cond: Val<bool>,
    then: impl FnOnce() -> Val<T>,
    otherwise: impl FnOnce() -> Val<T>,
) -> Val<T> {
    match known(cond) {
        Some(true) => return then(),
        Some(false) => return otherwise(),
        None => {}
    }
    let tmp = Var::<T>::uninit("branch_value");
    if_(cond, || tmp.set(then()), || tmp.set(otherwise()));
    tmp.get()
}

pub fn loop_(body: impl FnOnce()) {
    let body = block(body);
    with(|c| {
        c.stmt(Statement::Loop {
            body,
            continuing: Block::new(),
            break_if: None,
        })
    });
}

pub fn while_(cond: impl FnOnce() -> Val<bool>, body: impl FnOnce()) {
    loop_(|| {
        let c = cond();
        if_(c, || {}, break_);
        body();
    })
}

/// Integer types that `for i in a..b` iterates over.
pub trait RangeInt: super::ops::Ordered + GpuType {
    fn one() -> Val<Self>;
}
impl RangeInt for u32 {
    fn one() -> Val<u32> {
        lit(1u32)
    }
}
impl RangeInt for i32 {
    fn one() -> Val<i32> {
        lit(1i32)
    }
}
impl RangeInt for usize {
    fn one() -> Val<usize> {
        lit(1usize)
    }
}

/// `for i in start..end` (or `..=end` when `inclusive`). The increment lives in the
/// loop's continuing block, so `continue` still advances `i`.
pub fn for_range<T: RangeInt>(
    start: Val<T>,
    end: Val<T>,
    inclusive: bool,
    body: impl FnOnce(Val<T>),
) where
    Val<T>: std::ops::Add<Val<T>, Output = Val<T>>,
{
    let i = Var::new("i", start);
    let loop_body = block(|| {
        let cur = i.get();
        let go = if inclusive {
            le(cur, end)
        } else {
            lt(cur, end)
        };
        if_(go, || {}, break_);
        body(cur);
    });
    let continuing = block(|| i.set(i.get() + T::one()));
    with(|c| {
        c.stmt(Statement::Loop {
            body: loop_body,
            continuing,
            break_if: None,
        })
    });
}

/// `for i in (start..end).rev()`. The decrement happens at the top of the body, so
/// `continue` needs no continuing block and an empty range never underflows.
pub fn for_range_rev<T: RangeInt>(start: Val<T>, end: Val<T>, body: impl FnOnce(Val<T>))
where
    Val<T>: std::ops::Sub<Val<T>, Output = Val<T>>,
{
    let i = Var::new("i", end);
    loop_(|| {
        let cur = i.get();
        if_(le(cur, start), break_, || {});
        let v = cur - T::one();
        i.set(v);
        body(v);
    });
}

pub fn break_() {
    with(|c| c.stmt(Statement::Break));
}

pub fn continue_() {
    with(|c| c.stmt(Statement::Continue));
}

/// `return;` (or the end of a kernel). In an inlined helper this is a compile error
/// reported by the front end before we get here.
pub fn return_() {
    with(|c| {
        check_not_inlined(c.inline_depth);
        c.stmt(Statement::Return { value: None })
    });
}

pub fn return_value<T>(v: Val<T>) {
    with(|c| {
        check_not_inlined(c.inline_depth);
        c.stmt(Statement::Return { value: Some(v.h) })
    });
}

fn check_not_inlined(depth: u32) {
    assert!(
        depth == 0,
        "early `return` in a helper that is inlined because it receives workgroup or storage \
         memory; end the helper with its value instead"
    );
}

/// `a && b`, evaluating `b` only when `a` holds (it may index out of bounds otherwise).
/// Known operands fold: `false && b` is `false` with `b` never built, `true && b` is `b`.
pub fn and(a: Val<bool>, b: impl FnOnce() -> Val<bool>) -> Val<bool> {
    match known(a) {
        Some(true) => return b(),
        Some(false) => return a,
        None => {}
    }
    let r = Var::new("and", a);
    if_(a, || r.set(b()), || {});
    r.get()
}

/// `a || b`, evaluating `b` only when `a` does not hold.
/// Known operands fold: `true || b` is `true` with `b` never built, `false || b` is `b`.
pub fn or(a: Val<bool>, b: impl FnOnce() -> Val<bool>) -> Val<bool> {
    match known(a) {
        Some(true) => return a,
        Some(false) => return b(),
        None => {}
    }
    let r = Var::new("or", a);
    if_(a, || {}, || r.set(b()));
    r.get()
}

/// Marks an expression statement whose value is unused (e.g. `f(x);`).
pub fn discard<T>(_v: T) {}

/// What an `if`/`else` produces: nothing (a statement) or a value.
pub trait BranchValue: Sized {
    fn branch(
        cond: Val<bool>,
        then: impl FnOnce() -> Self,
        otherwise: impl FnOnce() -> Self,
    ) -> Self;
    /// The value of a branch that ends in `break`/`continue`/`return` (never used).
    fn diverged() -> Self;
}
impl BranchValue for () {
    fn branch(cond: Val<bool>, then: impl FnOnce(), otherwise: impl FnOnce()) {
        if_(cond, then, otherwise)
    }
    fn diverged() {}
}
impl<T: GpuType> BranchValue for Val<T> {
    fn branch(
        cond: Val<bool>,
        then: impl FnOnce() -> Self,
        otherwise: impl FnOnce() -> Self,
    ) -> Self {
        if_value(cond, then, otherwise)
    }
    fn diverged() -> Self {
        super::val::zero()
    }
}

/// `if c { a } else { b }`, as a statement or as a value.
pub fn if_else<R: BranchValue>(
    cond: Val<bool>,
    then: impl FnOnce() -> R,
    otherwise: impl FnOnce() -> R,
) -> R {
    R::branch(cond, then, otherwise)
}

pub fn diverged<R: BranchValue>() -> R {
    R::diverged()
}
