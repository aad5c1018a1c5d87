//! Pointers, loads, stores and atomics of the vector form. A naga pointer is a [`Place`]: a
//! buffer binding plus a byte offset per lane, or a local variable (a stack slot holding all
//! lanes, structure of arrays) plus an index path. Places whose path is the same for every
//! lane load and store whole registers; others gather and scatter one scalar leaf at a time,
//! except buffer accesses: a load of one element for every lane is one load per leaf; the
//! lanes' consecutive elements move with one wide load or store; a struct's elements that
//! lie apart move as one row per lane, transposed.
//! Every access is bounds-checked: an out-of-range lane sets the dispatch's error flag and
//! is masked off, where the host form would panic.

use naga::{Handle, ScalarKind, TypeInner};

use super::deferred::{deferred_offsets, holds_atomic, FLUSH};
use super::lower::{Fx, Val};
use super::rows::RowsAt;
use super::types::{byte_size, iota, lanes, leaves, scalar, splat_const, value_type, Lowering};

/// Bytes of the constant that a load at one address for all lanes reads where no lane
/// loads ([`Fx::load_once`]).
const ZEROS: u64 = 4096;

#[derive(Clone, Debug)]
pub enum Idx {
    Const(u32),
    /// A per-lane index (`<W x i32>`) and the length it must stay below.
    Dyn(String, u32),
}

#[derive(Clone, Debug)]
pub enum Root {
    Local {
        slot: String,
        slot_ty: String,
        path: Vec<Idx>,
    },
    /// Binding `g` of the `env` table, at byte offset `konst` plus `dynamic` (`<W x i64>`,
    /// when the lanes' offsets differ). `stride`: the stride of the array the last
    /// per-lane index stepped through, so that lanes indexing consecutive elements (a
    /// path's state at its own slot) can be told at run time and read with one wide load.
    Buf {
        g: usize,
        konst: u64,
        dynamic: Option<String>,
        stride: u64,
    },
}

/// A plan for reading or writing consecutive lanes' elements as one vector of 32-bit
/// words (`Fx::wide_plan`): `m` words per lane and each leaf's (path, scalar, word).
pub struct Wide {
    m: u64,
    leaves: Vec<(Vec<u32>, &'static str, u64)>,
}

/// Where lane 0's element of a wide access starts: binding `g`, byte offset `konst` plus
/// `base0` (an `i64` value).
pub struct WideAt {
    g: usize,
    konst: u64,
    base0: String,
}

impl Root {
    /// A local place one index deeper (a buffer place is unchanged: its indices are
    /// offsets, added by the caller).
    fn push(mut self, i: Idx) -> Root {
        if let Root::Local { path, .. } = &mut self {
            path.push(i);
        }
        self
    }
}

#[derive(Clone, Debug)]
pub struct Place {
    pub root: Root,
    /// The naga type the place holds.
    pub ty: TypeInner,
}

fn intrinsic_suffix(s: &str) -> &'static str {
    match s {
        "float" => "f32",
        "i1" => "i1",
        _ => "i32",
    }
}

impl Fx<'_> {
    pub fn place(&self, h: Handle<naga::Expression>) -> Lowering<Place> {
        match self.val(h)? {
            Val::P(p) => Ok(p),
            Val::R { .. } => Err("a value used as a pointer".into()),
        }
    }

    pub fn global_place(&self, g: Handle<naga::GlobalVariable>) -> Lowering<Val> {
        let pos = self.globals[g.index()].ok_or("a global without a buffer")?;
        let gv = &self.m.global_variables[g];
        if !matches!(
            gv.space,
            naga::AddressSpace::Storage { .. } | naga::AddressSpace::Uniform
        ) {
            return Err(format!("globals in address space {:?}", gv.space));
        }
        Ok(Val::P(Place {
            root: Root::Buf {
                g: pos,
                konst: 0,
                dynamic: None,
                stride: 0,
            },
            ty: self.m.types[gv.ty].inner.clone(),
        }))
    }

    pub fn local_place(&self, l: Handle<naga::LocalVariable>) -> Val {
        let (slot, slot_ty) = self.locals[l.index()].clone();
        Val::P(Place {
            root: Root::Local {
                slot,
                slot_ty,
                path: Vec::new(),
            },
            ty: self.m.types[self.fun.local_variables[l].ty].inner.clone(),
        })
    }

    /// `base[index]` on a place, with `index` a per-lane value of naga kind `kind`.
    pub fn index_place(&mut self, p: Place, index: &Val, kind: ScalarKind) -> Lowering<Val> {
        let (elem, stride, len) = match p.ty {
            TypeInner::Array { base, stride, size } => (
                self.m.types[base].inner.clone(),
                stride,
                match size {
                    naga::ArraySize::Constant(n) => Some(n.get()),
                    _ => None,
                },
            ),
            TypeInner::Vector { size, scalar: s } => {
                (TypeInner::Scalar(s), s.width as u32, Some(size as u32))
            }
            ref other => return Err(format!("indexing a {other:?}")),
        };
        let root = match p.root {
            local @ Root::Local { .. } => local.push(Idx::Dyn(
                index.v()?.to_string(),
                len.ok_or("a runtime-sized local")?,
            )),
            Root::Buf {
                g, konst, dynamic, ..
            } => {
                let ext = if kind == ScalarKind::Sint {
                    "sext"
                } else {
                    "zext"
                };
                let v64 = lanes("i64");
                let wide = self.op(&format!("{ext} {} to {v64}", index.typed()?));
                let scaled = self.op(&format!(
                    "mul {v64} {wide}, {}",
                    splat_const("i64", &stride.to_string())
                ));
                let sum = match dynamic {
                    Some(d) => self.op(&format!("add {v64} {d}, {scaled}")),
                    None => scaled,
                };
                Root::Buf {
                    g,
                    konst,
                    dynamic: Some(sum),
                    stride: u64::from(stride),
                }
            }
        };
        Ok(Val::P(Place { root, ty: elem }))
    }

    /// `base.index` (a member, or an element at a constant index) on a place.
    pub fn member_place(&mut self, p: Place, index: u32) -> Lowering<Val> {
        let (ty, offset) = match p.ty {
            TypeInner::Struct { ref members, .. } => {
                let mem = members.get(index as usize).ok_or("a member out of range")?;
                (self.m.types[mem.ty].inner.clone(), u64::from(mem.offset))
            }
            TypeInner::Array { base, stride, .. } => {
                (self.m.types[base].inner.clone(), u64::from(index * stride))
            }
            TypeInner::Vector { scalar: s, .. } => {
                (TypeInner::Scalar(s), u64::from(index * s.width as u32))
            }
            ref other => return Err(format!("a member of a {other:?}")),
        };
        let root = match p.root {
            local @ Root::Local { .. } => local.push(Idx::Const(index)),
            Root::Buf {
                g,
                konst,
                dynamic,
                stride,
            } => Root::Buf {
                g,
                konst: konst + offset,
                dynamic,
                stride,
            },
        };
        Ok(Val::P(Place { root, ty }))
    }

    /// Sets the error flag if any lane of `bad` is on.
    pub fn report(&mut self, bad: &str) {
        let any = self.any(bad);
        let (fail, ok) = (self.label(), self.label());
        self.line(&format!("br i1 {any}, label %{fail}, label %{ok}"));
        self.body.push_str(&format!("{fail}:\n"));
        self.line("store atomic i32 1, ptr %err monotonic, align 4");
        self.line(&format!("br label %{ok}"));
        self.body.push_str(&format!("{ok}:\n"));
    }

    /// Narrows `mask` to the lanes whose access stays in bounds, reporting the others.
    fn in_bounds(&mut self, p: &Place, mask: &str) -> Lowering<String> {
        let mut ok: Option<String> = None;
        match &p.root {
            Root::Local { path, .. } => {
                for i in path {
                    if let Idx::Dyn(v, n) = i {
                        let c = self.op(&format!(
                            "icmp ult {} {v}, {}",
                            lanes("i32"),
                            splat_const("i32", &n.to_string())
                        ));
                        ok = Some(match ok {
                            Some(o) => self.and(&o, &c),
                            None => c,
                        });
                    }
                }
            }
            Root::Buf {
                g, konst, dynamic, ..
            } => {
                let size = self.buffer_size(*g);
                let end = konst + byte_size(self.m, &p.ty);
                let c = match dynamic {
                    Some(d) => {
                        // `d <= size - end`, unsigned, where `end <= size`: a negative offset
                        // (a signed index below zero) is huge unsigned and fails, where
                        // `d + end <= size` would wrap and pass.
                        let v64 = lanes("i64");
                        let fits = self.op(&format!("icmp ule i64 {end}, {size}"));
                        let room = self.op(&format!("sub i64 {size}, {end}"));
                        let r = self.splat("i64", &room);
                        let c = self.op(&format!("icmp ule {v64} {d}, {r}"));
                        let f = self.splat("i1", &fits);
                        self.and(&c, &f)
                    }
                    None => {
                        let c = self.op(&format!("icmp ule i64 {end}, {size}"));
                        self.splat("i1", &c)
                    }
                };
                ok = Some(c);
            }
        }
        let Some(ok) = ok else {
            return Ok(mask.to_string());
        };
        let nok = self.not(&ok);
        let bad = self.and(mask, &nok);
        self.report(&bad);
        Ok(self.and(mask, &ok))
    }

    /// A scalar register in every lane.
    pub fn splat(&mut self, s: &str, x: &str) -> String {
        let v = lanes(s);
        let one = self.op(&format!("insertelement {v} poison, {s} {x}, i32 0"));
        self.op(&format!(
            "shufflevector {v} {one}, {v} poison, {} zeroinitializer",
            lanes("i32")
        ))
    }

    fn env_field(&mut self, g: usize, at: u64, ty: &str) -> String {
        let p = self.op(&format!(
            "getelementptr i8, ptr %env, i64 {}",
            g as u64 * 16 + at
        ));
        self.op(&format!("load {ty}, ptr {p}, !invariant.load !0"))
    }
    pub(super) fn buffer_base(&mut self, g: usize) -> String {
        self.env_field(g, 0, "ptr")
    }
    fn buffer_size(&mut self, g: usize) -> String {
        self.env_field(g, 8, "i64")
    }

    /// Per-lane addresses of every scalar leaf of the place, with the leaf's scalar type
    /// and its path in the value.
    fn leaf_pointers(&mut self, p: &Place) -> Lowering<Vec<(Vec<u32>, String, String)>> {
        let ls = leaves(self.m, &p.ty)?;
        let mut out = Vec::with_capacity(ls.len());
        let pv = lanes("ptr");
        match &p.root {
            Root::Buf {
                g, konst, dynamic, ..
            } => {
                let base = self.buffer_base(*g);
                for l in ls {
                    let s = scalar(l.scalar)?.to_string();
                    let at = konst + l.offset;
                    let ptrs = match dynamic {
                        Some(d) => {
                            let v64 = lanes("i64");
                            let o = self.op(&format!(
                                "add {v64} {d}, {}",
                                splat_const("i64", &at.to_string())
                            ));
                            self.op(&format!("getelementptr i8, ptr {base}, {v64} {o}"))
                        }
                        None => {
                            let one = self.op(&format!("getelementptr i8, ptr {base}, i64 {at}"));
                            self.splat("ptr", &one)
                        }
                    };
                    out.push((l.path, s, ptrs));
                }
            }
            Root::Local {
                slot,
                slot_ty,
                path,
            } => {
                let mut idx = String::new();
                for i in path {
                    match i {
                        Idx::Const(c) => idx.push_str(&format!(", i32 {c}")),
                        Idx::Dyn(v, _) => idx.push_str(&format!(", {} {v}", lanes("i32"))),
                    }
                }
                if !path.iter().any(|i| matches!(i, Idx::Dyn(..))) {
                    return Err("per-lane addresses of a uniform local place".into());
                }
                for l in ls {
                    let s = scalar(l.scalar)?.to_string();
                    if s == "i1" {
                        return Err("booleans in a local indexed per lane".into());
                    }
                    let mut leaf_idx = idx.clone();
                    for c in &l.path {
                        leaf_idx.push_str(&format!(", i32 {c}"));
                    }
                    let vecs = self.op(&format!(
                        "getelementptr {slot_ty}, ptr {slot}, i32 0{leaf_idx}"
                    ));
                    let ptrs = self.op(&format!(
                        "getelementptr {s}, {pv} {vecs}, {} {}",
                        lanes("i32"),
                        iota()
                    ));
                    out.push((l.path, s, ptrs));
                }
            }
        }
        Ok(out)
    }

    /// The address of a local place whose path is the same for every lane.
    pub fn uniform_local(&mut self, p: &Place) -> Option<String> {
        let Root::Local {
            slot,
            slot_ty,
            path,
        } = &p.root
        else {
            return None;
        };
        let mut idx = String::new();
        for i in path {
            match i {
                Idx::Const(c) => idx.push_str(&format!(", i32 {c}")),
                Idx::Dyn(..) => return None,
            }
        }
        if idx.is_empty() {
            return Some(slot.clone());
        }
        Some(self.op(&format!("getelementptr {slot_ty}, ptr {slot}, i32 0{idx}")))
    }

    pub fn load(&mut self, p: &Place) -> Lowering<Val> {
        let ty = value_type(self.m, &p.ty)?;
        if holds_atomic(self.m, &p.ty) {
            self.flush_deferred();
        }
        if let Some(addr) = self.uniform_local(p) {
            let v = self.op(&format!("load {ty}, ptr {addr}"));
            return Ok(Val::r(ty, v));
        }
        let e = self.exec();
        let mask = self.in_bounds(p, &e)?;
        if let Root::Buf {
            g,
            konst,
            dynamic: Some(d),
            ..
        } = &p.root
        {
            return self.load_maybe_uniform(p, &ty, *g, *konst, d, &mask);
        }
        if let Root::Buf {
            g,
            konst,
            dynamic: None,
            ..
        } = &p.root
        {
            return self.load_once(p, &ty, *g, &konst.to_string(), &mask);
        }
        self.gather(p, &ty, &mask)
    }

    /// A buffer load at the same byte offset `at` (an `i64` operand) in every lane: one
    /// scalar load per leaf, broadcast, where a gather from the same address would cost a
    /// gather per leaf. Where no lane loads (then `at` may be out of bounds) it reads
    /// [`ZEROS`] instead: a select of the address rather than a branch around the loads,
    /// whose blocks and stack slot, at every such access, cost LLVM a fifth more time to
    /// compile the extend kernel (BENCHMARKS.md). A place larger than `ZEROS` gathers.
    fn load_once(&mut self, p: &Place, ty: &str, g: usize, at: &str, mask: &str) -> Lowering<Val> {
        if byte_size(self.m, &p.ty) > ZEROS {
            return self.gather(p, ty, mask);
        }
        let any = self.any(mask);
        let base = self.buffer_base(g);
        let real = self.op(&format!("getelementptr i8, ptr {base}, i64 {at}"));
        self.declare(&format!(
            "@cohort_zeros = private unnamed_addr constant [{ZEROS} x i8] zeroinitializer, align 64"
        ));
        let from = self.op(&format!("select i1 {any}, ptr {real}, ptr @cohort_zeros"));
        let mut parts = Vec::new();
        for l in leaves(self.m, &p.ty)? {
            let s = scalar(l.scalar)?;
            let ptr = self.op(&format!("getelementptr i8, ptr {from}, i64 {}", l.offset));
            let x = self.op(&format!("load {s}, ptr {ptr}, align 4"));
            let x = self.splat(s, &x);
            parts.push((l.path, lanes(s), x));
        }
        Ok(Val::r(ty, self.assemble(ty, parts)))
    }

    /// A buffer load at per-lane offsets. When every lane that loads reads the same
    /// address (the root of a BVH, a shared triangle) it loads once and broadcasts; when
    /// the lanes read consecutive elements (a path's state at its own slot) it loads them
    /// with one wide masked load; otherwise it gathers. The same values each way, far
    /// fewer memory operations in the first two.
    fn load_maybe_uniform(
        &mut self,
        p: &Place,
        ty: &str,
        g: usize,
        konst: u64,
        d: &str,
        mask: &str,
    ) -> Lowering<Val> {
        let v64 = lanes("i64");
        let slot = self.alloca(ty);
        let (first, d0) = self.first_lane(mask, d);
        let all = self.splat("i64", &d0);
        let same = self.op(&format!("icmp eq {v64} {d}, {all}"));
        let differ = self.not(&same);
        let differ = self.and(mask, &differ);
        let diverge = self.any(&differ);
        let (one, many, join) = (self.label(), self.label(), self.label());
        self.line(&format!("br i1 {diverge}, label %{many}, label %{one}"));
        self.body.push_str(&format!("{one}:\n"));
        let at = self.op(&format!("add i64 {d0}, {konst}"));
        let v = self.load_once(p, ty, g, &at, mask)?;
        self.line(&format!("store {}, ptr {slot}", v.typed()?));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{many}:\n"));
        let stride = match p.root {
            Root::Buf { stride, .. } => stride,
            _ => 0,
        };
        if let Some(plan) = self.wide_plan(p, stride) {
            let (ok, base0) = self.consecutive(d, &first, &d0, stride, mask);
            let (wide, scattered) = (self.label(), self.label());
            self.line(&format!("br i1 {ok}, label %{wide}, label %{scattered}"));
            self.body.push_str(&format!("{wide}:\n"));
            let at = WideAt { g, konst, base0 };
            let v = self.wide_load(&at, &plan, mask, ty);
            self.line(&format!("store {ty} {v}, ptr {slot}"));
            self.line(&format!("br label %{join}"));
            self.body.push_str(&format!("{scattered}:\n"));
        }
        let v = match self.row_plan(p) {
            Some(rows) => {
                let at = RowsAt {
                    g,
                    konst,
                    d,
                    d0: &d0,
                };
                let x = self.rows_load(&at, mask, &rows);
                Val::r(ty, self.assemble(ty, x))
            }
            None => self.gather(p, ty, mask)?,
        };
        self.line(&format!("store {}, ptr {slot}", v.typed()?));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        let r = self.op(&format!("load {ty}, ptr {slot}"));
        Ok(Val::r(ty, r))
    }

    /// The first lane on in `mask` (lane 0 when none is) and that lane's offset in `d`.
    fn first_lane(&mut self, mask: &str, d: &str) -> (String, String) {
        let first = self.first_active(mask);
        let d0 = self.op(&format!("extractelement {} {d}, i32 {first}", lanes("i64")));
        (first, d0)
    }

    /// The index (`i32`) of the first lane on in `mask` (lane 0 when none is).
    pub fn first_active(&mut self, mask: &str) -> String {
        let m = Fx::mask_ty();
        let w = super::types::w();
        let bits = self.op(&format!("bitcast {m} {mask} to i{w}"));
        self.declare(&format!("declare i{w} @llvm.cttz.i{w}(i{w}, i1)"));
        let first = self.op(&format!("call i{w} @llvm.cttz.i{w}(i{w} {bits}, i1 false)"));
        let first = self.mask_word_i32(w, &first);
        self.op(&format!("and i32 {first}, {}", w - 1))
    }

    /// An `i{w}` of mask bits (or a count of them) as an `i32`: `zext` below 32 lanes; at 32
    /// the value already is one (LLVM has no `zext` from a type to itself).
    fn mask_word_i32(&mut self, w: u32, x: &str) -> String {
        if w < 32 {
            self.op(&format!("zext i{w} {x} to i32"))
        } else {
            x.to_string()
        }
    }

    /// Whether every lane of `mask` sits at `base0 + stride * lane`, with `base0` the offset
    /// lane 0 would have (from the first lane's offset `d0`): `(i1, base0)`.
    fn consecutive(
        &mut self,
        d: &str,
        first: &str,
        d0: &str,
        stride: u64,
        mask: &str,
    ) -> (String, String) {
        let v64 = lanes("i64");
        let f64_ = self.op(&format!("zext i32 {first} to i64"));
        let back = self.op(&format!("mul i64 {f64_}, {stride}"));
        let base0 = self.op(&format!("sub i64 {d0}, {back}"));
        let steps: Vec<String> = (0..u64::from(super::types::w()))
            .map(|k| format!("i64 {}", k * stride))
            .collect();
        let b = self.splat("i64", &base0);
        let expect = self.op(&format!("add {v64} {b}, <{}>", steps.join(", ")));
        let off = self.op(&format!("icmp ne {v64} {d}, {expect}"));
        let bad = self.and(mask, &off);
        let any = self.any(&bad);
        let ok = self.op(&format!("xor i1 {any}, true"));
        (ok, base0)
    }

    /// Each leaf's lanes out of `all` (of type `vt`), which holds lane k's words from
    /// `lo` on at `k * m`: the leaves, for `assemble`.
    fn pick_leaves(
        &mut self,
        vt: &str,
        all: &str,
        m: u64,
        lo: u64,
        leaves: &[(Vec<u32>, &'static str, u64)],
    ) -> Vec<(Vec<u32>, String, String)> {
        let mut parts = Vec::with_capacity(leaves.len());
        for (path, s, word) in leaves {
            let pick: Vec<String> = (0..u64::from(super::types::w()))
                .map(|k| format!("i32 {}", k * m + word - lo))
                .collect();
            let x = self.op(&format!(
                "shufflevector {vt} {all}, {vt} poison, {} <{}>",
                lanes("i32"),
                pick.join(", ")
            ));
            let x = self.words_as(&x, s);
            parts.push((path.clone(), lanes(s), x));
        }
        parts
    }

    /// How consecutive lanes of a place read as one wide vector of 32-bit words: `m` words
    /// per lane (the array's stride), and each leaf's path, scalar and word in the lane's
    /// block. `None` where that does not pay: no stride, leaves that are not 32-bit
    /// words, or elements mostly of other members (a material's one field), whose wide
    /// load would be longer than the gathers it replaces.
    fn wide_plan(&self, p: &Place, stride: u64) -> Option<Wide> {
        if stride == 0 || stride % 4 != 0 {
            return None;
        }
        let m = stride / 4;
        let ls = leaves(self.m, &p.ty).ok()?;
        if m > 4 * ls.len() as u64 || m * u64::from(super::types::w()) > 256 {
            return None;
        }
        let mut leaves_out = Vec::with_capacity(ls.len());
        for l in ls {
            let s = scalar(l.scalar).ok()?;
            if s == "i1" || l.offset % 4 != 0 || l.offset + 4 > stride {
                return None;
            }
            leaves_out.push((l.path, s, l.offset / 4));
        }
        Some(Wide {
            m,
            leaves: leaves_out,
        })
    }

    /// `<W*m x i1>`: lane `k`'s mask bit on the words of its block that `plan` reads.
    fn wide_mask(&mut self, plan: &Wide, mask: &str) -> (String, String) {
        let w = u64::from(super::types::w());
        let n = w * plan.m;
        let spread: Vec<String> = (0..n).map(|j| format!("i32 {}", j / plan.m)).collect();
        let e = self.op(&format!(
            "shufflevector {} {mask}, {} poison, <{n} x i32> <{}>",
            Fx::mask_ty(),
            Fx::mask_ty(),
            spread.join(", ")
        ));
        let used: Vec<String> = (0..n)
            .map(|j| {
                let on = plan.leaves.iter().any(|l| l.2 == j % plan.m);
                format!("i1 {on}")
            })
            .collect();
        let ty = format!("<{n} x i1>");
        let e = self.op(&format!("and {ty} {e}, <{}>", used.join(", ")));
        (e, ty)
    }

    /// The address of lane 0's block: binding `g`'s base plus `konst + base0`.
    fn wide_pointer(&mut self, at: &WideAt) -> String {
        let base = self.buffer_base(at.g);
        let off = self.op(&format!("add i64 {}, {}", at.base0, at.konst));
        self.op(&format!("getelementptr i8, ptr {base}, i64 {off}"))
    }

    /// Loads consecutive lanes' blocks with one masked load and picks each leaf's lanes.
    fn wide_load(&mut self, at: &WideAt, plan: &Wide, mask: &str, ty: &str) -> String {
        let w = u64::from(super::types::w());
        let n = w * plan.m;
        let ptr = self.wide_pointer(at);
        let (e, mty) = self.wide_mask(plan, mask);
        let vt = format!("<{n} x i32>");
        self.declare(&format!(
            "declare {vt} @llvm.masked.load.v{n}i32.p0(ptr, i32, {mty}, {vt})"
        ));
        let wide = self.op(&format!(
            "call {vt} @llvm.masked.load.v{n}i32.p0(ptr {ptr}, i32 4, {mty} {e}, {vt} zeroinitializer)"
        ));
        let parts = self.pick_leaves(&vt, &wide, plan.m, 0, &plan.leaves);
        self.assemble(ty, parts)
    }

    /// Stores consecutive lanes' leaves of `value` with one masked store.
    fn wide_store(&mut self, at: &WideAt, plan: &Wide, mask: &str, value: &Val) -> Lowering<()> {
        let w = u64::from(super::types::w());
        let n = w * plan.m;
        let (joined, len) = self.leaves_as_words(value, &plan.leaves)?;
        let place: Vec<String> = (0..n)
            .map(|j| {
                let (k, word) = (j / plan.m, j % plan.m);
                match plan.leaves.iter().position(|l| l.2 == word) {
                    Some(leaf) => format!("i32 {}", leaf as u64 * w + k),
                    None => "i32 undef".to_string(),
                }
            })
            .collect();
        let vt = format!("<{n} x i32>");
        let wide = self.op(&format!(
            "shufflevector <{len} x i32> {joined}, <{len} x i32> poison, <{n} x i32> <{}>",
            place.join(", ")
        ));
        let ptr = self.wide_pointer(at);
        let (e, mty) = self.wide_mask(plan, mask);
        self.declare(&format!(
            "declare void @llvm.masked.store.v{n}i32.p0({vt}, ptr, i32, {mty})"
        ));
        self.line(&format!(
            "call void @llvm.masked.store.v{n}i32.p0({vt} {wide}, ptr {ptr}, i32 4, {mty} {e})"
        ));
        Ok(())
    }

    /// A leaf's lanes (scalar `s`, 32 bits) as `<W x i32>`, for moving words.
    pub(super) fn as_words(&mut self, x: &str, s: &str) -> String {
        if s == "i32" {
            return x.to_string();
        }
        self.op(&format!("bitcast {} {x} to {}", lanes(s), lanes("i32")))
    }

    /// [`Fx::as_words`] undone: `<W x i32>` as lanes of scalar `s`.
    pub(super) fn words_as(&mut self, x: &str, s: &str) -> String {
        if s == "i32" {
            return x.to_string();
        }
        self.op(&format!("bitcast {} {x} to {}", lanes("i32"), lanes(s)))
    }

    /// The `leaves` of `value`, each as `<W x i32>`, in one vector of `W * P` words (P the
    /// next power of two of their count, the padding poison): leaf j's lane k at j * W + k.
    /// The vector and its length.
    fn leaves_as_words(
        &mut self,
        value: &Val,
        leaves: &[(Vec<u32>, &'static str, u64)],
    ) -> Lowering<(String, u64)> {
        let mut level = Vec::with_capacity(leaves.len());
        for (path, s, _) in leaves {
            let x = self.leaf_of(value, path)?;
            level.push(self.as_words(&x, s));
        }
        if level.is_empty() {
            return Err("a store of no leaves".into());
        }
        Ok(self.concat(level, u64::from(super::types::w())))
    }

    /// Vectors of `len` words each (at least one), concatenated pairwise into one vector
    /// of `len * P` words, P the next power of two of their count (the padding poison):
    /// the vector and its length.
    pub(super) fn concat(&mut self, mut level: Vec<String>, len: u64) -> (String, u64) {
        let mut len = len;
        while level.len() > 1 {
            if level.len() % 2 == 1 {
                level.push("poison".to_string());
            }
            let ids: Vec<String> = (0..2 * len).map(|j| format!("i32 {j}")).collect();
            let mut next = Vec::with_capacity(level.len() / 2);
            for pair in level.chunks(2) {
                next.push(self.op(&format!(
                    "shufflevector <{len} x i32> {}, <{len} x i32> {}, <{} x i32> <{}>",
                    pair[0],
                    pair[1],
                    2 * len,
                    ids.join(", ")
                )));
            }
            level = next;
            len *= 2;
        }
        (level.swap_remove(0), len)
    }

    /// The leaf at `path` of `value` (the value itself for an empty path).
    pub(super) fn leaf_of(&mut self, value: &Val, path: &[u32]) -> Lowering<String> {
        if path.is_empty() {
            return Ok(value.v()?.to_string());
        }
        let at: Vec<String> = path.iter().map(|c| c.to_string()).collect();
        Ok(self.op(&format!(
            "extractvalue {}, {}",
            value.typed()?,
            at.join(", ")
        )))
    }

    /// A value of LLVM type `ty` from its leaves (path, vector type, value); a scalar
    /// type's one leaf is the value itself.
    fn assemble(&mut self, ty: &str, parts: Vec<(Vec<u32>, String, String)>) -> String {
        if parts.len() == 1 && parts[0].0.is_empty() {
            return parts[0].2.clone();
        }
        let mut acc = "poison".to_string();
        for (path, vt, x) in parts {
            let at: Vec<String> = path.iter().map(|c| c.to_string()).collect();
            acc = self.op(&format!(
                "insertvalue {ty} {acc}, {vt} {x}, {}",
                at.join(", ")
            ));
        }
        acc
    }

    /// Loads each scalar leaf with a masked gather.
    fn gather(&mut self, p: &Place, ty: &str, mask: &str) -> Lowering<Val> {
        let mut parts = Vec::new();
        for (path, s, ptrs) in self.leaf_pointers(p)? {
            let sfx = intrinsic_suffix(&s);
            let v = lanes(&s);
            self.declare(&format!(
                "declare {v} @llvm.masked.gather.v{w}{sfx}.v{w}p0({}, i32, {}, {v})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::w()
            ));
            let x = self.op(&format!(
                "call {v} @llvm.masked.gather.v{w}{sfx}.v{w}p0({} {ptrs}, i32 4, {} {mask}, {v} zeroinitializer)",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::w()
            ));
            parts.push((path, v, x));
        }
        let acc = self.assemble(ty, parts);
        Ok(Val::r(ty, acc))
    }

    /// Stores `value` under `mask`: one wide masked store where the lanes' elements are
    /// consecutive, else a masked scatter per leaf.
    pub fn store(&mut self, p: &Place, value: &Val, mask: &str) -> Lowering<()> {
        let ty = value_type(self.m, &p.ty)?;
        if holds_atomic(self.m, &p.ty) {
            self.flush_deferred();
        }
        if let Some(addr) = self.uniform_local(p) {
            let old = self.op(&format!("load {ty}, ptr {addr}"));
            let new = self.blend_typed(mask, value, &Val::r(ty.clone(), old), &p.ty.clone())?;
            self.line(&format!("store {}, ptr {addr}", new.typed()?));
            return Ok(());
        }
        let mask = self.in_bounds(p, mask)?;
        let Root::Buf {
            g,
            konst,
            dynamic: Some(d),
            stride,
        } = p.root.clone()
        else {
            return self.scatter(p, value, &mask);
        };
        let (first, d0) = self.first_lane(&mask, &d);
        let at = RowsAt {
            g,
            konst,
            d: &d,
            d0: &d0,
        };
        let Some(plan) = self.wide_plan(p, stride) else {
            return self.scattered_store(p, value, &mask, &at);
        };
        let (ok, base0) = self.consecutive(&d, &first, &d0, stride, &mask);
        let (wide, scattered, join) = (self.label(), self.label(), self.label());
        self.line(&format!("br i1 {ok}, label %{wide}, label %{scattered}"));
        self.body.push_str(&format!("{wide}:\n"));
        self.wide_store(&WideAt { g, konst, base0 }, &plan, &mask, value)?;
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{scattered}:\n"));
        self.scattered_store(p, value, &mask, &at)?;
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        Ok(())
    }

    /// A buffer store at per-lane offsets `d` (binding `g`, plus `konst`; `d0` the first
    /// running lane's) that are neither all one nor consecutive: a struct or vector as one
    /// row per lane (a scatter costs 3.6 ns per 8 lanes whatever its mask, as a gather
    /// does), a scalar scattered.
    fn scattered_store(&mut self, p: &Place, value: &Val, mask: &str, at: &RowsAt) -> Lowering<()> {
        match self.row_plan(p) {
            Some(plan) => self.rows_store(at, mask, &plan, value),
            None => self.scatter(p, value, mask),
        }
    }

    /// Stores each scalar leaf with a masked scatter.
    fn scatter(&mut self, p: &Place, value: &Val, mask: &str) -> Lowering<()> {
        for (path, s, ptrs) in self.leaf_pointers(p)? {
            let v = lanes(&s);
            let x = self.leaf_of(value, &path)?;
            let sfx = intrinsic_suffix(&s);
            self.declare(&format!(
                "declare void @llvm.masked.scatter.v{w}{sfx}.v{w}p0({v}, {}, i32, {})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::w()
            ));
            self.line(&format!(
                "call void @llvm.masked.scatter.v{w}{sfx}.v{w}p0({v} {x}, {} {ptrs}, i32 4, {} {mask})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::w()
            ));
        }
        Ok(())
    }

    /// `mask ? new : old` for each lane, leaf by leaf.
    pub fn blend_typed(
        &mut self,
        mask: &str,
        new: &Val,
        old: &Val,
        t: &TypeInner,
    ) -> Lowering<Val> {
        let ty = value_type(self.m, t)?;
        let ls = leaves(self.m, t)?;
        if ls.len() == 1 && ls[0].path.is_empty() {
            let v = self.op(&format!(
                "select {} {mask}, {}, {}",
                Fx::mask_ty(),
                new.typed()?,
                old.typed()?
            ));
            return Ok(Val::r(ty, v));
        }
        let mut acc = old.v()?.to_string();
        for l in ls {
            let at: Vec<String> = l.path.iter().map(|c| c.to_string()).collect();
            let at = at.join(", ");
            let v = lanes(scalar(l.scalar)?);
            let a = self.op(&format!("extractvalue {}, {at}", new.typed()?));
            let b = self.op(&format!("extractvalue {}, {at}", old.typed()?));
            let s = self.op(&format!(
                "select {} {mask}, {v} {a}, {v} {b}",
                Fx::mask_ty()
            ));
            acc = self.op(&format!("insertvalue {ty} {acc}, {v} {s}, {at}"));
        }
        Ok(Val::r(ty, acc))
    }

    /// `mask ? new : old` for a function's return value.
    pub fn blend(&mut self, mask: &str, new: &Val, old: &Val) -> Lowering<Val> {
        let r = self
            .fun
            .result
            .as_ref()
            .ok_or("a value returned from a void function")?;
        let t = self.m.types[r.ty].inner.clone();
        self.blend_typed(mask, new, old, &t)
    }

    /// Where every lane of `mask` adds (`op` `add` or `sub`) the same value at the same
    /// address, as a kernel counts what it finished, one atomic adds the value times the
    /// number of lanes, and each lane's old value is what the lane-by-lane loop would give
    /// it (the old value plus the value times the lanes before it). Lanes that contend for
    /// one cache line then make one locked operation per block instead of one each. With
    /// `deferred` (a site whose old values nobody reads), the block's sum is added to the
    /// site's pending sum instead ([`Fx::defer_add`]). Falls through to the lane-by-lane
    /// loop otherwise; branches to `join` when done.
    #[allow(clippy::too_many_arguments)]
    fn atomic_add_once(
        &mut self,
        op: &str,
        mask: &str,
        ptrs: &str,
        val: &str,
        old_slot: &str,
        join: &str,
        deferred: Option<u32>,
    ) {
        let w = super::types::w();
        let (v, v64, m) = (lanes("i32"), lanes("i64"), Fx::mask_ty());
        let first = self.first_active(mask);
        let p0 = self.op(&format!(
            "extractelement {} {ptrs}, i32 {first}",
            lanes("ptr")
        ));
        let at = self.op(&format!("ptrtoint {} {ptrs} to {v64}", lanes("ptr")));
        let at0 = self.op(&format!("ptrtoint ptr {p0} to i64"));
        let at0s = self.splat("i64", &at0);
        let same_at = self.op(&format!("icmp eq {v64} {at}, {at0s}"));
        let x0 = self.op(&format!("extractelement {v} {val}, i32 {first}"));
        let x0s = self.splat("i32", &x0);
        let same_x = self.op(&format!("icmp eq {v} {val}, {x0s}"));
        let same = self.and(&same_at, &same_x);
        let differ = self.not(&same);
        let differ = self.and(mask, &differ);
        let diverge = self.any(&differ);
        let none = self.not(mask);
        let none = self.op(&format!(
            "call i1 @llvm.vector.reduce.and.v{w}i1({m} {none})"
        ));
        self.declare(&format!("declare i1 @llvm.vector.reduce.and.v{w}i1({m})"));
        let either = self.op(&format!("or i1 {diverge}, {none}"));
        let (once, lanes_) = (self.label(), self.label());
        self.line(&format!("br i1 {either}, label %{lanes_}, label %{once}"));
        self.body.push_str(&format!("{once}:\n"));
        let bits = self.op(&format!("bitcast {m} {mask} to i{w}"));
        self.declare(&format!("declare i{w} @llvm.ctpop.i{w}(i{w})"));
        let count = self.op(&format!("call i{w} @llvm.ctpop.i{w}(i{w} {bits})"));
        let count = self.mask_word_i32(w, &count);
        let total = self.op(&format!("mul i32 {x0}, {count}"));
        if let Some(site) = deferred {
            let delta = match op {
                "sub" => self.op(&format!("sub i32 0, {total}")),
                _ => total,
            };
            self.defer_add(site, &p0, &delta);
            self.line(&format!("br label %{join}"));
            self.body.push_str(&format!("{lanes_}:\n"));
            return;
        }
        let old = self.op(&format!("atomicrmw {op} ptr {p0}, i32 {total} seq_cst"));
        // Each lane's count of running lanes before it.
        let bits32 = self.mask_word_i32(w, &bits);
        let bits32 = self.splat("i32", &bits32);
        let below: Vec<String> = (0..w).map(|l| format!("i32 {}", (1u32 << l) - 1)).collect();
        let before = self.op(&format!("and {v} {bits32}, <{}>", below.join(", ")));
        self.declare(&format!("declare {v} @llvm.ctpop.v{w}i32({v})"));
        let before = self.op(&format!("call {v} @llvm.ctpop.v{w}i32({v} {before})"));
        let step = self.op(&format!("mul {v} {x0s}, {before}"));
        let olds = self.splat("i32", &old);
        let olds = self.op(&format!("{op} {v} {olds}, {step}"));
        self.line(&format!("store {v} {olds}, ptr {old_slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{lanes_}:\n"));
    }

    /// Adds `delta` (`i32`) to deferred site `site`'s pending sum for address `p`. A site
    /// holds one address: a different one first adds the pending sum to the old address.
    /// The sums live in the run's context (`%err`, `deferred::DEFERRED_AT`) and are added by one
    /// atomic each when the run ends or before any other atomic access
    /// ([`Fx::flush_deferred`]).
    fn defer_add(&mut self, site: u32, p: &str, delta: &str) {
        let (at_ptr, at_sum) = deferred_offsets(site);
        let sp = self.op(&format!("getelementptr i8, ptr %err, i64 {at_ptr}"));
        let sv = self.op(&format!("getelementptr i8, ptr %err, i64 {at_sum}"));
        let cur = self.op(&format!("load ptr, ptr {sp}"));
        let pending = self.op(&format!("load i32, ptr {sv}"));
        let same = self.op(&format!("icmp eq ptr {cur}, {p}"));
        let empty = self.op(&format!("icmp eq i32 {pending}, 0"));
        let keep = self.op(&format!("or i1 {same}, {empty}"));
        let (flush, add) = (self.label(), self.label());
        let from = self.label();
        self.line(&format!("br label %{from}"));
        self.body.push_str(&format!("{from}:\n"));
        self.line(&format!("br i1 {keep}, label %{add}, label %{flush}"));
        self.body.push_str(&format!("{flush}:\n"));
        self.op(&format!("atomicrmw add ptr {cur}, i32 {pending} seq_cst"));
        self.line(&format!("br label %{add}"));
        self.body.push_str(&format!("{add}:\n"));
        let base = self.op(&format!("phi i32 [ {pending}, %{from} ], [ 0, %{flush} ]"));
        let sum = self.op(&format!("add i32 {base}, {delta}"));
        self.line(&format!("store ptr {p}, ptr {sp}"));
        self.line(&format!("store i32 {sum}, ptr {sv}"));
    }

    /// Adds every deferred site's pending sum, before an atomic access that could see it.
    pub(super) fn flush_deferred(&mut self) {
        self.line(&format!("call void @{FLUSH}(ptr %err)"));
    }

    /// An atomic read-modify-write, one lane after another (in lane order, as the host
    /// form runs its invocations), or, for an add that every lane makes alike, once.
    pub fn atomic(
        &mut self,
        pointer: Handle<naga::Expression>,
        fun: &naga::AtomicFunction,
        value: Handle<naga::Expression>,
        result: Option<Handle<naga::Expression>>,
    ) -> Lowering<()> {
        let p = self.place(pointer)?;
        let s = match p.ty {
            TypeInner::Atomic(s) if s.kind != ScalarKind::Float => s,
            ref other => return Err(format!("atomics on {other:?}")),
        };
        if !matches!(p.root, Root::Buf { .. }) {
            return Err("atomics outside buffers".into());
        }
        let signed = s.kind == ScalarKind::Sint;
        let e = self.exec();
        let mask = self.in_bounds(&p, &e)?;
        let (_, _, ptrs) = self.leaf_pointers(&p)?.remove(0);
        let val = self.val(value)?.v()?.to_string();
        let cmp = match fun {
            naga::AtomicFunction::Exchange { compare: Some(c) } => {
                Some(self.val(*c)?.v()?.to_string())
            }
            _ => None,
        };
        let op = match fun {
            naga::AtomicFunction::Add => "add",
            naga::AtomicFunction::Subtract => "sub",
            naga::AtomicFunction::And => "and",
            naga::AtomicFunction::InclusiveOr => "or",
            naga::AtomicFunction::ExclusiveOr => "xor",
            naga::AtomicFunction::Min if signed => "min",
            naga::AtomicFunction::Min => "umin",
            naga::AtomicFunction::Max if signed => "max",
            naga::AtomicFunction::Max => "umax",
            naga::AtomicFunction::Exchange { .. } => "xchg",
        };
        let v = lanes("i32");
        let old_slot = self.alloca(&v);
        let done_slot = self.alloca(&Fx::mask_ty());
        self.line(&format!("store {v} zeroinitializer, ptr {old_slot}"));
        self.line(&format!(
            "store {} zeroinitializer, ptr {done_slot}",
            Fx::mask_ty()
        ));
        let join = self.label();
        let adds = matches!(
            fun,
            naga::AtomicFunction::Add | naga::AtomicFunction::Subtract
        );
        // An add whose old value no expression reads: nothing in the dispatch can tell
        // when it lands, except an atomic access that flushes the pending sums first.
        let unread = result.is_none_or(|r| self.info[r].ref_count == 0);
        let deferred = (adds && unread).then(|| {
            let site = *self.sites;
            *self.sites += 1;
            site
        });
        if deferred.is_none() {
            self.flush_deferred();
        }
        if adds {
            self.atomic_add_once(op, &mask, &ptrs, &val, &old_slot, &join, deferred);
        }
        for lane in 0..super::types::w() {
            let on = self.op(&format!(
                "extractelement {} {mask}, i32 {lane}",
                Fx::mask_ty()
            ));
            let (run, next) = (self.label(), self.label());
            self.line(&format!("br i1 {on}, label %{run}, label %{next}"));
            self.body.push_str(&format!("{run}:\n"));
            let ptr = self.op(&format!(
                "extractelement {} {ptrs}, i32 {lane}",
                lanes("ptr")
            ));
            let x = self.op(&format!("extractelement {v} {val}, i32 {lane}"));
            let old = match &cmp {
                Some(c) => {
                    let want = self.op(&format!("extractelement {v} {c}, i32 {lane}"));
                    let pair = self.op(&format!(
                        "cmpxchg ptr {ptr}, i32 {want}, i32 {x} seq_cst seq_cst"
                    ));
                    let ok = self.op(&format!("extractvalue {{ i32, i1 }} {pair}, 1"));
                    let d = self.op(&format!("load {}, ptr {done_slot}", Fx::mask_ty()));
                    let d = self.op(&format!(
                        "insertelement {} {d}, i1 {ok}, i32 {lane}",
                        Fx::mask_ty()
                    ));
                    self.line(&format!("store {} {d}, ptr {done_slot}", Fx::mask_ty()));
                    self.op(&format!("extractvalue {{ i32, i1 }} {pair}, 0"))
                }
                None => self.op(&format!("atomicrmw {op} ptr {ptr}, i32 {x} seq_cst")),
            };
            let acc = self.op(&format!("load {v}, ptr {old_slot}"));
            let acc = self.op(&format!("insertelement {v} {acc}, i32 {old}, i32 {lane}"));
            self.line(&format!("store {v} {acc}, ptr {old_slot}"));
            self.line(&format!("br label %{next}"));
            self.body.push_str(&format!("{next}:\n"));
        }
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        if let Some(r) = result {
            let old = self.op(&format!("load {v}, ptr {old_slot}"));
            let out = if cmp.is_some() {
                let m = Fx::mask_ty();
                let d = self.op(&format!("load {m}, ptr {done_slot}"));
                let a = self.op(&format!("insertvalue {{ {v}, {m} }} poison, {v} {old}, 0"));
                let b = self.op(&format!("insertvalue {{ {v}, {m} }} {a}, {m} {d}, 1"));
                Val::r(format!("{{ {v}, {m} }}"), b)
            } else {
                Val::r(v.clone(), old)
            };
            self.vals[r.index()] = Some(out);
        }
        Ok(())
    }
}
