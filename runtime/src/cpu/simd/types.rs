//! How naga types look in the vector form: every value holds all `W` lanes of a block, with
//! each scalar leaf a `<W x T>` LLVM vector (structure of arrays), and where their scalar
//! leaves lie in a buffer (the GPU layout the host shares). `W`, here and in the comments of
//! the lowering, is the width of the kernel being lowered ([`w`]).

use std::cell::Cell;

use naga::{Module, Scalar, ScalarKind, TypeInner, VectorSize};

/// Lanes per block where no JIT says what the CPU's registers hold (`width`): one AVX2
/// register of `f32`s.
pub const DEFAULT_WIDTH: u32 = 8;

/// The widths a lowering takes: powers of two up to 32, the most one `i32` mask word holds.
pub const WIDTHS: [u32; 3] = [8, 16, 32];

thread_local! {
    /// The width of the lowering running on this thread (`Width`).
    static WIDTH: Cell<u32> = const { Cell::new(DEFAULT_WIDTH) };
}

/// Lanes per block of the kernel being lowered on this thread: every value holds this many.
pub fn w() -> u32 {
    WIDTH.with(Cell::get)
}

/// Sets this thread's lowering width until dropped (one kernel's lowering).
pub struct Width(u32);

impl Width {
    pub fn set(lanes: u32) -> Width {
        debug_assert!(WIDTHS.contains(&lanes), "{lanes} lanes");
        Width(WIDTH.with(|c| c.replace(lanes)))
    }
}

impl Drop for Width {
    fn drop(&mut self) {
        WIDTH.with(|c| c.set(self.0));
    }
}

pub type Lowering<T> = Result<T, String>;

/// The LLVM scalar type of a naga scalar the vector form supports.
pub fn scalar(s: Scalar) -> Lowering<&'static str> {
    match (s.kind, s.width) {
        (ScalarKind::Bool, _) => Ok("i1"),
        (ScalarKind::Sint | ScalarKind::Uint, 4) => Ok("i32"),
        (ScalarKind::Float, 4) => Ok("float"),
        _ => Err(format!(
            "scalars of kind {:?} and width {}",
            s.kind, s.width
        )),
    }
}

/// `<W x s>`.
pub fn lanes(s: &str) -> String {
    format!("<{} x {s}>", w())
}

pub fn size_of(v: VectorSize) -> u32 {
    v as u32
}

/// The LLVM type of a value of naga type `t` in the vector form.
pub fn value_type(m: &Module, t: &TypeInner) -> Lowering<String> {
    Ok(match *t {
        TypeInner::Scalar(s) | TypeInner::Atomic(s) => lanes(scalar(s)?),
        TypeInner::Vector { size, scalar: s } => {
            format!("[{} x {}]", size_of(size), lanes(scalar(s)?))
        }
        TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => format!(
            "[{} x [{} x {}]]",
            size_of(columns),
            size_of(rows),
            lanes(scalar(s)?)
        ),
        TypeInner::Struct { ref members, .. } => {
            let parts = members
                .iter()
                .map(|mem| value_type(m, &m.types[mem.ty].inner))
                .collect::<Lowering<Vec<_>>>()?;
            format!("{{ {} }}", parts.join(", "))
        }
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            ..
        } => format!("[{} x {}]", n, value_type(m, &m.types[base].inner)?),
        ref other => return Err(format!("values of type {other:?}")),
    })
}

/// One scalar leaf of a type: its index path in the vector form's aggregate, its byte offset
/// in the buffer layout and its scalar.
#[derive(Clone, Debug)]
pub struct Leaf {
    pub path: Vec<u32>,
    pub offset: u64,
    pub scalar: Scalar,
}

/// Larger values are not worth a vector form (and would make huge code).
const MAX_LEAVES: usize = 4096;

/// Every scalar leaf of `t`, in order.
pub fn leaves(m: &Module, t: &TypeInner) -> Lowering<Vec<Leaf>> {
    let mut out = Vec::new();
    collect(m, t, &mut Vec::new(), 0, &mut out)?;
    Ok(out)
}

fn collect(
    m: &Module,
    t: &TypeInner,
    path: &mut Vec<u32>,
    offset: u64,
    out: &mut Vec<Leaf>,
) -> Lowering<()> {
    if out.len() > MAX_LEAVES {
        return Err("a value with more than 4096 scalars".into());
    }
    match *t {
        TypeInner::Scalar(s) | TypeInner::Atomic(s) => out.push(Leaf {
            path: path.clone(),
            offset,
            scalar: s,
        }),
        TypeInner::Vector { size, scalar: s } => {
            for i in 0..size_of(size) {
                path.push(i);
                out.push(Leaf {
                    path: path.clone(),
                    offset: offset + u64::from(i * s.width as u32),
                    scalar: s,
                });
                path.pop();
            }
        }
        TypeInner::Matrix {
            columns,
            rows,
            scalar: s,
        } => {
            // Columns are aligned like vectors of their row count (vec3 columns to 16 bytes).
            let stride: u64 = if rows == VectorSize::Bi { 8 } else { 16 };
            for c in 0..size_of(columns) {
                for r in 0..size_of(rows) {
                    out.push(Leaf {
                        path: [path.as_slice(), &[c, r]].concat(),
                        offset: offset + u64::from(c) * stride + u64::from(r * 4),
                        scalar: s,
                    });
                }
            }
        }
        TypeInner::Struct { ref members, .. } => {
            for (i, mem) in members.iter().enumerate() {
                path.push(i as u32);
                collect(
                    m,
                    &m.types[mem.ty].inner,
                    path,
                    offset + u64::from(mem.offset),
                    out,
                )?;
                path.pop();
            }
        }
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            stride,
        } => {
            for i in 0..n.get() {
                path.push(i);
                collect(
                    m,
                    &m.types[base].inner,
                    path,
                    offset + u64::from(i * stride),
                    out,
                )?;
                path.pop();
            }
        }
        ref other => return Err(format!("values of type {other:?}")),
    }
    Ok(())
}

/// Bytes a value of type `t` covers in a buffer.
pub fn byte_size(m: &Module, t: &TypeInner) -> u64 {
    u64::from(t.size(m.to_ctx()))
}

/// An LLVM constant vector with every lane `v` (text of the value, without its type).
pub fn splat_const(s: &str, v: &str) -> String {
    let one = format!("{s} {v}");
    format!("<{}>", vec![one; w() as usize].join(", "))
}

/// `<0, 1, ..., w()-1>` as an `i32` constant vector.
pub fn iota() -> String {
    let parts: Vec<String> = (0..w()).map(|i| format!("i32 {i}")).collect();
    format!("<{}>", parts.join(", "))
}

/// An `f32` as LLVM IR writes float constants: the bits of the equal `f64`, in hex.
pub fn float_text(v: f32) -> String {
    format!("0x{:016X}", f64::from(v).to_bits())
}
