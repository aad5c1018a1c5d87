//! Every repository file the documentation names in backticks exists: the README,
//! `docs/*.md` and BENCHMARKS.md point readers at sources, scripts, tests and results, and
//! a moved or deleted file must not leave a dead reference behind (issue 10, "the house").
//! Paths outside the repository (`../shared/...`) and placeholders (`DIR/figures.csv`, an
//! all-capitals component) are not checked; a path may be given relative to the repository
//! or to the `tests` crate (the compile-fail cases).

use std::path::{Path, PathBuf};

const EXTENSIONS: &[&str] = &[
    "rs", "md", "py", "sh", "toml", "xml", "json", "yaml", "yml", "exr", "csv", "png", "gz",
];

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The backticked spans of `text` that look like repository paths.
fn named_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for span in text.split('`').skip(1).step_by(2) {
        // `path:line` and `path:line-line` name a place in the file.
        let path = span.split(':').next().unwrap_or("");
        let plausible = path.contains('/')
            && !path.starts_with("../")
            && !path.starts_with("...")
            && !path.starts_with('/')
            && path
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_./-".contains(c))
            && EXTENSIONS.iter().any(|e| path.ends_with(&format!(".{e}")));
        let placeholder = path.split('/').any(|c| {
            let stem = c.split('.').next().unwrap_or("");
            !stem.is_empty() && stem.chars().all(|ch| ch.is_ascii_uppercase() || ch == '_')
        });
        if plausible && !placeholder {
            out.push(path.to_string());
        }
    }
    out
}

#[test]
fn documented_paths_exist() {
    let root = repo();
    let mut docs = vec![root.join("README.md"), root.join("BENCHMARKS.md")];
    for entry in std::fs::read_dir(root.join("docs")).unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "md") {
            docs.push(p);
        }
    }
    let mut missing = Vec::new();
    let mut checked = 0;
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for path in named_paths(&text) {
            checked += 1;
            if !root.join(&path).exists() && !root.join("tests").join(&path).exists() {
                missing.push(format!("{}: `{path}`", doc.display()));
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} paths found: is the scan broken?"
    );
    assert!(
        missing.is_empty(),
        "documentation names files that do not exist:\n{}",
        missing.join("\n")
    );
}

#[test]
fn the_scan_finds_paths_and_skips_placeholders() {
    let text = "see `render/src/lights.rs:12-40`, `../shared/PAPER.md`, `DIR/figures.csv`, \
                `cohort render`, `a/b.txt` and `docs/results/x.csv.gz`";
    assert_eq!(
        named_paths(text),
        ["render/src/lights.rs", "docs/results/x.csv.gz"]
    );
}
