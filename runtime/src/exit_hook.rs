//! Background compiles stopped before exit destroys anything. glibc's `exit` first runs
//! the exiting thread's thread-local destructors, then the `atexit` handlers, newest first;
//! among those are the destructors of the static objects libLLVM creates, each registered
//! when first used. A compile in flight can be the first to use one, so a handler that
//! waits for it (registered earlier) would run after that object is gone: a SIGSEGV in
//! `cohort-llvm` at exit (BENCHMARKS.md, 2026-11-30). Before `main`, this registers a
//! thread-local destructor of the main thread that waits for the compile in flight: a
//! program that returns from `main` (a test binary, a tool that never calls
//! `stop_background_compiles`) then stops its compiles before any static object goes.
//! A `process::exit` from another thread runs that thread's destructors instead, and
//! falls back on the `atexit` handler.

#[cfg(all(target_os = "linux", target_env = "gnu"))]
mod glibc {
    use std::ffi::c_void;

    extern "C" {
        /// glibc's registration of a thread-local destructor (what C++'s `thread_local`
        /// uses): `dtor(obj)` runs when the calling thread exits, before `atexit`
        /// handlers when it exits the process. `dso` is any address in the registering
        /// object, which glibc keeps loaded until then.
        fn __cxa_thread_atexit_impl(
            dtor: extern "C" fn(*mut c_void),
            obj: *mut c_void,
            dso: *mut c_void,
        ) -> i32;
    }

    extern "C" fn stop(_: *mut c_void) {
        crate::cpu::simd::stop_compiles("as the main thread exits");
    }

    /// Runs before `main`, on the main thread (the loader calls `.init_array` there).
    extern "C" fn register() {
        // SAFETY: `stop` is a plain C function taking the (unused) object pointer; the
        // address passed as `dso` lies in this program's code.
        unsafe {
            __cxa_thread_atexit_impl(stop, std::ptr::null_mut(), register as *mut c_void);
        }
    }

    #[used]
    #[link_section = ".init_array"]
    pub static REGISTER: extern "C" fn() = register;
}

/// Called where the JIT opens, so that the linker keeps this module (and with it the
/// `.init_array` entry) in every program that can compile a vector form.
pub fn keep() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    std::hint::black_box(&glibc::REGISTER);
}
