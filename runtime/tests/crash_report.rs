//! A process that crashes says where: the fatal-signal report names the signal, the
//! address, the thread, and the kernel whose vector form holds the faulting instruction.
//! Each case crashes a child process (this test binary, run again for one test).

use std::process::Command;

use cohort_runtime::crash_report;

/// Set in the child: which crash to cause.
const CHILD: &str = "COHORT_CRASH_REPORT_CHILD";

/// Reads address 8: aligned and not null (which debug builds would refuse before the
/// read), and never mapped.
#[inline(never)]
extern "C" fn read_unmapped() -> u64 {
    // SAFETY: none; the fault is the point, in the child process only.
    unsafe { std::ptr::read_volatile(std::ptr::dangling::<u64>()) }
}

/// Runs test `name` of this binary in a child with `CHILD` set, which must die of signal
/// `signal` (the report defers to the handler before it); the child's stderr.
fn crash_child(name: &str, signal: i32) -> String {
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", name, "--nocapture", "--test-threads", "1"])
        .env(CHILD, "1")
        .output()
        .unwrap();
    use std::os::unix::process::ExitStatusExt as _;
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.signal(), Some(signal), "{err}");
    err
}

/// Runs `f` on a thread named `name` with a stack of `stack` bytes, after installing the
/// handler (in the child).
fn crash_in_thread(name: &str, stack: usize, f: fn()) {
    crash_report::install();
    std::thread::Builder::new()
        .name(name.into())
        .stack_size(stack)
        .spawn(f)
        .unwrap()
        .join()
        .ok();
}

#[test]
fn an_unmapped_read_is_reported_with_its_thread_and_mapping() {
    if std::env::var_os(CHILD).is_some() {
        crash_in_thread("crashing-one", 1 << 20, || {
            read_unmapped();
        });
        return;
    }
    let err = crash_child(
        "an_unmapped_read_is_reported_with_its_thread_and_mapping",
        libc::SIGSEGV,
    );
    assert!(
        err.contains("cohort: fatal SIGSEGV (address 0x8, si_code 1) in thread `crashing-one`"),
        "{err}"
    );
    // The instruction lies in this test binary's mapping.
    let exe = std::env::current_exe().unwrap();
    let exe = exe.file_name().unwrap().to_string_lossy();
    assert!(
        err.lines()
            .any(|l| l.starts_with("cohort:   at instruction 0x") && l.contains(&*exe)),
        "{err}"
    );
}

#[test]
fn a_fault_in_named_code_names_the_kernel() {
    if std::env::var_os(CHILD).is_some() {
        crash_report::install();
        // `read_unmapped` stands for a vector form: its first bytes are named as one.
        crash_report::name_code(read_unmapped as *const () as usize, 256, "some_kernel");
        let _guard = crash_report::compiling("another_kernel");
        read_unmapped();
        return;
    }
    let err = crash_child("a_fault_in_named_code_names_the_kernel", libc::SIGSEGV);
    assert!(
        err.contains(": the CPU vector form of `some_kernel` + 0x"),
        "{err}"
    );
    assert!(
        err.contains("LLVM was compiling the vector form of `another_kernel`"),
        "{err}"
    );
}

/// Recurses until the stack runs out (the test on `n` only keeps the compiler from
/// seeing that).
#[inline(never)]
fn deeper(n: u64) -> u64 {
    if std::hint::black_box(n) == u64::MAX {
        return 0;
    }
    let pad = std::hint::black_box([n; 64]);
    deeper(n + 1) + pad[(n % 64) as usize]
}

#[test]
fn a_stack_overflow_is_reported_and_rust_still_says_so() {
    if std::env::var_os(CHILD).is_some() {
        // The handler runs on the thread's alternate stack, the overflowed one being full.
        crash_in_thread("too-deep", 256 * 1024, || {
            deeper(0);
        });
        return;
    }
    // Rust's handler, which runs next, names the overflow and aborts.
    let err = crash_child(
        "a_stack_overflow_is_reported_and_rust_still_says_so",
        libc::SIGABRT,
    );
    assert!(
        err.contains("cohort: fatal SIGSEGV") && err.contains("in thread `too-deep`"),
        "{err}"
    );
    assert!(err.contains("has overflowed its stack"), "{err}");
}
