//! `cohort check`: the statistical tests of every built-in sampling routine on one device
//! (`cohort_render::validate`, docs/VALIDATION.md): each diffuse strategy at the group
//! levels the renderer runs it at, and every BSDF's sampling. Prints the table; exits
//! non-zero when a test fails (the observed and expected tables of each failure are then
//! written as PNGs to `--out`).

use std::path::PathBuf;

use clap::ValueEnum;
use cohort::runtime::{BackendKind, Device};
use cohort::Group;
use cohort_render::validate::{self, BsdfOptions, Report, SamplerOptions};
use cohort_render::validate::{
    CoherentCosine, CoherentEqualArea, CoherentUniform, Cosine, DiffuseSampler,
};

/// Which backend runs the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CheckBackend {
    /// A real GPU if there is one, else the CPU backend.
    Auto,
    Cpu,
    Vulkan,
    Wgpu,
}

#[derive(clap::Args)]
pub struct CheckArgs {
    /// Which backend runs the kernels.
    #[arg(long, value_enum, default_value_t = CheckBackend::Auto)]
    backend: CheckBackend,
    /// Rays per sampler and group level, and samples per BSDF and incident direction.
    #[arg(long, default_value_t = 1 << 17)]
    samples: u32,
    /// Where the observed and expected tables of failed tests are written (PNG).
    #[arg(long, default_value = "check-failures")]
    out: PathBuf,
    /// Overall significance of the tests (Sidak-corrected over all of them).
    #[arg(long, default_value_t = 0.01)]
    alpha: f64,
    /// Seed of the random numbers (the tests are deterministic for a seed).
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Only the diffuse strategies (no BSDFs).
    #[arg(long)]
    samplers_only: bool,
}

fn device(backend: CheckBackend) -> Result<Device, String> {
    let kind = match backend {
        CheckBackend::Auto => {
            let (d, why) = Device::best_explained().map_err(|e| e.to_string())?;
            if let Some(why) = why {
                eprintln!("note: checking on the CPU backend: {why} (--backend names another)");
            }
            return Ok(d);
        }
        CheckBackend::Cpu => BackendKind::Cpu,
        CheckBackend::Vulkan => BackendKind::Vulkan,
        CheckBackend::Wgpu => BackendKind::Wgpu,
    };
    Device::new(kind).map_err(|e| e.to_string())
}

fn strategy<S: DiffuseSampler + 'static>(
    d: &Device,
    name: &str,
    levels: &[Group],
    args: &CheckArgs,
    report: &mut Report,
) -> Result<(), String> {
    let opts = SamplerOptions {
        name: Some(name.into()),
        levels: levels.to_vec(),
        samples: args.samples,
        seed: args.seed,
        alpha: args.alpha,
        ..Default::default()
    };
    eprintln!("checking {name} ...");
    let r = validate::sampler::<S>(d, &opts).map_err(|e| e.to_string())?;
    report.merge(r);
    Ok(())
}

/// The report of every built-in routine on `d` (the samplers' and BSDFs' tests, one Sidak
/// correction over all).
pub fn check_all(d: &Device, args: &CheckArgs) -> Result<Report, String> {
    let mut report = Report::new(validate::device_name(d), args.alpha);
    let coherent = [
        Group::Thread,
        Group::Warp,
        Group::Block(256),
        Group::Block(1024),
        Group::Grid,
    ];
    strategy::<Cosine>(d, "normal (Cosine)", &[Group::Thread], args, &mut report)?;
    strategy::<CoherentUniform>(d, "CoherentUniform", &coherent, args, &mut report)?;
    strategy::<CoherentCosine>(d, "CoherentCosine", &coherent, args, &mut report)?;
    strategy::<CoherentEqualArea>(d, "CoherentEqualArea", &coherent, args, &mut report)?;
    if !args.samplers_only {
        eprintln!("checking the BSDFs ...");
        let opts = BsdfOptions {
            samples: args.samples,
            seed: args.seed,
            alpha: args.alpha,
            ..Default::default()
        };
        let r = validate::bsdf(d, &validate::builtin_bsdfs(), &opts).map_err(|e| e.to_string())?;
        report.merge(r);
    }
    Ok(report)
}

pub fn run(args: CheckArgs) -> Result<(), String> {
    let d = device(args.backend)?;
    let report = check_all(&d, &args)?;
    println!("{report}");
    if report.passed() {
        return Ok(());
    }
    let written = report
        .write_failure_images(&args.out)
        .map_err(|e| e.to_string())?;
    for p in &written {
        eprintln!("wrote {}", p.display());
    }
    Err(format!(
        "{} of {} tests failed",
        report.failures().len(),
        report.counted()
    ))
}
