//! Pointers, loads, stores and atomics of the vector form. A naga pointer is a [`Place`]: a
//! buffer binding plus a byte offset per lane, or a local variable (a stack slot holding all
//! lanes, structure of arrays) plus an index path. Places whose path is the same for every
//! lane load and store whole registers; others gather and scatter one scalar leaf at a time.
//! Every access is bounds-checked: an out-of-range lane sets the dispatch's error flag and
//! is masked off, where the host form would panic.

use naga::{Handle, ScalarKind, TypeInner};

use super::lower::{Fx, Val};
use super::types::{byte_size, iota, lanes, leaves, scalar, splat_const, value_type, Lowering};

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
    /// when the lanes' offsets differ).
    Buf {
        g: usize,
        konst: u64,
        dynamic: Option<String>,
    },
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
            Root::Local {
                slot,
                slot_ty,
                mut path,
            } => {
                path.push(Idx::Dyn(
                    index.v()?.to_string(),
                    len.ok_or("a runtime-sized local")?,
                ));
                Root::Local {
                    slot,
                    slot_ty,
                    path,
                }
            }
            Root::Buf { g, konst, dynamic } => {
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
            Root::Local {
                slot,
                slot_ty,
                mut path,
            } => {
                path.push(Idx::Const(index));
                Root::Local {
                    slot,
                    slot_ty,
                    path,
                }
            }
            Root::Buf { g, konst, dynamic } => Root::Buf {
                g,
                konst: konst + offset,
                dynamic,
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
            Root::Buf { g, konst, dynamic } => {
                let size = self.buffer_size(*g);
                let end = konst + byte_size(self.m, &p.ty);
                let c = match dynamic {
                    Some(d) => {
                        let v64 = lanes("i64");
                        let e = self.op(&format!(
                            "add {v64} {d}, {}",
                            splat_const("i64", &end.to_string())
                        ));
                        let s = self.splat("i64", &size);
                        self.op(&format!("icmp ule {v64} {e}, {s}"))
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
    fn buffer_base(&mut self, g: usize) -> String {
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
            Root::Buf { g, konst, dynamic } => {
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
    fn uniform_local(&mut self, p: &Place) -> Option<String> {
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
        } = &p.root
        {
            return self.load_maybe_uniform(p, &ty, *g, *konst, d, &mask);
        }
        self.gather(p, &ty, &mask)
    }

    /// A buffer load at per-lane offsets that, when every lane that loads reads the same
    /// address (the root of a BVH, a shared triangle), loads once and broadcasts instead
    /// of gathering: the same values, far fewer memory operations.
    fn load_maybe_uniform(
        &mut self,
        p: &Place,
        ty: &str,
        g: usize,
        konst: u64,
        d: &str,
        mask: &str,
    ) -> Lowering<Val> {
        let m = Fx::mask_ty();
        let v64 = lanes("i64");
        let w = super::types::W;
        let slot = self.alloca(ty);
        let bits = self.op(&format!("bitcast {m} {mask} to i{w}"));
        self.declare(&format!("declare i{w} @llvm.cttz.i{w}(i{w}, i1)"));
        let first = self.op(&format!("call i{w} @llvm.cttz.i{w}(i{w} {bits}, i1 false)"));
        let first = self.op(&format!("zext i{w} {first} to i32"));
        let first = self.op(&format!("and i32 {first}, {}", w - 1));
        let d0 = self.op(&format!("extractelement {v64} {d}, i32 {first}"));
        let all = self.splat("i64", &d0);
        let same = self.op(&format!("icmp eq {v64} {d}, {all}"));
        let differ = self.not(&same);
        let differ = self.and(mask, &differ);
        let diverge = self.any(&differ);
        let (one, many, join) = (self.label(), self.label(), self.label());
        self.line(&format!("br i1 {diverge}, label %{many}, label %{one}"));
        self.body.push_str(&format!("{one}:\n"));
        let any = self.any(mask);
        let (load, skip) = (self.label(), self.label());
        self.line(&format!("br i1 {any}, label %{load}, label %{skip}"));
        self.body.push_str(&format!("{load}:\n"));
        let base = self.buffer_base(g);
        let mut acc = "poison".to_string();
        let ls = leaves(self.m, &p.ty)?;
        let single = ls.len() == 1 && ls[0].path.is_empty();
        for l in ls {
            let s = scalar(l.scalar)?;
            let at = self.op(&format!("add i64 {d0}, {}", konst + l.offset));
            let ptr = self.op(&format!("getelementptr i8, ptr {base}, i64 {at}"));
            let x = self.op(&format!("load {s}, ptr {ptr}, align 4"));
            let x = self.splat(s, &x);
            if single {
                acc = x;
            } else {
                let at: Vec<String> = l.path.iter().map(|c| c.to_string()).collect();
                acc = self.op(&format!(
                    "insertvalue {ty} {acc}, {} {x}, {}",
                    lanes(s),
                    at.join(", ")
                ));
            }
        }
        self.line(&format!("store {ty} {acc}, ptr {slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{skip}:\n"));
        self.line(&format!("store {ty} zeroinitializer, ptr {slot}"));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{many}:\n"));
        let v = self.gather(p, ty, mask)?;
        self.line(&format!("store {}, ptr {slot}", v.typed()?));
        self.line(&format!("br label %{join}"));
        self.body.push_str(&format!("{join}:\n"));
        let r = self.op(&format!("load {ty}, ptr {slot}"));
        Ok(Val::r(ty, r))
    }

    /// Loads each scalar leaf with a masked gather.
    fn gather(&mut self, p: &Place, ty: &str, mask: &str) -> Lowering<Val> {
        let ty = ty.to_string();
        let mut acc = "poison".to_string();
        let parts = self.leaf_pointers(p)?;
        let single = parts.len() == 1 && parts[0].0.is_empty();
        for (path, s, ptrs) in parts {
            let sfx = intrinsic_suffix(&s);
            let v = lanes(&s);
            self.declare(&format!(
                "declare {v} @llvm.masked.gather.v{w}{sfx}.v{w}p0({}, i32, {}, {v})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::W
            ));
            let x = self.op(&format!(
                "call {v} @llvm.masked.gather.v{w}{sfx}.v{w}p0({} {ptrs}, i32 4, {} {mask}, {v} zeroinitializer)",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::W
            ));
            if single {
                return Ok(Val::r(ty, x));
            }
            let at: Vec<String> = path.iter().map(|c| c.to_string()).collect();
            acc = self.op(&format!(
                "insertvalue {ty} {acc}, {v} {x}, {}",
                at.join(", ")
            ));
        }
        Ok(Val::r(ty, acc))
    }

    pub fn store(&mut self, p: &Place, value: &Val, mask: &str) -> Lowering<()> {
        let ty = value_type(self.m, &p.ty)?;
        if let Some(addr) = self.uniform_local(p) {
            let old = self.op(&format!("load {ty}, ptr {addr}"));
            let new = self.blend_typed(mask, value, &Val::r(ty.clone(), old), &p.ty.clone())?;
            self.line(&format!("store {}, ptr {addr}", new.typed()?));
            return Ok(());
        }
        let mask = self.in_bounds(p, mask)?;
        for (path, s, ptrs) in self.leaf_pointers(p)? {
            let v = lanes(&s);
            let x = if path.is_empty() {
                value.v()?.to_string()
            } else {
                let at: Vec<String> = path.iter().map(|c| c.to_string()).collect();
                self.op(&format!(
                    "extractvalue {}, {}",
                    value.typed()?,
                    at.join(", ")
                ))
            };
            let sfx = intrinsic_suffix(&s);
            self.declare(&format!(
                "declare void @llvm.masked.scatter.v{w}{sfx}.v{w}p0({v}, {}, i32, {})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::W
            ));
            self.line(&format!(
                "call void @llvm.masked.scatter.v{w}{sfx}.v{w}p0({v} {x}, {} {ptrs}, i32 4, {} {mask})",
                lanes("ptr"),
                Fx::mask_ty(),
                w = super::types::W
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

    /// An atomic read-modify-write, one lane after another (in lane order, as the host
    /// form runs its invocations).
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
        for lane in 0..super::types::W {
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
