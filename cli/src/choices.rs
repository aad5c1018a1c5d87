//! The values the options take, as the parser knows them: every choice among fixed names is
//! a clap `ValueEnum` (so `--help` lists the names and a wrong one is a usage error, before
//! any scene is read or device opened), and every number with a range has a parser that
//! enforces it. `cohort render`, `cohort view` (its live `set NAME VALUE` too), `cohort
//! figures`, `cohort merge` and `cohort compare` take their values from here, so each name
//! and range is written once.

use std::ffi::OsStr;

use clap::builder::{EnumValueParser, PossibleValue, RangedI64ValueParser, TypedValueParser};
use clap::ValueEnum;
use cohort::runtime::BackendKind;
use cohort::Group;
use cohort_render::{Algorithm, InPatch, IntegratorKind};

/// `--backend`: which GPU (or CPU) backend runs the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// WGSL through wgpu.
    Wgpu,
    /// SPIR-V through ash (also accepted as `ash`).
    #[value(alias = "ash")]
    Vulkan,
    /// The native CPU backend (the kernels compiled as Rust).
    Cpu,
}

impl Backend {
    pub fn kind(self) -> BackendKind {
        match self {
            Backend::Wgpu => BackendKind::Wgpu,
            Backend::Vulkan => BackendKind::Vulkan,
            Backend::Cpu => BackendKind::Cpu,
        }
    }
}

/// `--algorithm` (and each item of `figures --configs`): `normal` or a coherence group.
/// The listed names are the paper's; `block_N` with N a multiple of 32 up to 1024 is
/// accepted too.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlgorithmChoice(pub Algorithm);

const fn coherent(group: Group) -> AlgorithmChoice {
    AlgorithmChoice(Algorithm {
        group,
        coherent: true,
    })
}

/// The named algorithms, in the order the viewer's keys 1-6 select them.
static ALGORITHMS: [AlgorithmChoice; 6] = [
    AlgorithmChoice(Algorithm::NORMAL),
    coherent(Group::Warp),
    coherent(Group::Block(256)),
    coherent(Group::Block(512)),
    coherent(Group::Block(1024)),
    coherent(Group::Grid),
];

impl ValueEnum for AlgorithmChoice {
    fn value_variants<'a>() -> &'a [Self] {
        &ALGORITHMS
    }

    /// The listed names, and any `block_N` the renderer takes.
    fn from_str(input: &str, ignore_case: bool) -> Result<Self, String> {
        let name = if ignore_case {
            input.to_ascii_lowercase()
        } else {
            input.to_string()
        };
        Algorithm::parse(&name)
            .map(AlgorithmChoice)
            .ok_or_else(|| format!("invalid variant: {input}"))
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        let (name, help) = match self.0.group {
            _ if !self.0.coherent => (
                "normal",
                "Independent cosine sampling per path (the baseline)",
            ),
            Group::Warp => ("warp", "Coherent: a warp of 32 paths shares a patch"),
            Group::Block(256) => ("block_256", "Coherent: a block of 256 paths shares a patch"),
            Group::Block(512) => ("block_512", "Coherent: a block of 512 paths shares a patch"),
            Group::Block(1024) => (
                "block_1024",
                "Coherent: a block of 1024 paths shares a patch",
            ),
            Group::Grid => ("grid", "Coherent: every path of a dispatch shares a patch"),
            // Other block sizes are accepted but not listed.
            _ => return None,
        };
        Some(PossibleValue::new(name).help(help))
    }
}

impl AlgorithmChoice {
    pub fn name(self) -> String {
        self.0.name()
    }
}

/// The value parser of `--algorithm`: the listed names (a wrong one lists them), or any
/// `block_N` of [`AlgorithmChoice::from_str`].
#[derive(Clone)]
pub struct AlgorithmParser;

impl TypedValueParser for AlgorithmParser {
    type Value = AlgorithmChoice;

    fn parse_ref(
        &self,
        cmd: &clap::Command,
        arg: Option<&clap::Arg>,
        value: &OsStr,
    ) -> Result<AlgorithmChoice, clap::Error> {
        EnumValueParser::<AlgorithmChoice>::new()
            .parse_ref(cmd, arg, value)
            .or_else(|e| {
                value
                    .to_str()
                    .and_then(|s| AlgorithmChoice::from_str(s, true).ok())
                    .ok_or(e)
            })
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(
            ALGORITHMS.iter().filter_map(ValueEnum::to_possible_value),
        ))
    }
}

/// `--in-patch`: how a ray samples inside its group's patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum InPatchChoice {
    /// Uniform by solid angle, weighted by the exact pdf (the paper).
    Uniform,
    /// Cosine-weighted inside the patch.
    Cosine,
    /// Equal-area patches through the Shirley–Chiu concentric map.
    EqualArea,
}

impl InPatchChoice {
    pub fn to_render(self) -> InPatch {
        match self {
            InPatchChoice::Uniform => InPatch::Uniform,
            InPatchChoice::Cosine => InPatch::Cosine,
            InPatchChoice::EqualArea => InPatch::EqualArea,
        }
    }
}

/// `--rr`: who draws the Russian roulette that ends paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RrChoice {
    /// Per path: each path draws its own roulette.
    Path,
    /// Per group: one draw for all paths of a coherence group (the paper's `_rr`).
    Group,
    /// Group roulette plus whole-group termination: when any path of a group ends, the
    /// others play one shared roulette with continuation --end-continue (warp and block
    /// groups only).
    Whole,
}

/// `--roulette`: which continuation probability the roulette (drawn as `--rr` says) uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum RouletteChoice {
    /// `mitsuba` for Mitsuba XML scenes rendered with `--rr path`, `fixed` otherwise.
    Auto,
    /// The paper's constant continuation 0.8 from the first bounce (also `paper`).
    #[value(alias = "paper")]
    Fixed,
    /// Mitsuba's `path`: from the scene's rr_depth on, by throughput.
    Mitsuba,
}

/// `--shading`: how shading is organised (`cohort_render::Shading`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadingChoice {
    /// Both designs measured on the render, the faster kept, where the choice cannot
    /// change the image (a GPU, draws keyed by path, a scene of several BSDF kinds);
    /// elsewhere one kernel.
    Auto,
    /// One shading kernel built with the scene's BSDF kinds shades every ray.
    Kernel,
    /// Material queues: the rays are partitioned by the BSDF kind they hit, and one
    /// shading kernel per kind shades its queue (pbrt-v4's wavefront organisation).
    Queues,
}

impl ShadingChoice {
    pub fn to_render(self) -> cohort_render::Shading {
        match self {
            ShadingChoice::Auto => cohort_render::Shading::Auto,
            ShadingChoice::Kernel => cohort_render::Shading::Kernel,
            ShadingChoice::Queues => cohort_render::Shading::Queues,
        }
    }
}

/// `--integrator`: the light transport estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum IntegratorChoice {
    /// Next-event estimation: an emitter sample at every non-delta vertex, combined with
    /// BSDF sampling by MIS (Mitsuba's `path` integrator).
    Nee,
    /// Implicit path tracing: a path counts only the emitters it hits (the paper's).
    Path,
}

impl IntegratorChoice {
    pub fn to_render(self) -> IntegratorKind {
        match self {
            IntegratorChoice::Nee => IntegratorKind::Nee,
            IntegratorChoice::Path => IntegratorKind::Path,
        }
    }
}

/// `figures --columns`: the columns of Figs. 4, 5 and 7.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ColumnChoice {
    /// The paper's first column: per-path Russian roulette, with compaction.
    Path,
    /// `_rr`: group Russian roulette, with compaction.
    Rr,
    /// `_rr (NO)`: group Russian roulette, no compaction.
    RrNo,
    /// Beyond the paper: whole-group termination, with compaction (`grid` is skipped).
    Whole,
    /// Beyond the paper: whole-group termination, no compaction (`grid` is skipped).
    WholeNo,
}

/// The name of a choice, as the command line writes it.
pub fn name<E: ValueEnum>(value: &E) -> String {
    value
        .to_possible_value()
        .map(|p| p.get_name().to_string())
        .unwrap_or_default()
}

/// Every listed name of a choice, in order.
pub fn names<E: ValueEnum>() -> Vec<String> {
    E::value_variants().iter().map(name).collect()
}

/// Parses a choice by name, as the command line does (the viewer's `set NAME VALUE`).
pub fn parse<E: ValueEnum>(value: &str) -> Result<E, String> {
    E::from_str(value, true)
        .map_err(|_| format!("`{value}` is not one of: {}", names::<E>().join(", ")))
}

/// Parses a number with the value parser the command line uses for it, so that its range
/// is the same everywhere.
pub fn parse_number<P: TypedValueParser>(parser: P, value: &str) -> Result<P::Value, String> {
    parser
        .parse_ref(&clap::Command::new("set"), None, OsStr::new(value))
        .map_err(|e| match std::error::Error::source(&e) {
            Some(why) => format!("`{value}`: {why}"),
            None => format!("`{value}` is not a valid value"),
        })
}

/// `--n`: N of the N x 4N hemisphere patches.
pub fn patches_n() -> RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=1000)
}

/// `--light-cells`: K of the K x K light strata.
pub fn light_cells() -> RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=64)
}

/// Counts and sizes that must be at least 1 (`--paths`, `--width`, `--slices`, ...).
pub fn at_least_one() -> RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

/// `--interleave`: D, odd (pixel coordinates are multiplied by D).
pub fn odd(s: &str) -> Result<u32, String> {
    let d: u32 = s
        .parse()
        .map_err(|_| format!("`{s}` is not a whole number"))?;
    if d.is_multiple_of(2) {
        return Err(format!("{d} is even: D must be odd (1 for none)"));
    }
    Ok(d)
}

/// A continuation probability, in (0, 1] (`--end-continue`).
pub fn probability(s: &str) -> Result<f32, String> {
    let p: f32 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !(p > 0.0 && p <= 1.0) {
        return Err(format!(
            "{p} is not in (0, 1] (0 would cut paths short: biased)"
        ));
    }
    Ok(p)
}

/// The longest time budget taken, in seconds (a Duration of more would overflow).
const MAX_SECONDS: f64 = 1e6;

/// A time budget in seconds: positive and at most 10^6 (`--time`, `--reference-time`).
pub fn seconds(s: &str) -> Result<f64, String> {
    let t: f64 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !(t > 0.0 && t <= MAX_SECONDS) {
        return Err(format!(
            "{t} is not a positive number of seconds up to {MAX_SECONDS:e}"
        ));
    }
    Ok(t)
}

/// A finite number, negative or not (`--exposure`, in stops).
pub fn finite(s: &str) -> Result<f32, String> {
    let v: f32 = s.parse().map_err(|_| format!("`{s}` is not a number"))?;
    if !v.is_finite() {
        return Err(format!("{v} is not a finite number"));
    }
    Ok(v)
}

/// A finite number, zero or more (`compare --tolerance`).
pub fn non_negative(s: &str) -> Result<f32, String> {
    let v = finite(s)?;
    if v < 0.0 {
        return Err(format!("{v} is negative: a tolerance is 0 or more"));
    }
    Ok(v)
}

/// `--devices`: `all`, or device indices such as `0,1`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum DeviceList {
    All,
    Indices(Vec<usize>),
}

pub fn device_list(s: &str) -> Result<DeviceList, String> {
    if s.trim() == "all" {
        return Ok(DeviceList::All);
    }
    let mut indices: Vec<usize> = Vec::new();
    for item in s.split(',').map(str::trim) {
        let i: usize = item.parse().map_err(|_| {
            format!("`{item}` is not a device index (expected `all` or a list such as 0,1)")
        })?;
        if indices.contains(&i) {
            return Err(format!("device {i} is listed twice"));
        }
        indices.push(i);
    }
    Ok(DeviceList::Indices(indices))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for v in RrChoice::value_variants() {
            assert_eq!(parse::<RrChoice>(&name(v)).unwrap(), *v);
        }
        assert_eq!(
            names::<InPatchChoice>(),
            ["uniform", "cosine", "equal-area"]
        );
        assert_eq!(parse::<Backend>("ash").unwrap(), Backend::Vulkan);
        assert_eq!(
            parse::<RouletteChoice>("paper").unwrap(),
            RouletteChoice::Fixed
        );
        assert!(parse::<RrChoice>("sometimes")
            .unwrap_err()
            .contains("path, group, whole"));
    }

    #[test]
    fn algorithms_take_any_block_size_the_renderer_takes() {
        let block_64 = parse::<AlgorithmChoice>("block_64").unwrap();
        assert_eq!(block_64.0.group, Group::Block(64));
        assert_eq!(block_64.name(), "block_64");
        assert!(parse::<AlgorithmChoice>("block_100").is_err());
        assert_eq!(
            names::<AlgorithmChoice>(),
            [
                "normal",
                "warp",
                "block_256",
                "block_512",
                "block_1024",
                "grid"
            ]
        );
        for a in AlgorithmChoice::value_variants() {
            assert_eq!(parse::<AlgorithmChoice>(&a.name()).unwrap(), *a);
        }
    }

    #[test]
    fn numbers_are_checked_by_the_command_lines_parsers() {
        assert_eq!(parse_number(patches_n(), "1000").unwrap(), 1000);
        assert!(parse_number(patches_n(), "0")
            .unwrap_err()
            .contains("1..=1000"));
        assert!(parse_number(odd, "4").unwrap_err().contains("odd"));
        assert!(probability("0").is_err() && probability("1").is_ok());
        assert!(seconds("-1").is_err() && seconds("1e300").is_err());
        assert!(non_negative("-1").is_err() && finite("-1").is_ok());
        assert_eq!(
            device_list("0, 2").unwrap(),
            DeviceList::Indices(vec![0, 2])
        );
        assert!(device_list("0,0").unwrap_err().contains("twice"));
    }
}
