//! LLVM, found at run time: the vector form's IR text is parsed, optimised at `-O2` for this
//! CPU and compiled by an ORC `LLJIT` through libLLVM's C API, loaded with `dlopen` as
//! Dr.Jit loads it. Nothing links against LLVM: without a libLLVM the CPU backend runs
//! host forms. `COHORT_LIBLLVM` names the library; otherwise the newest of the usual
//! sonames is taken (Mesa's software Vulkan driver already brings one).

use std::ffi::{c_char, c_void, CStr, CString};
use std::sync::Mutex;

use libloading::Library;

type P = *mut c_void;

/// The C API functions this module calls, resolved once.
struct Api {
    _lib: Library,
    name: String,
    dispose_message: unsafe extern "C" fn(*mut c_char),
    membuf: unsafe extern "C" fn(*const c_char, usize, *const c_char, i32) -> P,
    parse: unsafe extern "C" fn(P, P, *mut P, *mut *mut c_char) -> i32,
    tsc_new: unsafe extern "C" fn() -> P,
    tsc_context: unsafe extern "C" fn(P) -> P,
    tsm_new: unsafe extern "C" fn(P, P) -> P,
    jit_add: unsafe extern "C" fn(P, P, P) -> P,
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

/// The process's one JIT (ORC sessions are long-lived; kernels are added to it).
pub struct Jit {
    api: Api,
    jit: P,
    next: u64,
}
// The JIT is used under a mutex only.
unsafe impl Send for Jit {}

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

fn open() -> Result<(Library, String), String> {
    let wanted: Vec<String> = match std::env::var("COHORT_LIBLLVM") {
        Ok(p) if !p.is_empty() => vec![p],
        _ => CANDIDATES.iter().map(|s| s.to_string()).collect(),
    };
    let mut last = String::from("no libLLVM named");
    for name in wanted {
        // SAFETY: loading LLVM runs its static constructors, which have no preconditions.
        match unsafe { Library::new(&name) } {
            Ok(lib) => return Ok((lib, name)),
            Err(e) => last = e.to_string(),
        }
    }
    Err(format!(
        "no libLLVM (15 or newer) found ({last}); set COHORT_LIBLLVM to its path"
    ))
}

fn sym<T: Copy>(lib: &Library, name: &str) -> Result<T, String> {
    let c = format!("{name}\0");
    // SAFETY: the caller's `T` is the C signature of `name`.
    unsafe { lib.get::<T>(c.as_bytes()) }
        .map(|s| *s)
        .map_err(|e| format!("{name}: {e}"))
}

impl Jit {
    fn new() -> Result<Jit, String> {
        let (lib, name) = open()?;
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
            let cpu = sym::<unsafe extern "C" fn() -> *mut c_char>(&lib, "LLVMGetHostCPUName")?();
            let features =
                sym::<unsafe extern "C" fn() -> *mut c_char>(&lib, "LLVMGetHostCPUFeatures")?();
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
            // Level 2 (default), reloc default, code model JIT default.
            let tm = create_tm(target, triple, cpu, features, 2, 0, 1);
            let layout_of: unsafe extern "C" fn(P) -> P = sym(&lib, "LLVMCreateTargetDataLayout")?;
            let layout_str: unsafe extern "C" fn(P) -> *mut c_char =
                sym(&lib, "LLVMCopyStringRepOfTargetData")?;
            let data_layout = CString::from(CStr::from_ptr(layout_str(layout_of(tm))));
            let triple_s = CString::from(CStr::from_ptr(triple));
            let api = Api {
                dispose_message: sym(&lib, "LLVMDisposeMessage")?,
                membuf: sym(&lib, "LLVMCreateMemoryBufferWithMemoryRangeCopy")?,
                parse: sym(&lib, "LLVMParseIRInContext")?,
                tsc_new: sym(&lib, "LLVMOrcCreateNewThreadSafeContext")?,
                tsc_context: sym(&lib, "LLVMOrcThreadSafeContextGetContext")?,
                tsm_new: sym(&lib, "LLVMOrcCreateNewThreadSafeModule")?,
                jit_add: sym(&lib, "LLVMOrcLLJITAddLLVMIRModule")?,
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
            Ok(Jit { api, jit, next: 0 })
        }
    }

    /// Which library this JIT runs on.
    pub fn library(&self) -> &str {
        &self.api.name
    }

    /// A fresh symbol name for the next kernel's entry function.
    pub fn fresh_symbol(&mut self) -> String {
        self.next += 1;
        format!("cohort_run_{}", self.next)
    }

    /// Parses, optimises and compiles `ir`; returns the address of `symbol`.
    pub fn compile(&mut self, ir: &str, symbol: &str) -> Result<usize, String> {
        let a = &self.api;
        // SAFETY: the C API is used as documented; ownership of the module passes to the
        // thread-safe module, and of that to the JIT.
        unsafe {
            let tsc = (a.tsc_new)();
            let ctx = (a.tsc_context)(tsc);
            let name = c"cohort-kernel";
            let buf = (a.membuf)(ir.as_ptr() as *const c_char, ir.len(), name.as_ptr(), 0);
            let mut module: P = std::ptr::null_mut();
            let mut msg: *mut c_char = std::ptr::null_mut();
            if (a.parse)(ctx, buf, &mut module, &mut msg) != 0 {
                let m = CStr::from_ptr(msg).to_string_lossy().into_owned();
                (a.dispose_message)(msg);
                return Err(format!("LLVM rejected the vector form: {m}"));
            }
            (a.set_target)(module, a.triple.as_ptr());
            (a.set_data_layout)(module, a.data_layout.as_ptr());
            let passes = CString::new("default<O2>").expect("no NUL");
            a.check((a.run_passes)(
                module,
                passes.as_ptr(),
                a.tm,
                (a.pass_options)(),
            ))?;
            let tsm = (a.tsm_new)(module, tsc);
            a.check((a.jit_add)(self.jit, (a.jit_dylib)(self.jit), tsm))?;
            let mut addr = 0u64;
            let s = CString::new(symbol).map_err(|e| e.to_string())?;
            a.check((a.jit_lookup)(self.jit, &mut addr, s.as_ptr()))?;
            Ok(addr as usize)
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

/// The process's JIT, opened on first use (`Err` once, with the reason, where there is no
/// usable libLLVM).
pub fn jit() -> &'static Result<Mutex<Jit>, String> {
    static JIT: std::sync::OnceLock<Result<Mutex<Jit>, String>> = std::sync::OnceLock::new();
    JIT.get_or_init(|| Jit::new().map(Mutex::new))
}
