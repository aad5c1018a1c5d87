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

/// Runs test `name` of this binary in a child with `CHILD` set, which must still die of
/// SIGSEGV (the report defers to the handler before it); the child's stderr.
fn crash_child(name: &str) -> String {
    let out = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", name, "--nocapture", "--test-threads", "1"])
        .env(CHILD, "1")
        .output()
        .unwrap();
    use std::os::unix::process::ExitStatusExt as _;
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.signal(), Some(libc::SIGSEGV), "{err}");
    err
}

#[test]
fn an_unmapped_read_is_reported_with_its_thread_and_mapping() {
    if std::env::var_os(CHILD).is_some() {
        crash_report::install();
        std::thread::Builder::new()
            .name("crashing-one".into())
            .spawn(|| read_unmapped())
            .unwrap()
            .join()
            .ok();
        return;
    }
    let err = crash_child("an_unmapped_read_is_reported_with_its_thread_and_mapping");
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
    let err = crash_child("a_fault_in_named_code_names_the_kernel");
    assert!(
        err.contains(": the CPU vector form of `some_kernel` + 0x"),
        "{err}"
    );
    assert!(
        err.contains("LLVM was compiling the vector form of `another_kernel`"),
        "{err}"
    );
}
