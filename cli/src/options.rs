//! The renderer configuration a user chooses by name (`--algorithm block_256`, `--rr
//! group`, ...), parsed once for `cohort render` and `cohort view`. The viewer also
//! changes it live, by the same names (`set algorithm grid` in a script, a key in the
//! window), and `--compare` gives a second one as `name=value` overrides.

use cohort_render::{RenderOptions, Roulette};

use crate::choices::{
    self, AlgorithmChoice, InPatchChoice, IntegratorChoice, RouletteChoice, RrChoice, ShadingChoice,
};

/// The options that select the estimator and the paper's configuration, as the user
/// chose them.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub algorithm: AlgorithmChoice,
    pub n: u32,
    pub in_patch: InPatchChoice,
    pub rr: RrChoice,
    pub roulette: RouletteChoice,
    pub end_continue: f32,
    pub interleave: u32,
    pub coherent_glossy: bool,
    pub compact: bool,
    pub retire: bool,
    pub reorder: u32,
    pub shading: ShadingChoice,
    pub integrator: IntegratorChoice,
    pub coherent_light: bool,
    pub light_cells: u32,
    pub seed: u32,
    /// Ray slots in flight (`RenderOptions::wavefront`); fixed for a renderer's life, so
    /// not one of the names `set` changes.
    pub wavefront: Option<u32>,
}

/// Every name `Config::set` takes, for error messages and the viewer's help.
pub const NAMES: &[&str] = &[
    "algorithm",
    "n",
    "in-patch",
    "rr",
    "roulette",
    "end-continue",
    "interleave",
    "coherent-glossy",
    "compact",
    "retire",
    "reorder",
    "shading",
    "integrator",
    "coherent-light",
    "light-cells",
    "seed",
];

fn parse_bool(v: &str) -> Result<bool, String> {
    match v {
        "true" | "on" | "yes" | "1" => Ok(true),
        "false" | "off" | "no" | "0" => Ok(false),
        _ => Err(format!("expected on or off, got `{v}`")),
    }
}

impl Config {
    /// Sets the option `name` (as on the command line, without `--`) to `value`, parsed
    /// and range-checked as the command line does ([`choices`]).
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        use choices::{parse, parse_number};
        let r: Result<(), String> = match name {
            "algorithm" => parse(value).map(|v| self.algorithm = v),
            "n" => parse_number(choices::patches_n(), value).map(|v| self.n = v),
            "in-patch" => parse(value).map(|v| self.in_patch = v),
            "rr" => parse(value).map(|v| self.rr = v),
            "roulette" => parse(value).map(|v| self.roulette = v),
            "end-continue" => {
                parse_number(choices::probability, value).map(|v| self.end_continue = v)
            }
            "interleave" => parse_number(choices::odd, value).map(|v| self.interleave = v),
            "coherent-glossy" => parse_bool(value).map(|v| self.coherent_glossy = v),
            "compact" => parse_bool(value).map(|v| self.compact = v),
            "retire" => parse_bool(value).map(|v| self.retire = v),
            "reorder" => parse_number(clap::value_parser!(u32), value).map(|v| self.reorder = v),
            "shading" => parse(value).map(|v| self.shading = v),
            "integrator" => parse(value).map(|v| self.integrator = v),
            "coherent-light" => parse_bool(value).map(|v| self.coherent_light = v),
            "light-cells" => {
                parse_number(choices::light_cells(), value).map(|v| self.light_cells = v)
            }
            "seed" => parse_number(clap::value_parser!(u32), value).map(|v| self.seed = v),
            _ => {
                return Err(format!(
                    "unknown option `{name}` (one of: {})",
                    NAMES.join(", ")
                ))
            }
        };
        r.map_err(|e| format!("{name}: {e}"))
    }

    /// The value of the option `name`, as `set` takes it (`None`: no such option).
    pub fn get(&self, name: &str) -> Option<String> {
        use choices::name as n;
        let on_off = |b: bool| if b { "on" } else { "off" }.to_string();
        Some(match name {
            "algorithm" => self.algorithm.name(),
            "n" => self.n.to_string(),
            "in-patch" => n(&self.in_patch),
            "rr" => n(&self.rr),
            "roulette" => n(&self.roulette),
            "end-continue" => self.end_continue.to_string(),
            "interleave" => self.interleave.to_string(),
            "coherent-glossy" => on_off(self.coherent_glossy),
            "compact" => on_off(self.compact),
            "retire" => on_off(self.retire),
            "reorder" => self.reorder.to_string(),
            "shading" => n(&self.shading),
            "integrator" => n(&self.integrator),
            "coherent-light" => on_off(self.coherent_light),
            "light-cells" => self.light_cells.to_string(),
            "seed" => self.seed.to_string(),
            _ => return None,
        })
    }

    /// Applies `name=value` overrides separated by commas (`--compare`).
    pub fn with_overrides(&self, overrides: &str) -> Result<Config, String> {
        let mut c = self.clone();
        for item in overrides
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
        {
            let (k, v) = item
                .split_once('=')
                .ok_or_else(|| format!("expected NAME=VALUE, got `{item}`"))?;
            c.set(k.trim().trim_start_matches("--"), v.trim())?;
        }
        Ok(c)
    }

    /// The renderer's options for a scene (`embedded`: one of the embedded scenes, which
    /// decides the `auto` roulette). Combinations are checked by `RenderOptions::check`.
    pub fn options(&self, embedded: bool) -> RenderOptions {
        let (group_rr, whole_group_end) = match self.rr {
            RrChoice::Path => (false, None),
            RrChoice::Group => (true, None),
            RrChoice::Whole => (true, Some(self.end_continue)),
        };
        let roulette = match self.roulette {
            RouletteChoice::Auto if self.rr == RrChoice::Path && !embedded => Roulette::Mitsuba,
            RouletteChoice::Auto | RouletteChoice::Fixed => Roulette::Fixed,
            RouletteChoice::Mitsuba => Roulette::Mitsuba,
        };
        RenderOptions {
            algorithm: self.algorithm.0,
            in_patch: self.in_patch.to_render(),
            patches_n: self.n,
            group_rr,
            interleave: self.interleave,
            coherent_glossy: self.coherent_glossy,
            seed: self.seed,
            compact: self.compact,
            retire: self.retire,
            reorder: self.reorder,
            shading: self.shading.to_render(),
            whole_group_end,
            integrator: self.integrator.to_render(),
            roulette,
            coherent_light: self.coherent_light,
            light_cells: self.light_cells,
            wavefront: self.wavefront,
            ..Default::default()
        }
    }

    /// One line naming the configuration as the paper does (`block_256_rr (NO), N = 64,
    /// ...`).
    pub fn label(&self) -> String {
        format!(
            "{}{}{}, N = {}, in-patch {}, D = {}, integrator {}{}",
            self.algorithm.name(),
            match self.rr {
                RrChoice::Whole => format!("_rr, whole-group end (q = {})", self.end_continue),
                RrChoice::Group => "_rr".into(),
                RrChoice::Path => String::new(),
            },
            if self.compact { "" } else { " (NO)" },
            self.n,
            choices::name(&self.in_patch),
            self.interleave,
            choices::name(&self.integrator),
            if self.coherent_light {
                format!(", coherent light (K = {})", self.light_cells)
            } else {
                String::new()
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn base() -> Config {
        Config {
            algorithm: choices::parse("normal").unwrap(),
            n: 64,
            in_patch: InPatchChoice::Uniform,
            rr: RrChoice::Path,
            roulette: RouletteChoice::Auto,
            end_continue: 0.5,
            interleave: 1,
            coherent_glossy: false,
            compact: false,
            retire: true,
            reorder: 0,
            shading: ShadingChoice::Auto,
            integrator: IntegratorChoice::Nee,
            coherent_light: false,
            light_cells: 4,
            seed: 1,
            wavefront: None,
        }
    }

    #[test]
    fn overrides_set_named_options_and_reject_unknown_ones() {
        let c = base()
            .with_overrides("algorithm=block_256, interleave=5,compact=on,retire=off")
            .unwrap();
        assert_eq!(c.algorithm.name(), "block_256");
        assert_eq!(c.interleave, 5);
        assert!(c.compact);
        assert!(!c.retire && !c.options(true).retire);
        let o = c.options(true);
        assert!(o.algorithm.coherent);
        assert_eq!(o.interleave, 5);
        let refused = |overrides: &str, needle: &str| {
            let e = base().with_overrides(overrides).unwrap_err();
            assert!(e.contains(needle), "{overrides}: {e}");
        };
        refused("colour=red", "unknown option");
        refused("n=many", "n: `many`");
        refused("algorithm", "expected NAME=VALUE");
        refused("algorithm=block_3", "normal, warp, block_256");
        // The same ranges as the command line's.
        refused("n=0", "1..=1000");
        refused("interleave=4", "odd");
        refused("end-continue=0", "(0, 1]");
        refused("light-cells=65", "1..=64");
        let c = base()
            .with_overrides("rr=WHOLE,in-patch=equal-area")
            .unwrap();
        assert_eq!(c.get("rr").unwrap(), "whole");
        assert_eq!(c.get("in-patch").unwrap(), "equal-area");
    }

    #[test]
    fn auto_roulette_is_mitsubas_for_xml_scenes_with_per_path_roulette() {
        assert_eq!(base().options(false).roulette, Roulette::Mitsuba);
        assert_eq!(base().options(true).roulette, Roulette::Fixed);
        let group = base().with_overrides("rr=group").unwrap();
        assert_eq!(group.options(false).roulette, Roulette::Fixed);
    }
}
