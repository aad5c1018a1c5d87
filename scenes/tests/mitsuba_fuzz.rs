//! A small randomized test of the Mitsuba loader: the shared scenes' XML text, mutated (attributes
//! deleted or altered, elements duplicated, deleted, swapped or renamed, the text cut short),
//! must load or fail with an error, strictly and leniently, and never panic. Deterministic seed;
//! bounded in iterations and time.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use cohort_scenes::{load_mitsuba_str_with, LoadOptions};

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[self.below(items.len())]
    }
}

const VALUES: &[&str] = &[
    "",
    "-1",
    "0",
    "1",
    "nan",
    "inf",
    "1e40",
    "-1e40",
    "abc",
    "$x",
    "\\$",
    "$",
    "x y z",
    "1, 2",
    "1,2,3,4",
    "99999999999999999999",
    "ggx",
    "beckmann",
    "none",
    "Au",
    "water",
    "obj",
    "ply",
    "sphere",
    "nosuch",
    "scene.xml",
    "meshes",
    "..",
    "diagonal",
    "true",
    "maybe",
    "3.0.0",
    "0.6.0",
];

const TAGS: &[&str] = &[
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "texture",
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
    "translate",
    "rotate",
    "scale",
    "lookat",
    "matrix",
    "ref",
    "include",
    "path",
    "default",
    "alias",
    "wibble",
    "scene",
];

const INSERTS: &[&str] = &[
    r#"<ref id="zz"/>"#,
    r#"<include filename="scene.xml"/>"#,
    r#"<path value="meshes"/>"#,
    r#"<default name="x" value="1"/>"#,
    r#"<bsdf type="twosided" id="loop"><ref id="loop"/></bsdf>"#,
    r#"<shape type="sphere"><ref name="bsdf" id="zz"/></shape>"#,
    r#"<emitter type="constant"/>"#,
    r#"<integrator type="aov"><integrator type="path"/></integrator>"#,
    "<",
    "</shape>",
    "<!-- -->",
];

/// Byte ranges of the attribute values (between the quotes) in `text`.
fn attribute_values(text: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(i) = text[from..].find("=\"") {
        let start = from + i + 2;
        let Some(len) = text[start..].find('"') else {
            break;
        };
        out.push((start, start + len));
        from = start + len + 1;
    }
    out
}

fn mutate(rng: &mut Rng, text: &str) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let n = lines.len();
    if n == 0 {
        return rng.pick(INSERTS).to_string();
    }
    match rng.below(9) {
        0 => {
            // Delete an attribute (name="value").
            let values = attribute_values(text);
            if values.is_empty() {
                return text.to_string();
            }
            let (start, end) = values[rng.below(values.len())];
            let name_start = text[..start - 2]
                .rfind(|c: char| c.is_whitespace())
                .map_or(0, |i| i + 1);
            return format!("{}{}", &text[..name_start], &text[end + 1..]);
        }
        1 => {
            // Alter an attribute value.
            let values = attribute_values(text);
            if values.is_empty() {
                return text.to_string();
            }
            let (start, end) = values[rng.below(values.len())];
            let v = rng.pick(VALUES);
            return format!("{}{v}{}", &text[..start], &text[end..]);
        }
        2 => {
            let i = rng.below(n);
            let line = lines[i].clone();
            lines.insert(i, line);
        }
        3 => {
            lines.remove(rng.below(n));
        }
        4 => {
            let (a, b) = (rng.below(n), rng.below(n));
            lines.swap(a, b);
        }
        5 => {
            // Cut the text short.
            let mut cut = rng.below(text.len());
            while !text.is_char_boundary(cut) {
                cut -= 1;
            }
            return text[..cut].to_string();
        }
        6 => {
            // Rename an element.
            let i = rng.below(n);
            if let Some(start) = lines[i].find('<') {
                let rest = &lines[i][start + 1..];
                let len = rest
                    .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .unwrap_or(rest.len());
                let tag = rng.pick(TAGS);
                lines[i] = format!("{}<{tag}{}", &lines[i][..start], &rest[len..]);
            }
        }
        7 => {
            let i = rng.below(n);
            lines.insert(i, rng.pick(INSERTS).to_string());
        }
        _ => {
            // Duplicate a whole element block (from a line to the next line at its indent).
            let i = rng.below(n);
            let j = (i + 1 + rng.below(12)).min(n);
            let block: Vec<String> = lines[i..j].to_vec();
            for (k, l) in block.into_iter().enumerate() {
                lines.insert(j + k, l);
            }
        }
    }
    lines.join("\n")
}

fn env_rounds_set() -> bool {
    std::env::var_os("COHORT_FUZZ_ROUNDS").is_some()
}

#[test]
fn mutated_shared_scenes_never_panic() {
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes");
    let budget = Duration::from_secs(if env_rounds_set() { 3600 } else { 20 });
    let start = Instant::now();
    // COHORT_FUZZ_SEED / COHORT_FUZZ_ROUNDS run it longer or elsewhere; the default is fixed.
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let mut rng = Rng(env("COHORT_FUZZ_SEED").unwrap_or(0x9E37_79B9_7F4A_7C15) | 1);
    let rounds = env("COHORT_FUZZ_ROUNDS").unwrap_or(1500);
    let (mut loaded, mut failed, mut runs) = (0, 0, 0);
    let scenes = ["cornell-box", "stanford-like"];
    'outer: for round in 0..rounds {
        for name in scenes {
            let dir = shared.join(name);
            let Ok(original) = std::fs::read_to_string(dir.join("scene.xml")) else {
                eprintln!("{} missing: skipped", dir.display());
                continue;
            };
            let mut text = original;
            for _ in 0..1 + rng.below(3) {
                text = mutate(&mut rng, &text);
            }
            for lenient in [false, true] {
                let options = LoadOptions {
                    lenient,
                    params: if rng.below(4) == 0 {
                        vec![("x".into(), rng.pick(VALUES).into())]
                    } else {
                        Vec::new()
                    },
                };
                let result = catch_unwind(AssertUnwindSafe(|| {
                    load_mitsuba_str_with(&text, &dir, &options)
                }));
                match result {
                    Ok(Ok(_)) => loaded += 1,
                    Ok(Err(_)) => failed += 1,
                    Err(_) => panic!(
                        "the loader panicked (round {round}, {name}, lenient {lenient}) on:\n{text}"
                    ),
                }
                runs += 1;
            }
            if start.elapsed() > budget {
                break 'outer;
            }
        }
    }
    println!(
        "{runs} loads: {loaded} ok, {failed} errors, {:.1?}",
        start.elapsed()
    );
    assert!(runs > 0);
}
