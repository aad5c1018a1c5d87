//! The IR builder's state while one kernel specialisation is being built.
//!
//! Data flow: the code that `#[kernel]` generates runs once per specialisation; every
//! typed value operation (`Val + Val`, `if_`, `Var::store`, ...) lands here and appends
//! naga expressions and statements to the function being built. The state lives in a
//! thread-local because the generated code is ordinary Rust with operator overloading:
//! there is no context argument to thread through `a * b + c`.
//!
//! naga's scoping rules are enforced here once, so the rest of the crate need not care:
//! every expression that needs an `Emit` gets one before the next statement, and nothing
//! is appended to a block after it has been terminated by `break`/`continue`/`return`.

use naga::{Block, Expression, Function, Handle, Module, Span, Statement, Type, TypeInner};
use std::any::TypeId;
use std::cell::RefCell;
use std::collections::HashMap;

use crate::spec::{KernelInfo, Spec};

/// One naga function under construction (an entry point or a helper).
pub(crate) struct FnState {
    pub func: Function,
    blocks: Vec<Block>,
    terminated: Vec<bool>,
    /// Length of the expression arena when the current run of to-be-emitted
    /// expressions started.
    emit_start: Option<usize>,
}

impl FnState {
    pub fn new(name: &str) -> Self {
        FnState {
            func: Function {
                name: Some(name.to_string()),
                ..Default::default()
            },
            blocks: vec![Block::new()],
            terminated: vec![false],
            emit_start: None,
        }
    }

    fn flush_emit(&mut self) {
        if let Some(start) = self.emit_start.take() {
            let range = self.func.expressions.range_from(start);
            if !*self.terminated.last().unwrap() {
                self.blocks
                    .last_mut()
                    .unwrap()
                    .push(Statement::Emit(range), Span::UNDEFINED);
            }
        }
    }

    pub fn finish(mut self) -> Function {
        self.flush_emit();
        assert_eq!(self.blocks.len(), 1, "unbalanced blocks in IR builder");
        self.func.body = self.blocks.pop().unwrap();
        self.func
    }
}

pub(crate) struct Ctx {
    pub module: Module,
    pub fns: Vec<FnState>,
    pub fn_cache: HashMap<(TypeId, &'static str), Handle<naga::Function>>,
    /// Helpers being built or inlined, outermost first: a call already on it recurses.
    pub call_stack: Vec<(TypeId, &'static str)>,
    pub spec: Spec,
    pub info: &'static KernelInfo,
    pub uses_subgroups: bool,
    /// Whether the kernel has an operation at which invocations wait for each other on
    /// the CPU backend (barriers, subgroup operations, `group_any` above thread level):
    /// set by the intrinsics that emit one. `group_share` is not one: every invocation
    /// can compute its group's value there (`cohort::intrinsics::group_share`).
    pub synchronises: bool,
    pub next_binding: u32,
    pub bindings: Vec<crate::abi::Binding>,
    /// Storage buffers declared so far, and the lengths binding once `len()` is used.
    pub storage_buffers: u32,
    pub lengths: Option<Handle<naga::GlobalVariable>>,
    pub group_share_sites: u32,
    /// The print binding once the kernel prints, and its print sites in site order.
    pub print: Option<Handle<naga::GlobalVariable>>,
    pub prints: Vec<crate::abi::PrintSite>,
    /// What the kernel asks for that this specialisation cannot lower (e.g. `group_any`
    /// at grid level): reported by `emit` as a compile error at the kernel's span.
    pub unsupported: Vec<String>,
    /// Depth of helper bodies being inlined into their caller (no `return` there).
    pub inline_depth: u32,
    /// Entry-point values computed in the prologue, so they dominate every use.
    pub prologue: Prologue,
}

#[derive(Default, Clone, Copy)]
pub(crate) struct Prologue {
    pub local_index: Option<Handle<Expression>>,
    pub global_index: Option<Handle<Expression>>,
    pub workgroup_linear: Option<Handle<Expression>>,
    pub subgroup_lane: Option<Handle<Expression>>,
}

thread_local! {
    static CTX: RefCell<Option<Ctx>> = const { RefCell::new(None) };
}

/// Runs `f` on the builder state. Panics with a clear message when called outside a
/// kernel build: IR values only exist while a kernel is being built.
pub(crate) fn with<R>(f: impl FnOnce(&mut Ctx) -> R) -> R {
    CTX.with(|c| {
        let mut guard = c.borrow_mut();
        let ctx = guard.as_mut().expect(
            "cohort IR operation outside a kernel build: IR values exist only while \
             `<kernel>::build` runs",
        );
        f(ctx)
    })
}

pub(crate) fn install(ctx: Ctx) {
    CTX.with(|c| {
        let mut g = c.borrow_mut();
        assert!(
            g.is_none(),
            "nested kernel builds on one thread are not supported"
        );
        *g = Some(ctx);
    })
}

pub(crate) fn uninstall() -> Option<Ctx> {
    CTX.with(|c| c.borrow_mut().take())
}

/// Drops the builder state if a build panics half-way, so the thread can build again.
pub(crate) struct InstallGuard;
impl Drop for InstallGuard {
    fn drop(&mut self) {
        let _ = uninstall();
    }
}

fn needs_emit(e: &Expression) -> bool {
    !matches!(
        e,
        Expression::Literal(_)
            | Expression::Constant(_)
            | Expression::Override(_)
            | Expression::ZeroValue(_)
            | Expression::FunctionArgument(_)
            | Expression::GlobalVariable(_)
            | Expression::LocalVariable(_)
            | Expression::CallResult(_)
            | Expression::AtomicResult { .. }
            | Expression::WorkGroupUniformLoadResult { .. }
            | Expression::SubgroupBallotResult
            | Expression::SubgroupOperationResult { .. }
    )
}

impl Ctx {
    pub fn new(info: &'static KernelInfo, spec: Spec) -> Self {
        Ctx {
            module: Module::default(),
            fns: Vec::new(),
            fn_cache: HashMap::new(),
            call_stack: Vec::new(),
            spec,
            info,
            uses_subgroups: false,
            synchronises: false,
            next_binding: 0,
            storage_buffers: 0,
            lengths: None,
            bindings: Vec::new(),
            group_share_sites: 0,
            print: None,
            prints: Vec::new(),
            unsupported: Vec::new(),
            inline_depth: 0,
            prologue: Prologue::default(),
        }
    }

    pub fn f(&mut self) -> &mut FnState {
        self.fns.last_mut().expect("no function under construction")
    }

    pub fn expr(&mut self, e: Expression) -> Handle<Expression> {
        let emit = needs_emit(&e);
        let f = self.f();
        if !emit {
            f.flush_emit();
        }
        let len = f.func.expressions.len();
        let h = f.func.expressions.append(e, Span::UNDEFINED);
        if emit && f.emit_start.is_none() {
            f.emit_start = Some(len);
        }
        h
    }

    pub fn stmt(&mut self, s: Statement) {
        let f = self.f();
        f.flush_emit();
        if *f.terminated.last().unwrap() {
            return;
        }
        let terminates = matches!(
            s,
            Statement::Break | Statement::Continue | Statement::Return { .. } | Statement::Kill
        );
        f.blocks.last_mut().unwrap().push(s, Span::UNDEFINED);
        if terminates {
            *f.terminated.last_mut().unwrap() = true;
        }
    }

    pub fn push_block(&mut self) {
        let f = self.f();
        f.flush_emit();
        f.blocks.push(Block::new());
        f.terminated.push(false);
    }

    pub fn pop_block(&mut self) -> Block {
        let f = self.f();
        f.flush_emit();
        f.terminated.pop();
        f.blocks.pop().expect("block stack underflow")
    }

    pub fn ty(&mut self, inner: TypeInner) -> Handle<Type> {
        self.module
            .types
            .insert(Type { name: None, inner }, Span::UNDEFINED)
    }

    pub fn local(&mut self, name: Option<&str>, ty: Handle<Type>) -> Handle<Expression> {
        let f = self.f();
        let lv = f.func.local_variables.append(
            naga::LocalVariable {
                name: name.map(str::to_string),
                ty,
                init: None,
            },
            Span::UNDEFINED,
        );
        self.expr(Expression::LocalVariable(lv))
    }

    pub fn name_expr(&mut self, h: Handle<Expression>, name: &str) {
        let f = self.f();
        // Only emitted expressions may be named: the writers turn them into `let`s.
        if needs_emit(&f.func.expressions[h]) && !f.func.named_expressions.contains_key(&h) {
            f.func.named_expressions.insert(h, name.to_string());
        }
    }
}
