//! Scattered struct accesses as rows. Where the lanes' elements of a struct or vector lie
//! apart (a BVH node, a triangle, a queued slot's state), each lane's element moves as one
//! row of 32-bit words, and a transposition turns the W rows into the struct's leaves, one
//! `<W x i32>` per word, or the leaves back into rows. A gather or scatter of W lanes costs
//! the same whatever its mask (2.6-3.2 ns per gather on the AMD EPYC of BENCHMARKS.md), so
//! a struct of m words gathered costs m of them where rows cost W loads and the
//! transposition: log2(W) rounds of W two-register shuffles per W words of the row, all one
//! register of lanes wide, which LLVM lowers directly. (A transposition through one vector
//! of all the rows' words, W * n wide, took LLVM longer to compile: BENCHMARKS.md.)

use super::lower::{Fx, Val};
use super::memory::Place;
use super::types::{lanes, leaves, scalar, splat_const, w, Lowering};

/// Which words of the lanes' scattered elements of a place move as rows ([`Fx::row_plan`]):
/// words `lo..lo + n` of each element, and each leaf's (path, scalar, word).
pub struct Rows {
    lo: u64,
    n: u64,
    leaves: Vec<(Vec<u32>, &'static str, u64)>,
}

/// Where the lanes' elements of a scattered access lie: binding `g`, byte offset `konst`
/// plus each lane's `d` (`<W x i64>`), `d0` the first running lane's.
pub struct RowsAt<'a> {
    pub g: usize,
    pub konst: u64,
    pub d: &'a str,
    pub d0: &'a str,
}

impl Fx<'_> {
    /// How the lanes' scattered elements of a place read as rows: `None` for up to 4
    /// leaves, for leaves that are not 32-bit words, or where the words the leaves span
    /// are mostly not leaves.
    pub(super) fn row_plan(&self, p: &Place) -> Option<Rows> {
        let ls = leaves(self.m, &p.ty).ok()?;
        // A vector or struct of up to 4 leaves gathers: as fast in the renderer as its
        // rows, and a fifth less for LLVM to compile in the extend kernel (BENCHMARKS.md).
        if ls.len() <= 4 {
            return None;
        }
        let mut out = Vec::with_capacity(ls.len());
        for l in ls {
            let s = scalar(l.scalar).ok()?;
            // Rows move 32-bit words: a bool, a 64-bit scalar or an unaligned leaf gathers.
            if !matches!(s, "i32" | "float") || l.offset % 4 != 0 {
                return None;
            }
            out.push((l.path, s, l.offset / 4));
        }
        let lo = out.iter().map(|l| l.2).min()?;
        let n = out.iter().map(|l| l.2).max()? + 1 - lo;
        if n > 2 * out.len() as u64 || n * u64::from(w()) > 512 {
            return None;
        }
        Some(Rows { lo, n, leaves: out })
    }

    /// Each lane's address of word `lo` of its element (`<W x ptr>`); a lane that is off in
    /// `mask` points at the first running lane's element, which is in bounds.
    fn row_pointers(&mut self, at: &RowsAt, mask: &str, lo: u64) -> String {
        let v64 = lanes("i64");
        let first = self.splat("i64", at.d0);
        let d = self.op(&format!(
            "select {} {mask}, {v64} {}, {v64} {first}",
            Fx::mask_ty(),
            at.d
        ));
        let by = splat_const("i64", &(at.konst + 4 * lo).to_string());
        let off = self.op(&format!("add {v64} {d}, {by}"));
        let base = self.buffer_base(at.g);
        self.op(&format!("getelementptr i8, ptr {base}, {v64} {off}"))
    }

    /// Loads each lane's words `lo..lo + n` of its element with one vector load and
    /// transposes the rows into the leaves, for `assemble`.
    pub(super) fn rows_load(
        &mut self,
        at: &RowsAt,
        mask: &str,
        plan: &Rows,
    ) -> Vec<(Vec<u32>, String, String)> {
        let (w, n) = (u64::from(w()), plan.n);
        let ptrs = self.row_pointers(at, mask, plan.lo);
        let row_ty = format!("<{n} x i32>");
        let rows: Vec<String> = (0..w)
            .map(|k| {
                let p = self.op(&format!("extractelement {} {ptrs}, i32 {k}", lanes("ptr")));
                self.op(&format!("load {row_ty}, ptr {p}, align 4"))
            })
            .collect();
        let used = |word: u64| plan.leaves.iter().any(|l| l.2 - plan.lo == word);
        let mut words: Vec<Option<String>> = vec![None; n as usize];
        for c in 0..n.div_ceil(w) {
            if !(c * w..(c * w + w).min(n)).any(used) {
                continue;
            }
            let pieces: Vec<String> = rows.iter().map(|r| self.chunk(r, n, c)).collect();
            for (j, t) in self.transpose_rows(pieces).into_iter().enumerate() {
                if let Some(slot) = words.get_mut((c * w) as usize + j) {
                    *slot = Some(t);
                }
            }
        }
        plan.leaves
            .iter()
            .map(|(path, s, word)| {
                let x = words[(word - plan.lo) as usize]
                    .clone()
                    .expect("the chunk of every leaf's word is transposed");
                (path.clone(), lanes(s), self.words_as(&x, s))
            })
            .collect()
    }

    /// Words `c * W .. c * W + W` of a row of `n` words, as one `<W x i32>` (poison past
    /// `n`).
    fn chunk(&mut self, row: &str, n: u64, c: u64) -> String {
        let w = u64::from(w());
        if n == w && c == 0 {
            return row.to_string();
        }
        let pick: Vec<String> = (c * w..c * w + w)
            .map(|i| {
                if i < n {
                    format!("i32 {i}")
                } else {
                    "i32 undef".to_string()
                }
            })
            .collect();
        self.op(&format!(
            "shufflevector <{n} x i32> {row}, <{n} x i32> poison, {} <{}>",
            lanes("i32"),
            pick.join(", ")
        ))
    }

    /// The transpose of W vectors of W words (`<W x i32>` each, `poison` allowed):
    /// output j holds word j of every input, input k's in lane k. log2(W) rounds; each
    /// interleaves input i with input i + W/2, low halves into output 2i and high halves
    /// into output 2i + 1.
    fn transpose_rows(&mut self, mut v: Vec<String>) -> Vec<String> {
        let w = w() as usize;
        let half = w / 2;
        let ty = lanes("i32");
        let mask = |from: usize| -> String {
            let ids: Vec<String> = (0..half)
                .flat_map(|i| [format!("i32 {}", from + i), format!("i32 {}", w + from + i)])
                .collect();
            format!("<{}>", ids.join(", "))
        };
        let (lo, hi) = (mask(0), mask(half));
        let mut round = 1;
        while round < w {
            let mut next = Vec::with_capacity(w);
            for i in 0..half {
                let (a, b) = (&v[i], &v[i + half]);
                next.push(self.op(&format!(
                    "shufflevector {ty} {a}, {ty} {b}, {} {lo}",
                    lanes("i32")
                )));
                next.push(self.op(&format!(
                    "shufflevector {ty} {a}, {ty} {b}, {} {hi}",
                    lanes("i32")
                )));
            }
            v = next;
            round *= 2;
        }
        v
    }

    /// Stores each running lane's leaves of `value` as one row, words `lo..lo + n` of its
    /// element, with one masked store per lane in lane order (so that where two lanes
    /// write one element the higher lane's value stays, as in the host form); words of
    /// the span that hold no leaf are left as they are.
    pub(super) fn rows_store(
        &mut self,
        at: &RowsAt,
        mask: &str,
        plan: &Rows,
        value: &Val,
    ) -> Lowering<()> {
        let (w, n) = (u64::from(w()), plan.n);
        let mut words = vec!["poison".to_string(); n as usize];
        let mut keep = vec!["i1 false"; n as usize];
        for (path, s, word) in &plan.leaves {
            let x = self.leaf_of(value, path)?;
            words[(word - plan.lo) as usize] = self.as_words(&x, s);
            keep[(word - plan.lo) as usize] = "i1 true";
        }
        // Lane k's row, in chunks of W words.
        let mut pieces: Vec<Vec<String>> = vec![Vec::new(); w as usize];
        for c in 0..n.div_ceil(w) {
            let chunk: Vec<String> = (c * w..c * w + w)
                .map(|i| {
                    words
                        .get(i as usize)
                        .cloned()
                        .unwrap_or_else(|| "poison".to_string())
                })
                .collect();
            for (k, t) in self.transpose_rows(chunk).into_iter().enumerate() {
                pieces[k].push(t);
            }
        }
        let ptrs = self.row_pointers(at, mask, plan.lo);
        let (row_ty, mty) = (format!("<{n} x i32>"), format!("<{n} x i1>"));
        let keep = format!("<{}>", keep.join(", "));
        self.declare(&format!(
            "declare void @llvm.masked.store.v{n}i32.p0({row_ty}, ptr, i32, {mty})"
        ));
        for (k, lane) in pieces.into_iter().enumerate() {
            let (row, len) = self.concat(lane, w);
            let row = if len == n {
                row
            } else {
                let first: Vec<String> = (0..n).map(|i| format!("i32 {i}")).collect();
                self.op(&format!(
                    "shufflevector <{len} x i32> {row}, <{len} x i32> poison, {row_ty} <{}>",
                    first.join(", ")
                ))
            };
            let on = self.op(&format!("extractelement {} {mask}, i32 {k}", Fx::mask_ty()));
            let m = self.op(&format!(
                "select i1 {on}, {mty} {keep}, {mty} zeroinitializer"
            ));
            let p = self.op(&format!("extractelement {} {ptrs}, i32 {k}", lanes("ptr")));
            self.line(&format!(
                "call void @llvm.masked.store.v{n}i32.p0({row_ty} {row}, ptr {p}, i32 4, {mty} {m})"
            ));
        }
        Ok(())
    }
}
