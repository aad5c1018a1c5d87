//! LLVM, found at run time: the vector form's IR text is parsed, optimised at `-O2` for this
//! CPU and compiled to an object file through libLLVM's C API, loaded with `dlopen` as
//! Dr.Jit loads it; an ORC `LLJIT` links the object into the process. Object files are
//! kept in Cohort's cache folder, keyed by the IR, the library and the CPU, so a later
//! run skips LLVM's work. Nothing links against LLVM: without a libLLVM the CPU backend
//! runs host forms. `COHORT_LIBLLVM` names the library; otherwise the newest of the usual
//! sonames is taken (Mesa's software Vulkan driver already brings one).

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use libloading::Library;

type P = *mut c_void;

/// The C API functions this module calls, resolved once.
struct Api {
    _lib: Library,
    name: String,
    dispose_message: unsafe extern "C" fn(*mut c_char),
    membuf: unsafe extern "C" fn(*const c_char, usize, *const c_char, i32) -> P,
    parse: unsafe extern "C" fn(P, P, *mut P, *mut *mut c_char) -> i32,
    context_new: unsafe extern "C" fn() -> P,
    context_dispose: unsafe extern "C" fn(P),
    module_dispose: unsafe extern "C" fn(P),
    emit: unsafe extern "C" fn(P, P, i32, *mut *mut c_char, *mut P) -> i32,
    buffer_start: unsafe extern "C" fn(P) -> *const u8,
    buffer_size: unsafe extern "C" fn(P) -> usize,
    buffer_dispose: unsafe extern "C" fn(P),
    jit_add_object: unsafe extern "C" fn(P, P, P) -> P,
    jit_lookup: unsafe extern "C" fn(P, *mut u64, *const c_char) -> P,
    jit_dylib: unsafe extern "C" fn(P) -> P,
    error_message: unsafe extern "C" fn(P) -> *mut c_char,
    dispose_error_message: unsafe extern "C" fn(*mut c_char),
    run_passes: unsafe extern "C" fn(P, *const c_char, P, P) -> P,
    pass_options: unsafe extern "C" fn() -> P,
    set_data_layout: unsafe extern "C" fn(P, *const c_char),
    set_target: unsafe extern "C" fn(P, *const c_char),
    tm: P,
    data_layout: CString,
    triple: CString,
}

/// The process's one JIT (ORC sessions are long-lived; kernels are added to it). Linking
/// (milliseconds) and compiling (up to a second) hold different locks, so that a kernel
/// whose object is cached links while another one compiles.
pub struct Jit {
    api: Api,
    /// What the objects depend on besides the IR: the library and the host CPU.
    target_key: u64,
    /// `f32` lanes in one vector register of the target CPU (`lanes`).
    register_lanes: u32,
    linker: Mutex<Linker>,
    /// Held while LLVM optimises and emits (the target machine is not thread-safe).
    compiling: Mutex<()>,
}

struct Linker {
    jit: P,
    /// Entry addresses of the kernels linked so far, by key.
    linked: std::collections::HashMap<u64, usize>,
}

// The LLJIT is used under `linker` only and the target machine under `compiling`; the rest
// of `Api` is immutable function pointers and strings.
unsafe impl Send for Jit {}
unsafe impl Sync for Jit {}

const CANDIDATES: &[&str] = &[
    "libLLVM.so.19.1",
    "libLLVM-19.so",
    "libLLVM-18.so.1",
    "libLLVM-18.so",
    "libLLVM-17.so.1",
    "libLLVM-17.so",
    "libLLVM-16.so.1",
    "libLLVM-16.so",
    "libLLVM-15.so.1",
    "libLLVM-15.so",
];

/// The JIT on the first library of `COHORT_LIBLLVM`, or else of the usual names, that
/// loads and sets one up. A library can load and still refuse: Ubuntu 24.04's LLVM 17
/// cannot register the JIT's exception frames when it is opened privately (as here, so
/// that its symbols never displace those of another LLVM in the process, Mesa's), so the
/// next candidate is tried.
fn open() -> Result<Jit, String> {
    crate::exit_hook::keep();
    let wanted: Vec<String> = match std::env::var("COHORT_LIBLLVM") {
        Ok(p) if !p.is_empty() => vec![p],
        _ => CANDIDATES.iter().map(|s| s.to_string()).collect(),
    };
    let mut refused = Vec::new();
    let mut last = String::from("no libLLVM named");
    for name in wanted {
        // SAFETY: loading LLVM runs its static constructors, which have no preconditions.
        match unsafe { Library::new(&name) } {
            Ok(lib) => {
                // A second reference, never released: a library that refuses has already
                // started LLVM (its targets initialised), and unloading it would run
                // LLVM's static destructors in the middle of the process.
                // SAFETY: as above; the library is loaded already.
                if let Ok(keep) = unsafe { Library::new(&name) } {
                    std::mem::forget(keep);
                }
                match Jit::on(lib, name.clone()) {
                    Ok(jit) => return Ok(jit),
                    Err(e) => refused.push(format!("{name}: {e}")),
                }
            }
            Err(e) => last = e.to_string(),
        }
    }
    if refused.is_empty() {
        Err(format!(
            "no libLLVM (15 or newer) found ({last}); set COHORT_LIBLLVM to its path"
        ))
    } else {
        Err(format!(
            "no libLLVM (15 or newer) could run the JIT ({}); set COHORT_LIBLLVM to another",
            refused.join("; ")
        ))
    }
}

/// `COHORT_CPU_SIMD_TARGET=CPU[:FEATURES]` (LLVM's names: `x86-64-v3`, `skylake-avx512`,
/// `znver3:+avx2,-avx512f`) compiles vector forms for another x86-64 CPU than this one:
/// to run the code a machine without AVX-512 (or without AVX2) would run, on this one.
/// The CPU must be one this machine can run the code of.
fn target_override() -> Result<Option<(CString, CString)>, String> {
    let Ok(t) = std::env::var("COHORT_CPU_SIMD_TARGET") else {
        return Ok(None);
    };
    if t.is_empty() {
        return Ok(None);
    }
    let (cpu, features) = t.split_once(':').unwrap_or((&t, ""));
    let c = |s: &str| {
        CString::new(s).map_err(|_| format!("COHORT_CPU_SIMD_TARGET={t:?} holds a NUL byte"))
    };
    Ok(Some((c(cpu)?, c(features)?)))
}

/// The relocation model and code model (`LLVMRelocMode`, `LLVMCodeModel`) objects are
/// emitted with for this library's JIT linker. From LLVM 17 on, LLJIT links ELF x86-64
/// objects with JITLink, which places all of an object's sections in one allocation:
/// position-independent code in the default (small) code model, calls into libm through
/// a GOT. Before, it linked them with RuntimeDyld, whose memory manager maps code and
/// constants separately, each near its own kind's earlier mappings: they can end up more
/// than 2 GiB apart, past the small model's 32-bit PC-relative reach, and RuntimeDyld
/// then truncates the displacement without a word, so that a vector form reads its
/// constants from a wrong address. The large code model addresses them with 64-bit
/// absolute relocations (what LLVM's MCJIT uses on x86-64, as `JITDefault`). A library
/// without `LLVMGetVersion` is older than LLVM 16.
fn code_model(lib: &Library) -> (i32, i32) {
    const STATIC: i32 = 1;
    const PIC: i32 = 2;
    const DEFAULT: i32 = 0;
    const LARGE: i32 = 6;
    let version: Result<unsafe extern "C" fn(*mut u32, *mut u32, *mut u32), _> =
        sym(lib, "LLVMGetVersion");
    let major = version.ok().map(|get| {
        let (mut major, mut minor, mut patch) = (0, 0, 0);
        // SAFETY: `LLVMGetVersion` writes three unsigned integers.
        unsafe { get(&mut major, &mut minor, &mut patch) };
        major
    });
    match major {
        Some(m) if m >= 17 => (PIC, DEFAULT),
        _ => (STATIC, LARGE),
    }
}

fn sym<T: Copy>(lib: &Library, name: &str) -> Result<T, String> {
    let c = format!("{name}\0");
    // SAFETY: the caller's `T` is the C signature of `name`.
    unsafe { lib.get::<T>(c.as_bytes()) }
        .map(|s| *s)
        .map_err(|e| format!("{name}: {e}"))
}

impl Jit {
    /// The JIT on the loaded library `lib`, named `name`.
    fn on(lib: Library, name: String) -> Result<Jit, String> {
        // SAFETY: every symbol is declared with its C signature from llvm-c/*.h.
        unsafe {
            for init in [
                "LLVMInitializeX86TargetInfo",
                "LLVMInitializeX86Target",
                "LLVMInitializeX86TargetMC",
                "LLVMInitializeX86AsmPrinter",
            ] {
                sym::<unsafe extern "C" fn()>(&lib, init)?();
            }
            let triple =
                sym::<unsafe extern "C" fn() -> *mut c_char>(&lib, "LLVMGetDefaultTargetTriple")?();
            let (cpu_s, features_s) = match target_override()? {
                Some(t) => t,
                None => (
                    CString::from(CStr::from_ptr(
                        sym::<unsafe extern "C" fn() -> *mut c_char>(&lib, "LLVMGetHostCPUName")?(),
                    )),
                    CString::from(CStr::from_ptr(
                        sym::<unsafe extern "C" fn() -> *mut c_char>(
                            &lib,
                            "LLVMGetHostCPUFeatures",
                        )?(),
                    )),
                ),
            };
            let (cpu, features) = (cpu_s.as_ptr(), features_s.as_ptr());
            let (reloc, code_model) = code_model(&lib);
            let target_key = crate::hash64(
                crate::hash64(
                    crate::hash64(0, name.as_bytes()),
                    CStr::from_ptr(cpu).to_bytes(),
                ),
                &[
                    CStr::from_ptr(features).to_bytes(),
                    &[reloc as u8, code_model as u8],
                ]
                .concat(),
            );
            let mut target: P = std::ptr::null_mut();
            let mut msg: *mut c_char = std::ptr::null_mut();
            let get_target: unsafe extern "C" fn(*const c_char, *mut P, *mut *mut c_char) -> i32 =
                sym(&lib, "LLVMGetTargetFromTriple")?;
            if get_target(triple, &mut target, &mut msg) != 0 {
                return Err(format!(
                    "LLVM has no target for this machine: {}",
                    CStr::from_ptr(msg).to_string_lossy()
                ));
            }
            let create_tm: unsafe extern "C" fn(
                P,
                *const c_char,
                *const c_char,
                *const c_char,
                i32,
                i32,
                i32,
            ) -> P = sym(&lib, "LLVMCreateTargetMachine")?;
            // Optimisation level 2 (default); relocation and code model as `code_model` says.
            let tm = create_tm(target, triple, cpu, features, 2, reloc, code_model);
            let layout_of: unsafe extern "C" fn(P) -> P = sym(&lib, "LLVMCreateTargetDataLayout")?;
            let layout_str: unsafe extern "C" fn(P) -> *mut c_char =
                sym(&lib, "LLVMCopyStringRepOfTargetData")?;
            let data_layout = CString::from(CStr::from_ptr(layout_str(layout_of(tm))));
            let triple_s = CString::from(CStr::from_ptr(triple));
            let api = Api {
                dispose_message: sym(&lib, "LLVMDisposeMessage")?,
                membuf: sym(&lib, "LLVMCreateMemoryBufferWithMemoryRangeCopy")?,
                parse: sym(&lib, "LLVMParseIRInContext")?,
                context_new: sym(&lib, "LLVMContextCreate")?,
                context_dispose: sym(&lib, "LLVMContextDispose")?,
                module_dispose: sym(&lib, "LLVMDisposeModule")?,
                emit: sym(&lib, "LLVMTargetMachineEmitToMemoryBuffer")?,
                buffer_start: sym(&lib, "LLVMGetBufferStart")?,
                buffer_size: sym(&lib, "LLVMGetBufferSize")?,
                buffer_dispose: sym(&lib, "LLVMDisposeMemoryBuffer")?,
                jit_add_object: sym(&lib, "LLVMOrcLLJITAddObjectFile")?,
                jit_lookup: sym(&lib, "LLVMOrcLLJITLookup")?,
                jit_dylib: sym(&lib, "LLVMOrcLLJITGetMainJITDylib")?,
                error_message: sym(&lib, "LLVMGetErrorMessage")?,
                dispose_error_message: sym(&lib, "LLVMDisposeErrorMessage")?,
                run_passes: sym(&lib, "LLVMRunPasses")?,
                pass_options: sym(&lib, "LLVMCreatePassBuilderOptions")?,
                set_data_layout: sym(&lib, "LLVMSetDataLayout")?,
                set_target: sym(&lib, "LLVMSetTarget")?,
                tm,
                data_layout,
                triple: triple_s,
                name,
                _lib: lib,
            };
            let create_jit: unsafe extern "C" fn(*mut P, P) -> P =
                sym(&api._lib, "LLVMOrcCreateLLJIT")?;
            let mut jit: P = std::ptr::null_mut();
            let e = create_jit(&mut jit, std::ptr::null_mut());
            api.check(e)?;
            // Kernels call libm (`sinf`, `acosf`, ...): resolve them in this process.
            let generator: unsafe extern "C" fn(*mut P, c_char, P, P) -> P = sym(
                &api._lib,
                "LLVMOrcCreateDynamicLibrarySearchGeneratorForProcess",
            )?;
            let add_generator: unsafe extern "C" fn(P, P) =
                sym(&api._lib, "LLVMOrcJITDylibAddGenerator")?;
            let mut g: P = std::ptr::null_mut();
            api.check(generator(
                &mut g,
                0,
                std::ptr::null_mut(),
                std::ptr::null_mut(),
            ))?;
            add_generator((api.jit_dylib)(jit), g);
            Ok(Jit {
                api,
                target_key,
                register_lanes: register_lanes(&CStr::from_ptr(features).to_string_lossy()),
                linker: Mutex::new(Linker {
                    jit,
                    linked: Default::default(),
                }),
                compiling: Mutex::new(()),
            })
        }
    }

    /// The cache key of the object compiled from `ir`: the IR, the library and the CPU.
    pub fn key(&self, ir: &str) -> u64 {
        crate::hash64(self.target_key, ir.as_bytes())
    }

    /// `f32` lanes in one vector register of the CPU the vector forms are compiled for.
    pub fn register_lanes(&self) -> u32 {
        self.register_lanes
    }

    /// Which library this JIT runs on.
    pub fn library(&self) -> &str {
        &self.api.name
    }

    /// The entry address of a kernel's vector form if it is linked already or its object
    /// file is in the cache (then it is linked now); `None` if it must be compiled. `name`
    /// is the kernel's, for profiles (`perf_map`).
    pub fn cached(&self, ir: &str, entry: &str, name: &str) -> Option<Result<usize, String>> {
        let key = self.key(ir);
        if let Some(&addr) = self.lock_linker().linked.get(&key) {
            return Some(Ok(addr));
        }
        let object = std::fs::read(object_file(key)?).ok()?;
        Some(self.link(key, entry, name, &object))
    }

    /// Compiles the IR of a kernel's vector form, whose entry function is named `entry`
    /// (or takes its object file from the cache), links it and returns the entry's
    /// address and the time LLVM took (zero from the cache). The same IR is linked once
    /// per process.
    pub fn compile(&self, ir: &str, entry: &str, name: &str) -> Result<(usize, Duration), String> {
        if let Some(r) = self.cached(ir, entry, name) {
            return r.map(|a| (a, Duration::ZERO));
        }
        if EXITING.load(std::sync::atomic::Ordering::SeqCst) {
            return Err("the process is ending: no more compiles".into());
        }
        let key = self.key(ir);
        let ir = ir.replacen(
            &format!("@{entry}("),
            &format!("@{}(", symbol(entry, key)),
            1,
        );
        let (object, took) = {
            let _one = self.compiling.lock().unwrap_or_else(|e| e.into_inner());
            self.warm_up();
            let start = Instant::now();
            let object = {
                let _named = crate::crash_report::compiling(name);
                self.object(&ir)
            };
            // SAFETY: `atexit` takes a plain C function (if it fails, exit runs without it).
            unsafe { atexit(finish_compiles) };
            (object?, start.elapsed())
        };
        crate::disk_cache::save(&object_file(key), &object);
        if let Some(p) = host_time_file(key) {
            let _ = std::fs::remove_file(p);
        }
        self.link(key, entry, name, &object).map(|a| (a, took))
    }

    /// Before the process's first compile: compiles [`WARM_UP_IR`] (the object is thrown
    /// away) and registers [`finish_compiles`] after it. The static objects LLVM creates on
    /// first use register their destructors as they are created, so exit would run those
    /// of a first compile in flight before any handler registered earlier: a segfault at
    /// exit, seen in 1 of 174 renders on 16 cores (2026-11-30). The warm-up creates most of
    /// them, so the handler registered after it outlives them, and a compile in flight at
    /// exit is waited for. Runs under the `compiling` lock.
    fn warm_up(&self) {
        static DONE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
        if DONE.swap(true, std::sync::atomic::Ordering::SeqCst) {
            return;
        }
        let _named = crate::crash_report::compiling("the warm-up module");
        let _ = self.object(WARM_UP_IR);
        // SAFETY: `atexit` takes a plain C function (if it fails, exit runs without it).
        unsafe { atexit(finish_compiles) };
    }

    fn lock_linker(&self) -> std::sync::MutexGuard<'_, Linker> {
        self.linker.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Links an object file and returns its entry's address.
    fn link(&self, key: u64, entry: &str, name: &str, object: &[u8]) -> Result<usize, String> {
        let mut l = self.lock_linker();
        if let Some(&addr) = l.linked.get(&key) {
            return Ok(addr);
        }
        let a = &self.api;
        // SAFETY: the C API is used as documented; the JIT takes the buffer.
        let addr = unsafe {
            let name = c"cohort-kernel";
            let buf = (a.membuf)(
                object.as_ptr() as *const c_char,
                object.len(),
                name.as_ptr(),
                0,
            );
            a.check((a.jit_add_object)(l.jit, (a.jit_dylib)(l.jit), buf))?;
            let mut addr = 0u64;
            let s = CString::new(symbol(entry, key)).map_err(|e| e.to_string())?;
            a.check((a.jit_lookup)(l.jit, &mut addr, s.as_ptr()))?;
            addr as usize
        };
        l.linked.insert(key, addr);
        if let Some(size) = super::perf_map::text_size(object) {
            crate::crash_report::name_code(addr, size as usize, name);
            if super::perf_map::enabled() {
                super::perf_map::record(name, addr, size);
            }
        }
        Ok(addr)
    }

    /// Parses and optimises `ir`, and emits it as an object file for this CPU.
    fn object(&self, ir: &str) -> Result<Vec<u8>, String> {
        let a = &self.api;
        // SAFETY: the C API is used as documented; the module and context are disposed of
        // here, the object's buffer after copying it.
        unsafe {
            let ctx = (a.context_new)();
            let name = c"cohort-kernel";
            let buf = (a.membuf)(ir.as_ptr() as *const c_char, ir.len(), name.as_ptr(), 0);
            let mut module: P = std::ptr::null_mut();
            let mut msg: *mut c_char = std::ptr::null_mut();
            if (a.parse)(ctx, buf, &mut module, &mut msg) != 0 {
                let m = CStr::from_ptr(msg).to_string_lossy().into_owned();
                (a.dispose_message)(msg);
                (a.context_dispose)(ctx);
                return Err(format!("LLVM rejected the vector form: {m}"));
            }
            (a.set_target)(module, a.triple.as_ptr());
            (a.set_data_layout)(module, a.data_layout.as_ptr());
            let passes = c"default<O2>";
            let optimised = a.check((a.run_passes)(
                module,
                passes.as_ptr(),
                a.tm,
                (a.pass_options)(),
            ));
            let mut out: P = std::ptr::null_mut();
            let failed = optimised.is_err() || (a.emit)(a.tm, module, 1, &mut msg, &mut out) != 0;
            (a.module_dispose)(module);
            (a.context_dispose)(ctx);
            optimised?;
            if failed {
                let m = CStr::from_ptr(msg).to_string_lossy().into_owned();
                (a.dispose_message)(msg);
                return Err(format!("LLVM could not emit the vector form: {m}"));
            }
            let bytes =
                std::slice::from_raw_parts((a.buffer_start)(out), (a.buffer_size)(out)).to_vec();
            (a.buffer_dispose)(out);
            Ok(bytes)
        }
    }
}

impl Api {
    /// An `LLVMErrorRef` as a `Result`.
    unsafe fn check(&self, e: P) -> Result<(), String> {
        if e.is_null() {
            return Ok(());
        }
        let m = (self.error_message)(e);
        let s = CStr::from_ptr(m).to_string_lossy().into_owned();
        (self.dispose_error_message)(m);
        Err(format!("LLVM: {s}"))
    }
}

/// One name per IR, so that objects from the cache link under the name they were built with.
fn symbol(entry: &str, key: u64) -> String {
    format!("{entry}_{key:016x}")
}

/// Where the object file of the IR with key `key` is cached.
fn object_file(key: u64) -> Option<std::path::PathBuf> {
    crate::cache_dir().map(|d| d.join("cpu-vector").join(format!("{key:016x}.o")))
}

/// Where the time a kernel's host form has run on this machine, over runs, is kept until
/// its vector form (the object with key `key`) is compiled.
fn host_time_file(key: u64) -> Option<std::path::PathBuf> {
    crate::cache_dir().map(|d| d.join("cpu-vector").join(format!("{key:016x}.host-ns")))
}

/// Where the measured ratio of a kernel's forms (`Chooser`) is kept for its vector form
/// with key `key`.
fn verdict_file(key: u64) -> Option<std::path::PathBuf> {
    crate::cache_dir().map(|d| d.join("cpu-vector").join(format!("{key:016x}.verdict")))
}

/// ln(vector time / host time) as [`save_verdict`] last kept it, if it did.
pub fn verdict(key: u64) -> Option<f64> {
    read_word(verdict_file(key))
        .map(f64::from_le_bytes)
        .filter(|r| r.is_finite())
}

/// The eight bytes of a cache file that holds one word, if it is there and that long.
fn read_word(path: Option<std::path::PathBuf>) -> Option<[u8; 8]> {
    std::fs::read(path?).ok()?.try_into().ok()
}

/// Keeps a kernel's measured ratio of forms, for the next run on this machine.
pub fn save_verdict(key: u64, log_ratio: f64) {
    crate::disk_cache::save(&verdict_file(key), &log_ratio.to_le_bytes());
}

/// The time, in nanoseconds, recorded by [`save_host_time`] (0 if none).
pub fn host_time(key: u64) -> u64 {
    read_word(host_time_file(key)).map_or(0, u64::from_le_bytes)
}

/// Keeps the time a kernel's host form has run on this machine.
pub fn save_host_time(key: u64, ns: u64) {
    crate::disk_cache::save(&host_time_file(key), &ns.to_le_bytes());
}

/// 16 where the target has AVX-512 (LLVM's feature list names `+avx512f`), else 8 (AVX2).
fn register_lanes(features: &str) -> u32 {
    if features.split(',').any(|f| f == "+avx512f") {
        16
    } else {
        8
    }
}

/// The process's JIT, opened on first use (`Err` once, with the reason, where there is no
/// usable libLLVM).
pub fn jit() -> &'static Result<Jit, String> {
    JIT.get_or_init(open)
}

static JIT: std::sync::OnceLock<Result<Jit, String>> = std::sync::OnceLock::new();

extern "C" {
    fn atexit(f: extern "C" fn()) -> i32;
}

/// What the first compile of a process compiles before its kernel ([`Jit::warm_up`]): the
/// constructs the vector forms are made of (a loop, masked gathers, scatters, loads and
/// stores, reductions, float arithmetic and intrinsics, compares, selects, an atomic and
/// a libm call).
const WARM_UP_IR: &str = r#"
declare <8 x float> @llvm.masked.gather.v8f32.v8p0(<8 x ptr>, i32, <8 x i1>, <8 x float>)
declare void @llvm.masked.scatter.v8f32.v8p0(<8 x float>, <8 x ptr>, i32, <8 x i1>)
declare <8 x float> @llvm.masked.load.v8f32.p0(ptr, i32, <8 x i1>, <8 x float>)
declare void @llvm.masked.store.v8f32.p0(<8 x float>, ptr, i32, <8 x i1>)
declare i1 @llvm.vector.reduce.or.v8i1(<8 x i1>)
declare <8 x float> @llvm.sqrt.v8f32(<8 x float>)
declare <8 x float> @llvm.fma.v8f32(<8 x float>, <8 x float>, <8 x float>)
declare <8 x float> @llvm.minnum.v8f32(<8 x float>, <8 x float>)
declare <8 x i32> @llvm.ctpop.v8i32(<8 x i32>)
declare float @sinf(float)
define void @cohort_warm_up(ptr %base, <8 x i64> %idx, ptr %count, i32 %n) {
entry:
  br label %loop
loop:
  %i = phi i32 [ 0, %entry ], [ %i.next, %body ]
  %acc = phi <8 x float> [ zeroinitializer, %entry ], [ %acc.next, %body ]
  %more = icmp ult i32 %i, %n
  br i1 %more, label %body, label %done
body:
  %ptrs = getelementptr float, ptr %base, <8 x i64> %idx
  %mask = fcmp olt <8 x float> %acc, <float 1.0, float 1.0, float 1.0, float 1.0, float 1.0, float 1.0, float 1.0, float 1.0>
  %g = call <8 x float> @llvm.masked.gather.v8f32.v8p0(<8 x ptr> %ptrs, i32 4, <8 x i1> %mask, <8 x float> zeroinitializer)
  %w = call <8 x float> @llvm.masked.load.v8f32.p0(ptr %base, i32 4, <8 x i1> %mask, <8 x float> %g)
  %s = call <8 x float> @llvm.sqrt.v8f32(<8 x float> %w)
  %f = call <8 x float> @llvm.fma.v8f32(<8 x float> %s, <8 x float> %g, <8 x float> %acc)
  %d = fdiv <8 x float> %f, %w
  %m = call <8 x float> @llvm.minnum.v8f32(<8 x float> %d, <8 x float> %acc)
  %bits = bitcast <8 x float> %m to <8 x i32>
  %pop = call <8 x i32> @llvm.ctpop.v8i32(<8 x i32> %bits)
  %pf = uitofp <8 x i32> %pop to <8 x float>
  %acc.next = select <8 x i1> %mask, <8 x float> %pf, <8 x float> %acc
  call void @llvm.masked.scatter.v8f32.v8p0(<8 x float> %acc.next, <8 x ptr> %ptrs, i32 4, <8 x i1> %mask)
  call void @llvm.masked.store.v8f32.p0(<8 x float> %m, ptr %base, i32 4, <8 x i1> %mask)
  %any = call i1 @llvm.vector.reduce.or.v8i1(<8 x i1> %mask)
  %one = zext i1 %any to i32
  %old = atomicrmw add ptr %count, i32 %one seq_cst
  %x = extractelement <8 x float> %acc.next, i32 0
  %y = call float @sinf(float %x)
  store float %y, ptr %base
  %i.next = add i32 %i, 1
  br label %loop
done:
  ret void
}
"#;

/// Set by the first [`finish_compiles`] at exit.
static EXITING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Registered at exit after every compile (exit runs handlers newest first): waits for a
/// compile in flight, and keeps any other from starting ([`stop_compiles`]), before the libLLVM's static
/// objects are destroyed. Those created during a compile register their destructors then,
/// so a handler registered when the JIT opened would run after them. A background
/// compile still in LLVM while its statics were destroyed crashed the process after its
/// work was done: a segfault, or an LLVM fatal error such as "Cannot select", in 2 of 128
/// renders that compiled as they ended (2026-11-29). Still exposed: a compile in flight
/// that creates statics no earlier compile did, whose destructors run before this
/// handler; [`Jit::warm_up`] makes that rare, and [`crate::stop_background_compiles`],
/// called before exit, rules it out.
extern "C" fn finish_compiles() {
    stop_compiles("at exit");
}

/// Waits for a compile in flight (at most [`EXIT_WAIT`]) and keeps any other from
/// starting: what a process does before it ends, while LLVM's static objects are all
/// still there ([`crate::stop_background_compiles`], `crate::exit_hook`), and what exit's
/// handler does. `when` says which, in the `COHORT_CPU_SIMD_LOG` line of a wait.
pub fn stop_compiles(when: &str) {
    if EXITING.swap(true, std::sync::atomic::Ordering::SeqCst) {
        return;
    }
    let Some(Ok(j)) = JIT.get() else { return };
    let waited_for = crate::crash_report::compiling_now();
    // Bounded: a compile that never ends (LLVM broken under it by a static it created,
    // destroyed before this handler ran) must not keep the process from exiting. A
    // handler that waited without bound hung a render for 37 minutes.
    let start = Instant::now();
    while start.elapsed() < EXIT_WAIT {
        let guard = match j.compiling.try_lock() {
            Ok(g) => g,
            Err(std::sync::TryLockError::Poisoned(e)) => e.into_inner(),
            Err(std::sync::TryLockError::WouldBlock) => {
                std::thread::sleep(Duration::from_millis(1));
                continue;
            }
        };
        std::mem::forget(guard);
        if let (Some(name), true) = (waited_for, super::log()) {
            eprintln!(
                "cohort: waited {:.3} s {when} for the vector form of `{name}` to compile",
                start.elapsed().as_secs_f64()
            );
        }
        return;
    }
}

/// How long exit waits for a compile in flight: several times the longest compile
/// measured (0.75 s for the largest `extend` on two busy cores).
const EXIT_WAIT: Duration = Duration::from_secs(5);
