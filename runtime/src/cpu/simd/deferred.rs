//! Deferred atomic adds. A kernel that counts what it finished (`completed[0].fetch_add(1)`,
//! the old value unread) made one locked add per vector block, and on 16 cores those
//! adds fought over the counter's cache line (BENCHMARKS.md: `extend` 0.83-0.88x of its
//! time without them). Such an add now goes to a pending sum per site in the run's
//! context, and each site's sum is added by one atomic when the run ends (`cohort_run`'s
//! range of workgroups: the backend passes one workgroup per call, which lets rayon
//! balance the cores; runs of 32 workgroups measured slower on warp and block groups).
//!
//! Nothing in a dispatch can tell the difference: the old value is unread, the adds of
//! different invocations are unordered (WGSL's atomics are relaxed), and any other atomic
//! access in the kernel (a read-modify-write whose old value is read, an atomic load or
//! store) first adds the pending sums, so an invocation still sees its own adds.
//!
//! The context replaces the error flag as the functions' `%err` argument: word 0 is the
//! flag (`Fx::report` stores there), then 16 bytes per site, the address and the sum.

use naga::{Module, TypeInner};

/// The function that adds every site's pending sum (`void (ptr %ctx)`).
pub const FLUSH: &str = "cohort_flush";

/// Where the sites start in the context: after the error flag's 8-byte word.
pub const DEFERRED_AT: u64 = 8;

/// Byte offsets in the context of site `site`'s address and pending sum.
pub fn deferred_offsets(site: u32) -> (u64, u64) {
    let at = DEFERRED_AT + 16 * u64::from(site);
    (at, at + 8)
}

/// Whether a value of type `t` holds an atomic: loads and stores of it flush.
pub fn holds_atomic(m: &Module, t: &TypeInner) -> bool {
    match t {
        TypeInner::Atomic(_) => true,
        TypeInner::Array { base, .. } | TypeInner::BindingArray { base, .. } => {
            holds_atomic(m, &m.types[*base].inner)
        }
        TypeInner::Struct { members, .. } => members
            .iter()
            .any(|s| holds_atomic(m, &m.types[s.ty].inner)),
        _ => false,
    }
}

/// The definition of [`FLUSH`] for `sites` sites: each nonzero sum is added to its
/// address and cleared.
pub fn flush_function(sites: u32) -> String {
    let mut body = String::new();
    for s in 0..sites {
        let (at_ptr, at_sum) = deferred_offsets(s);
        body.push_str(&format!(
            "  %p{s}.at = getelementptr i8, ptr %ctx, i64 {at_ptr}
  %v{s}.at = getelementptr i8, ptr %ctx, i64 {at_sum}
  %p{s} = load ptr, ptr %p{s}.at
  %v{s} = load i32, ptr %v{s}.at
  %z{s} = icmp eq i32 %v{s}, 0
  br i1 %z{s}, label %s{s}.done, label %s{s}.add
s{s}.add:
  %o{s} = atomicrmw add ptr %p{s}, i32 %v{s} seq_cst
  store i32 0, ptr %v{s}.at
  br label %s{s}.done
s{s}.done:
"
        ));
    }
    format!("define internal void @{FLUSH}(ptr %ctx) {{\nentry:\n{body}  ret void\n}}\n")
}

/// The driver's lines that set up the context before the workgroups (`%ctx`, zeroed) and
/// that, after them, add the pending sums and pass the error flag on to `%err`. Empty
/// for a kernel without deferred sites, whose functions take `%err` itself.
pub fn driver_context(sites: u32) -> (String, String, &'static str) {
    if sites == 0 {
        return (String::new(), "  ret void\n".into(), "%err");
    }
    let bytes = DEFERRED_AT + 16 * u64::from(sites);
    let setup = format!(
        "  %ctx = alloca [{words} x i64], align 8
  call void @llvm.memset.p0.i64(ptr %ctx, i8 0, i64 {bytes}, i1 false)
",
        words = bytes / 8
    );
    let finish = format!(
        "  call void @{FLUSH}(ptr %ctx)
  %flag = load i32, ptr %ctx
  %failed = icmp ne i32 %flag, 0
  br i1 %failed, label %report, label %done
report:
  store atomic i32 1, ptr %err monotonic, align 4
  br label %done
done:
  ret void
"
    );
    (setup, finish, "%ctx")
}
