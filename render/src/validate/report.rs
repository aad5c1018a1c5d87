//! What the tests found: one [`TestResult`] per test, the Sidak-corrected verdict over all
//! of them ([`Report::passed`]), a table a person reads (`Display`), and the observed and
//! expected tables of failed tests as images ([`Report::write_failure_images`]).

use std::fmt;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::stats::{sidak, Outcome};
use crate::{output, Image};

/// Observed and expected values per cell of a (cos theta, phi) grid: `rows` bands of cos
/// theta (top row: cos theta = 1), `cols` of phi.
#[derive(Clone, Debug)]
pub struct Table {
    pub rows: usize,
    pub cols: usize,
    pub observed: Vec<f64>,
    pub expected: Vec<f64>,
}

/// One test.
#[derive(Clone, Debug)]
pub struct TestResult {
    /// What was tested: a strategy's or a BSDF's name.
    pub subject: String,
    /// Under which conditions: group level, normal, incident direction, parameters.
    pub config: String,
    /// Which test: "marginal", "within draw", "directions", "weights".
    pub test: String,
    pub outcome: Outcome,
    /// For information only: not counted by the Sidak correction nor by `passed`.
    pub informational: bool,
    /// Anything else a person should know (sample counts, integrals).
    pub note: String,
    pub table: Option<Table>,
}

/// The results of a set of tests, at overall significance `alpha`.
#[derive(Clone, Debug)]
pub struct Report {
    /// The device the kernels ran on, in words.
    pub device: String,
    pub alpha: f64,
    pub tests: Vec<TestResult>,
}

impl Report {
    pub fn new(device: String, alpha: f64) -> Report {
        Report {
            device,
            alpha,
            tests: Vec::new(),
        }
    }

    /// The tests that count (not informational).
    pub fn counted(&self) -> usize {
        self.tests.iter().filter(|t| !t.informational).count()
    }

    /// The p-value each counted test must reach: Sidak's correction of `alpha` over them.
    pub fn threshold(&self) -> f64 {
        sidak(self.alpha, self.counted())
    }

    /// Whether test `t` passed (an informational one always does).
    pub fn test_passed(&self, t: &TestResult) -> bool {
        t.informational || (t.outcome.failure.is_none() && t.outcome.p_value >= self.threshold())
    }

    /// Whether every counted test passed.
    pub fn passed(&self) -> bool {
        self.tests.iter().all(|t| self.test_passed(t))
    }

    /// The tests that failed.
    pub fn failures(&self) -> Vec<&TestResult> {
        self.tests.iter().filter(|t| !self.test_passed(t)).collect()
    }

    /// Adds `other`'s tests to this report (the correction then covers them all).
    pub fn merge(&mut self, other: Report) {
        self.tests.extend(other.tests);
    }

    /// Writes, for each failed test with a table, a PNG in `dir`: the observed values, the
    /// expected ones and their difference side by side (rows: cos theta from 1 at the top;
    /// columns: phi from 0 at the left; the difference red where more was observed, blue
    /// where less). Returns the files written.
    pub fn write_failure_images(&self, dir: &Path) -> std::io::Result<Vec<PathBuf>> {
        let mut written = Vec::new();
        for (i, t) in self.tests.iter().enumerate() {
            if self.test_passed(t) {
                continue;
            }
            let Some(table) = &t.table else { continue };
            std::fs::create_dir_all(dir)?;
            let name = format!(
                "{:03}_{}_{}_{}.png",
                i,
                slug(&t.subject),
                slug(&t.config),
                slug(&t.test)
            );
            let path = dir.join(name);
            output::write_png(&path, &table_image(table), 0.0)
                .map_err(|e| std::io::Error::other(e.to_string()))?;
            written.push(path);
        }
        Ok(written)
    }
}

fn slug(s: &str) -> String {
    let s: String = s
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let mut out = String::new();
    for part in s.split('_').filter(|p| !p.is_empty()) {
        if !out.is_empty() {
            out.push('_');
        }
        out.push_str(part);
    }
    out.chars().take(48).collect()
}

/// The three panels of a failed test's image.
fn table_image(t: &Table) -> Image {
    const CELL: usize = 8;
    const GAP: usize = 4;
    let pw = t.cols * CELL;
    let ph = t.rows * CELL;
    let width = 3 * pw + 2 * GAP;
    let max = t
        .expected
        .iter()
        .chain(&t.observed)
        .fold(0.0f64, |a, &b| a.max(b.abs()))
        .max(1e-300);
    let max_diff = t
        .expected
        .iter()
        .zip(&t.observed)
        .fold(0.0f64, |a, (e, o)| a.max((o - e).abs()))
        .max(1e-300);
    let mut pixels = vec![Vec3::splat(0.2); width * ph];
    for r in 0..t.rows {
        for c in 0..t.cols {
            let k = r * t.cols + c;
            let o = (t.observed[k] / max) as f32;
            let e = (t.expected[k] / max) as f32;
            let d = ((t.observed[k] - t.expected[k]) / max_diff) as f32;
            let diff = if d >= 0.0 {
                Vec3::new(d, 0.0, 0.0)
            } else {
                Vec3::new(0.0, 0.0, -d)
            };
            for (panel, color) in [Vec3::splat(o), Vec3::splat(e), diff]
                .into_iter()
                .enumerate()
            {
                let x0 = panel * (pw + GAP) + c * CELL;
                for y in r * CELL..(r + 1) * CELL {
                    for x in x0..x0 + CELL {
                        pixels[y * width + x] = color;
                    }
                }
            }
        }
    }
    Image {
        width: width as u32,
        height: ph as u32,
        paths: vec![1; pixels.len()],
        pixels,
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let threshold = self.threshold();
        writeln!(f, "device: {}", self.device)?;
        writeln!(
            f,
            "{} tests at significance {} (Sidak: each p >= {:.3e}); informational rows marked (i)",
            self.counted(),
            self.alpha,
            threshold
        )?;
        let w_subject = self
            .tests
            .iter()
            .map(|t| t.subject.chars().count())
            .max()
            .unwrap_or(0)
            .max(7);
        let w_config = self
            .tests
            .iter()
            .map(|t| t.config.chars().count())
            .max()
            .unwrap_or(0)
            .max(6);
        writeln!(
            f,
            "{:<w_subject$}  {:<w_config$}  {:<11}  {:>11}  {:>4}  {:>9}  {:<6}  note",
            "subject", "config", "test", "statistic", "dof", "p-value", "result"
        )?;
        for t in &self.tests {
            let result = if t.informational {
                "(i)"
            } else if self.test_passed(t) {
                "pass"
            } else {
                "FAIL"
            };
            let mut note = t.note.clone();
            if let Some(why) = &t.outcome.failure {
                if !note.is_empty() {
                    note.push_str("; ");
                }
                note.push_str(why);
            }
            writeln!(
                f,
                "{:<w_subject$}  {:<w_config$}  {:<11}  {:>11.2}  {:>4}  {:>9.2e}  {:<6}  {}",
                t.subject,
                t.config,
                t.test,
                t.outcome.statistic,
                t.outcome.dof,
                t.outcome.p_value,
                result,
                note
            )?;
        }
        let failed = self.failures().len();
        if failed == 0 {
            write!(f, "passed: all {} tests", self.counted())
        } else {
            write!(f, "FAILED: {failed} of {} tests", self.counted())
        }
    }
}
