//! The renderer configuration a user chooses by name (`--algorithm block_256`, `--rr
//! group`, ...), parsed once for `cohort render` and `cohort view`. The viewer also
//! changes it live, by the same names (`set algorithm grid` in a script, a key in the
//! window), and `--compare` gives a second one as `name=value` overrides.

use cohort_render::{Algorithm, InPatch, IntegratorKind, RenderOptions, Roulette};

/// The options that select the estimator and the paper's configuration, as the user
/// wrote them.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub algorithm: String,
    pub n: u32,
    pub in_patch: String,
    pub rr: String,
    pub roulette: String,
    pub end_continue: f32,
    pub interleave: u32,
    pub coherent_glossy: bool,
    pub compact: bool,
    pub reorder: u32,
    pub integrator: String,
    pub coherent_light: bool,
    pub light_cells: u32,
    pub seed: u32,
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
    "reorder",
    "integrator",
    "coherent-light",
    "light-cells",
    "seed",
];

/// The algorithms in the order the viewer cycles through them (keys 1-6).
pub const ALGORITHMS: &[&str] = &[
    "normal",
    "warp",
    "block_256",
    "block_512",
    "block_1024",
    "grid",
];

fn parse_bool(v: &str) -> Result<bool, String> {
    match v {
        "true" | "on" | "yes" | "1" => Ok(true),
        "false" | "off" | "no" | "0" => Ok(false),
        _ => Err(format!("expected on or off, got `{v}`")),
    }
}

fn parse_num<T: std::str::FromStr>(v: &str) -> Result<T, String> {
    v.parse().map_err(|_| format!("`{v}` is not a number"))
}

impl Config {
    /// Sets the option `name` (as on the command line, without `--`) to `value`; the
    /// value is checked when the options are built ([`Config::options`]).
    pub fn set(&mut self, name: &str, value: &str) -> Result<(), String> {
        let r: Result<(), String> = match name {
            "algorithm" => {
                self.algorithm = value.to_string();
                Ok(())
            }
            "n" => parse_num(value).map(|v| self.n = v),
            "in-patch" => {
                self.in_patch = value.to_string();
                Ok(())
            }
            "rr" => {
                self.rr = value.to_string();
                Ok(())
            }
            "roulette" => {
                self.roulette = value.to_string();
                Ok(())
            }
            "end-continue" => parse_num(value).map(|v| self.end_continue = v),
            "interleave" => parse_num(value).map(|v| self.interleave = v),
            "coherent-glossy" => parse_bool(value).map(|v| self.coherent_glossy = v),
            "compact" => parse_bool(value).map(|v| self.compact = v),
            "reorder" => parse_num(value).map(|v| self.reorder = v),
            "integrator" => {
                self.integrator = value.to_string();
                Ok(())
            }
            "coherent-light" => parse_bool(value).map(|v| self.coherent_light = v),
            "light-cells" => parse_num(value).map(|v| self.light_cells = v),
            "seed" => parse_num(value).map(|v| self.seed = v),
            _ => {
                return Err(format!(
                    "unknown option `{name}` (one of: {})",
                    NAMES.join(", ")
                ))
            }
        };
        r.map_err(|e| format!("{name}: {e}"))
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
    /// decides the `auto` roulette), checking every name.
    pub fn options(&self, embedded: bool) -> Result<RenderOptions, String> {
        let algorithm = Algorithm::parse(&self.algorithm).ok_or_else(|| {
            format!(
                "unknown algorithm `{}` (available: {})",
                self.algorithm,
                ALGORITHMS.join(", ")
            )
        })?;
        let in_patch = match self.in_patch.as_str() {
            "uniform" => InPatch::Uniform,
            "cosine" => InPatch::Cosine,
            "equal-area" => InPatch::EqualArea,
            other => {
                return Err(format!(
                    "unknown --in-patch `{other}` (uniform, cosine or equal-area)"
                ))
            }
        };
        let (group_rr, whole_group_end) = match self.rr.as_str() {
            "path" => (false, None),
            "group" => (true, None),
            "whole" => (true, Some(self.end_continue)),
            other => return Err(format!("unknown --rr `{other}` (path, group or whole)")),
        };
        let roulette = match self.roulette.as_str() {
            "auto" if self.rr == "path" && !embedded => Roulette::Mitsuba,
            "auto" => Roulette::Fixed,
            other => Roulette::parse(other)
                .ok_or_else(|| format!("unknown --roulette `{other}` (auto, fixed or mitsuba)"))?,
        };
        let integrator = IntegratorKind::parse(&self.integrator)
            .ok_or_else(|| format!("unknown --integrator `{}` (nee or path)", self.integrator))?;
        Ok(RenderOptions {
            algorithm,
            in_patch,
            patches_n: self.n,
            group_rr,
            interleave: self.interleave,
            coherent_glossy: self.coherent_glossy,
            seed: self.seed,
            compact: self.compact,
            reorder: self.reorder,
            whole_group_end,
            integrator,
            roulette,
            coherent_light: self.coherent_light,
            light_cells: self.light_cells,
            ..Default::default()
        })
    }

    /// One line naming the configuration as the paper does (`block_256_rr (NO), N = 64,
    /// ...`).
    pub fn label(&self) -> String {
        format!(
            "{}{}{}, N = {}, in-patch {}, D = {}, integrator {}{}",
            self.algorithm,
            match self.rr.as_str() {
                "whole" => format!("_rr, whole-group end (q = {})", self.end_continue),
                "group" => "_rr".into(),
                _ => String::new(),
            },
            if self.compact { "" } else { " (NO)" },
            self.n,
            self.in_patch,
            self.interleave,
            self.integrator,
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
            algorithm: "normal".into(),
            n: 64,
            in_patch: "uniform".into(),
            rr: "path".into(),
            roulette: "auto".into(),
            end_continue: 0.5,
            interleave: 1,
            coherent_glossy: false,
            compact: false,
            reorder: 0,
            integrator: "nee".into(),
            coherent_light: false,
            light_cells: 4,
            seed: 1,
        }
    }

    #[test]
    fn overrides_set_named_options_and_reject_unknown_ones() {
        let c = base()
            .with_overrides("algorithm=block_256, interleave=5,compact=on")
            .unwrap();
        assert_eq!(c.algorithm, "block_256");
        assert_eq!(c.interleave, 5);
        assert!(c.compact);
        let o = c.options(true).unwrap();
        assert!(o.algorithm.coherent);
        assert_eq!(o.interleave, 5);
        assert!(base()
            .with_overrides("colour=red")
            .unwrap_err()
            .contains("unknown option"));
        assert!(base()
            .with_overrides("n=many")
            .unwrap_err()
            .contains("not a number"));
        assert!(base().with_overrides("algorithm").is_err());
        let bad = base().with_overrides("algorithm=block_3").unwrap();
        assert!(bad.options(true).unwrap_err().contains("unknown algorithm"));
    }

    #[test]
    fn auto_roulette_is_mitsubas_for_xml_scenes_with_per_path_roulette() {
        assert_eq!(base().options(false).unwrap().roulette, Roulette::Mitsuba);
        assert_eq!(base().options(true).unwrap().roulette, Roulette::Fixed);
        let group = base().with_overrides("rr=group").unwrap();
        assert_eq!(group.options(false).unwrap().roulette, Roulette::Fixed);
    }
}
