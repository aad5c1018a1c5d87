//! A fatal signal's report. On SIGSEGV, SIGBUS, SIGILL or SIGFPE the process writes to
//! stderr which signal, the address it faulted on, the instruction that faulted and whose
//! code that is (a CPU vector form, by kernel name, else the mapping `/proc/self/maps`
//! names: a library, the program), the thread's name (libtest names a test's thread after
//! the test) and the vector form LLVM was compiling, if any. Then the handler that was
//! there before runs (Rust's stack-overflow message, or the default action), so the
//! process still dies of the signal. Without it a crash prints only "signal: 11", and on
//! a CI machine nothing more can be learned.
//!
//! The handler reads atomics and `/proc`, and writes to file descriptor 2 from buffers
//! on its stack: async-signal-safe calls only, so it cannot deadlock on a lock the
//! crashed thread held.

use std::sync::atomic::{AtomicPtr, AtomicUsize, Ordering};
use std::sync::{Once, OnceLock};

use libc::c_int;

const SIGNALS: [(c_int, &str); 4] = [
    (libc::SIGSEGV, "SIGSEGV"),
    (libc::SIGBUS, "SIGBUS"),
    (libc::SIGILL, "SIGILL"),
    (libc::SIGFPE, "SIGFPE"),
];

/// A named span of machine code (a vector form's `.text`).
struct Code {
    start: AtomicUsize,
    end: AtomicUsize,
    name: AtomicPtr<u8>,
    len: AtomicUsize,
}

/// Kernels past the table's size are reported by mapping only.
static CODE: [Code; 1024] = [const {
    Code {
        start: AtomicUsize::new(0),
        end: AtomicUsize::new(0),
        name: AtomicPtr::new(std::ptr::null_mut()),
        len: AtomicUsize::new(0),
    }
}; 1024];
static CODE_COUNT: AtomicUsize = AtomicUsize::new(0);

/// The name of the kernel whose vector form LLVM is compiling (null when none).
static COMPILING: AtomicPtr<u8> = AtomicPtr::new(std::ptr::null_mut());
static COMPILING_LEN: AtomicUsize = AtomicUsize::new(0);

/// The actions in place before [`install`], in `SIGNALS` order.
static PREVIOUS: OnceLock<[libc::sigaction; 4]> = OnceLock::new();

/// Installs the handler for the process (once; later calls do nothing).
pub fn install() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // SAFETY: `sigaction` with valid pointers; the handler has the SA_SIGINFO signature.
        unsafe {
            let mut old: [libc::sigaction; 4] = std::mem::zeroed();
            for (i, (sig, _)) in SIGNALS.iter().enumerate() {
                libc::sigaction(*sig, std::ptr::null(), &mut old[i]);
            }
            if PREVIOUS.set(old).is_err() {
                return;
            }
            for (sig, _) in SIGNALS {
                let mut new: libc::sigaction = std::mem::zeroed();
                new.sa_sigaction = handler
                    as extern "C" fn(c_int, *mut libc::siginfo_t, *mut libc::c_void)
                    as usize;
                // On the thread's alternate stack where it has one (Rust's threads do), so
                // that a stack overflow is reported too.
                new.sa_flags = libc::SA_SIGINFO | libc::SA_ONSTACK;
                libc::sigemptyset(&mut new.sa_mask);
                libc::sigaction(sig, &new, std::ptr::null_mut());
            }
        }
    });
}

/// Names `start..start + len` as the code of kernel `name` in later reports.
pub fn name_code(start: usize, len: usize, name: &str) {
    let i = CODE_COUNT.fetch_add(1, Ordering::AcqRel);
    let Some(c) = CODE.get(i) else { return };
    let name: &'static str = Box::leak(name.to_string().into_boxed_str());
    c.name.store(name.as_ptr() as *mut u8, Ordering::Release);
    c.len.store(name.len(), Ordering::Release);
    c.end.store(start + len, Ordering::Release);
    c.start.store(start, Ordering::Release);
}

/// Marks that LLVM is compiling kernel `name`'s vector form until the guard drops.
pub fn compiling(name: &str) -> Compiling {
    let name: &'static str = Box::leak(name.to_string().into_boxed_str());
    COMPILING_LEN.store(name.len(), Ordering::Release);
    COMPILING.store(name.as_ptr() as *mut u8, Ordering::Release);
    Compiling
}

/// The kernel whose vector form LLVM is compiling now, if any (the one a crash report
/// names).
pub fn compiling_now() -> Option<&'static str> {
    let p = COMPILING.load(Ordering::Acquire);
    if p.is_null() {
        return None;
    }
    let len = COMPILING_LEN.load(Ordering::Acquire);
    // SAFETY: a leaked &'static str's pointer and length, the length stored first;
    // compiles run one at a time, so the two belong together.
    Some(unsafe { std::str::from_utf8_unchecked(std::slice::from_raw_parts(p, len)) })
}

/// See [`compiling`].
pub struct Compiling;

impl Drop for Compiling {
    fn drop(&mut self) {
        COMPILING.store(std::ptr::null_mut(), Ordering::Release);
    }
}

extern "C" fn handler(sig: c_int, info: *mut libc::siginfo_t, ctx: *mut libc::c_void) {
    let which = SIGNALS.iter().position(|s| s.0 == sig);
    // SAFETY: the kernel passes a valid siginfo and ucontext to an SA_SIGINFO handler.
    let (addr, code) = unsafe { ((*info).si_addr() as usize, (*info).si_code) };
    report(
        which.map_or("a signal", |i| SIGNALS[i].1),
        addr,
        code,
        ip(ctx),
    );
    // The previous action again; a fault recurs when the instruction is retried, and a
    // signal that was sent (not raised by the instruction) is sent again.
    if let (Some(old), Some(i)) = (PREVIOUS.get(), which) {
        // SAFETY: restoring an action `sigaction` returned.
        unsafe {
            libc::sigaction(sig, &old[i], std::ptr::null_mut());
            if code <= 0 {
                libc::raise(sig);
            }
        }
    }
}

/// The faulting instruction's address, where this target's context is known.
fn ip(ctx: *mut libc::c_void) -> Option<usize> {
    #[cfg(all(target_os = "linux", target_arch = "x86_64"))]
    {
        // SAFETY: `ctx` is the ucontext the kernel passed.
        let uc = unsafe { &*(ctx as *const libc::ucontext_t) };
        Some(uc.uc_mcontext.gregs[libc::REG_RIP as usize] as usize)
    }
    #[cfg(not(all(target_os = "linux", target_arch = "x86_64")))]
    {
        let _ = ctx;
        None
    }
}

fn report(signal: &str, addr: usize, code: c_int, ip: Option<usize>) {
    let mut out = Line::new();
    out.push(b"cohort: fatal ");
    out.push(signal.as_bytes());
    out.push(b" (address ");
    out.hex(addr);
    out.push(b", si_code ");
    out.dec(code as i64);
    out.push(b") in thread `");
    let mut comm = [0u8; 64];
    let n = read_file(c"/proc/thread-self/comm", &mut comm);
    out.push(trim(&comm[..n]));
    out.push(b"`");
    out.flush();
    if let Some(ip) = ip {
        out.push(b"cohort:   at instruction ");
        out.hex(ip);
        match kernel_at(ip) {
            Some((name, start)) => {
                out.push(b": the CPU vector form of `");
                out.push(name);
                out.push(b"` + ");
                out.hex(ip - start);
                out.flush();
            }
            None => mapping_of(ip, &mut out),
        }
    }
    let p = COMPILING.load(Ordering::Acquire);
    if !p.is_null() {
        out.push(b"cohort:   LLVM was compiling the vector form of `");
        // SAFETY: a leaked &'static str's pointer and length, stored before the pointer.
        out.push(unsafe { std::slice::from_raw_parts(p, COMPILING_LEN.load(Ordering::Acquire)) });
        out.push(b"`");
        out.flush();
    }
}

fn kernel_at(ip: usize) -> Option<(&'static [u8], usize)> {
    let n = CODE_COUNT.load(Ordering::Acquire).min(CODE.len());
    CODE[..n].iter().find_map(|c| {
        let start = c.start.load(Ordering::Acquire);
        if start == 0 || ip < start || ip >= c.end.load(Ordering::Acquire) {
            return None;
        }
        let p = c.name.load(Ordering::Acquire);
        // SAFETY: a leaked &'static str's pointer and length, stored before `start`.
        Some((
            unsafe { std::slice::from_raw_parts(p, c.len.load(Ordering::Acquire)) },
            start,
        ))
    })
}

/// Ends `out` with the line of `/proc/self/maps` whose span holds `ip` (or that none
/// does), with `ip`'s offset in the mapped file.
fn mapping_of(ip: usize, out: &mut Line) {
    // SAFETY: plain open/read/close on a path and a stack buffer.
    let fd = unsafe { libc::open(c"/proc/self/maps".as_ptr(), libc::O_RDONLY) };
    if fd < 0 {
        out.push(b" (no /proc/self/maps)");
        out.flush();
        return;
    }
    let mut chunk = [0u8; 1024];
    let mut line = [0u8; 512];
    let mut len = 0;
    let mut found = false;
    'read: loop {
        // SAFETY: reading into a stack buffer of that size.
        let n = unsafe { libc::read(fd, chunk.as_mut_ptr().cast(), chunk.len()) };
        if n <= 0 {
            break;
        }
        for &b in &chunk[..n as usize] {
            if b != b'\n' {
                if len < line.len() {
                    line[len] = b;
                    len += 1;
                }
                continue;
            }
            if let Some((start, end, offset)) = span(&line[..len]) {
                if (start..end).contains(&ip) {
                    out.push(b" in ");
                    out.push(&line[..len]);
                    out.push(b" (offset ");
                    out.hex(ip - start + offset);
                    out.push(b")");
                    out.flush();
                    found = true;
                    break 'read;
                }
            }
            len = 0;
        }
    }
    // SAFETY: closing the descriptor opened above.
    unsafe { libc::close(fd) };
    if !found {
        out.push(b" in no mapping");
        out.flush();
    }
}

/// `start`, `end` and file offset of a `/proc/self/maps` line.
fn span(line: &[u8]) -> Option<(usize, usize, usize)> {
    let mut fields = line.split(|&b| b == b' ');
    let range = fields.next()?;
    let dash = range.iter().position(|&b| b == b'-')?;
    let _perms = fields.next()?;
    let offset = parse_hex(fields.next()?)?;
    Some((
        parse_hex(&range[..dash])?,
        parse_hex(&range[dash + 1..])?,
        offset,
    ))
}

fn parse_hex(s: &[u8]) -> Option<usize> {
    if s.is_empty() {
        return None;
    }
    s.iter().try_fold(0usize, |acc, &b| {
        let d = (b as char).to_digit(16)? as usize;
        acc.checked_mul(16)?.checked_add(d)
    })
}

fn read_file(path: &std::ffi::CStr, buf: &mut [u8]) -> usize {
    // SAFETY: plain open/read/close on a path and a caller's buffer.
    unsafe {
        let fd = libc::open(path.as_ptr(), libc::O_RDONLY);
        if fd < 0 {
            return 0;
        }
        let n = libc::read(fd, buf.as_mut_ptr().cast(), buf.len());
        libc::close(fd);
        n.max(0) as usize
    }
}

fn trim(s: &[u8]) -> &[u8] {
    let end = s
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(0, |i| i + 1);
    &s[..end]
}

/// A line built on the stack and written to stderr in one `write`.
struct Line {
    buf: [u8; 768],
    len: usize,
}

impl Line {
    fn new() -> Line {
        Line {
            buf: [0; 768],
            len: 0,
        }
    }
    fn push(&mut self, s: &[u8]) {
        let n = s.len().min(self.buf.len() - 1 - self.len);
        self.buf[self.len..self.len + n].copy_from_slice(&s[..n]);
        self.len += n;
    }
    fn hex(&mut self, x: usize) {
        let mut digits = [0u8; 18];
        let mut i = digits.len();
        let mut v = x;
        loop {
            i -= 1;
            digits[i] = b"0123456789abcdef"[v & 15];
            v >>= 4;
            if v == 0 {
                break;
            }
        }
        i -= 2;
        digits[i..i + 2].copy_from_slice(b"0x");
        self.push(&digits[i..]);
    }
    fn dec(&mut self, x: i64) {
        if x < 0 {
            self.push(b"-");
        }
        let mut digits = [0u8; 20];
        let mut i = digits.len();
        let mut v = x.unsigned_abs();
        loop {
            i -= 1;
            digits[i] = b'0' + (v % 10) as u8;
            v /= 10;
            if v == 0 {
                break;
            }
        }
        self.push(&digits[i..]);
    }
    /// Ends the line and writes it.
    fn flush(&mut self) {
        self.buf[self.len] = b'\n';
        // SAFETY: writing initialised bytes of a stack buffer to stderr.
        unsafe { libc::write(2, self.buf.as_ptr().cast(), self.len + 1) };
        self.len = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::{parse_hex, span};

    #[test]
    fn maps_lines_parse() {
        assert_eq!(
            span(b"7f87dbe9a000-7f87f0c25000 r-xp 00001000 00:00 0 /lib/x.so"),
            Some((0x7f87dbe9a000, 0x7f87f0c25000, 0x1000))
        );
        assert_eq!(span(b"garbage"), None);
        assert_eq!(parse_hex(b"ffffffffffffffffff"), None);
        assert_eq!(parse_hex(b""), None);
    }
}
