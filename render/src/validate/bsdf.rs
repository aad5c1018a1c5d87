//! The test of a BSDF's sampling routine: its kernel ([`sample_bsdf`]) draws directions for
//! one incident direction; the density it claims ([`eval_bsdf`], the renderer's MIS density)
//! and its value f·|cos| are integrated per cell of a (cos theta, phi) grid over the whole
//! sphere by a midpoint rule on a sub-grid, on the same device.
//!
//! - **directions** (counted): the counts per cell against the density's integrals,
//!   Pearson's test (`stats`); samples that fail (weight 0) count in a cell of their own,
//!   whose expected count is what the density lacks of 1. A density whose integral exceeds
//!   1 by more than the quadrature's error fails.
//! - **weights** (counted): the weights per cell against the integrals of f·|cos|, by the
//!   test of weighted means: what an unbiased estimator needs, whatever the density. Where
//!   the renderer weighs a sample by f·|cos| / density, each weight is also compared with
//!   that ratio at its direction (relative 1e-3).

use std::path::PathBuf;

use cohort::runtime::Device;
use cohort::Group;
use cohort_kernels::layout::Principled;
use cohort_kernels::sampling::polar_dir;
use cohort_kernels::validate::*;
use glam::{Vec2, Vec3, Vec4};

use super::report::{Report, Table, TestResult};
use super::stats::{pearson, MeanTest, Outcome};
use super::{device_name, ValidateError};

/// One BSDF with its parameters.
#[derive(Clone, Debug)]
pub struct BsdfCase {
    pub name: String,
    /// The kind and parameters (`wo`, `n` and `seed` are set per test).
    pub params: BsdfParams,
    /// `principled` and `principledthin` only.
    pub principled: Principled,
    /// The group level its samples are drawn at: above `Thread` only with coherent
    /// sampling (`params.cells` not 0), whose groups share their cell of the unit square.
    pub level: Group,
}

impl BsdfCase {
    fn new(name: &str, kind: u32, alpha: Vec2, eta: f32, beckmann: bool) -> BsdfCase {
        BsdfCase {
            name: name.into(),
            params: BsdfParams {
                kind,
                alpha,
                eta,
                beckmann: beckmann as u32,
                choose: 0.5,
                base: 0.5,
                ..Default::default()
            },
            principled: Principled::default(),
            level: Group::Thread,
        }
    }

    /// This case sampled coherently (`extend`'s `coherent_glossy`) by groups of `level`,
    /// sharing a cell of a `cells` x `cells` grid over the unit square.
    pub fn coherent(mut self, level: Group, cells: u32) -> BsdfCase {
        self.name = format!(
            "{} coherent {}",
            self.name,
            super::sampler::level_name(level)
        );
        self.level = level;
        self.params.cells = cells;
        self
    }
}

fn principled(name: &str, thin: bool, roughness: f32, anisotropic: f32) -> BsdfCase {
    let mut c = BsdfCase::new(
        name,
        if thin {
            VALIDATE_PRINCIPLED_THIN
        } else {
            VALIDATE_PRINCIPLED
        },
        Vec2::ZERO,
        1.5,
        false,
    );
    c.principled = Principled {
        base_color: Vec3::new(0.8, 0.5, 0.3),
        roughness,
        anisotropic,
        metallic: 0.3,
        spec_trans: 0.4,
        spec_tint: 0.2,
        sheen: 0.3,
        sheen_tint: 0.5,
        clearcoat: 0.5,
        clearcoat_gloss: 0.5,
        flatness: 0.3,
        diff_trans: 0.5,
        eta: 1.5,
        rate_a: 1.0,
        rate_b: 1.0,
        rate_c: 1.0,
        rate_d: 1.0,
        pad: 0,
    };
    c
}

/// The renderer's BSDFs, each at a few parameters.
pub fn builtin_bsdfs() -> Vec<BsdfCase> {
    let iso = Vec2::splat(0.4);
    let aniso = Vec2::new(0.25, 0.6);
    vec![
        BsdfCase::new("diffuse", VALIDATE_DIFFUSE, Vec2::ZERO, 1.0, false),
        BsdfCase::new(
            "roughconductor ggx a=0.4",
            VALIDATE_CONDUCTOR,
            iso,
            1.0,
            false,
        ),
        BsdfCase::new(
            "roughconductor ggx a=(0.25,0.6)",
            VALIDATE_CONDUCTOR,
            aniso,
            1.0,
            false,
        ),
        BsdfCase::new(
            "roughconductor beckmann a=0.4",
            VALIDATE_CONDUCTOR,
            iso,
            1.0,
            true,
        ),
        BsdfCase::new(
            "roughdielectric ggx a=0.4 eta=1.5",
            VALIDATE_DIELECTRIC,
            iso,
            1.5,
            false,
        ),
        BsdfCase::new(
            "roughdielectric ggx a=(0.25,0.6) eta=1/1.5",
            VALIDATE_DIELECTRIC,
            aniso,
            1.0 / 1.5,
            false,
        ),
        BsdfCase::new(
            "roughdielectric beckmann a=0.4 eta=1.5",
            VALIDATE_DIELECTRIC,
            iso,
            1.5,
            true,
        ),
        BsdfCase::new(
            "roughplastic coating ggx a=0.4",
            VALIDATE_COATING,
            iso,
            1.5,
            false,
        ),
        BsdfCase::new(
            "roughplastic coating beckmann a=0.4",
            VALIDATE_COATING,
            iso,
            1.5,
            true,
        ),
        BsdfCase::new(
            "roughplastic ggx a=0.4",
            VALIDATE_ROUGH_PLASTIC,
            iso,
            1.5,
            false,
        ),
        principled("principled r=0.5", false, 0.5, 0.0),
        principled("principled r=0.6 aniso=0.5", false, 0.6, 0.5),
        principled("principledthin r=0.5", true, 0.5, 0.0),
        BsdfCase::new(
            "roughconductor ggx a=0.4",
            VALIDATE_CONDUCTOR,
            iso,
            1.0,
            false,
        )
        .coherent(Group::Warp, 16),
        BsdfCase::new(
            "roughconductor beckmann a=(0.25,0.6)",
            VALIDATE_CONDUCTOR,
            aniso,
            1.0,
            true,
        )
        .coherent(Group::Warp, 16),
    ]
}

/// How [`bsdf`] tests.
#[derive(Clone, Debug)]
pub struct BsdfOptions {
    /// Samples per BSDF and incident direction.
    pub samples: u32,
    /// The incident directions' cos theta (phi 0.3).
    pub incident: Vec<f32>,
    /// Bands of cos theta in [-1, 1] and sectors of phi.
    pub cos_bins: usize,
    pub phi_bins: usize,
    /// Quadrature points per cell and axis.
    pub sub: usize,
    pub seed: u32,
    pub alpha: f64,
    /// Pooling: the least expected count of a cell (directions) and of samples landing in a
    /// cell (weights).
    pub min_expected: f64,
    pub min_draws: f64,
    /// Where to write the observed and expected tables of failed tests (PNG).
    pub out: Option<PathBuf>,
}

impl Default for BsdfOptions {
    fn default() -> Self {
        BsdfOptions {
            samples: 1 << 17,
            incident: vec![0.9, 0.5, 0.15],
            cos_bins: 16,
            phi_bins: 32,
            sub: 16,
            seed: 7,
            alpha: 0.01,
            min_expected: 5.0,
            min_draws: 10.0,
            out: None,
        }
    }
}

fn cell(d: Vec3, tb: usize, pb: usize) -> usize {
    let row = (((1.0 - d.z.clamp(-1.0, 1.0) as f64) * 0.5 * tb as f64) as usize).min(tb - 1);
    let mut phi = (d.y as f64).atan2(d.x as f64);
    if phi < 0.0 {
        phi += 2.0 * std::f64::consts::PI;
    }
    let col = ((phi / (2.0 * std::f64::consts::PI) * pb as f64) as usize).min(pb - 1);
    row * pb + col
}

/// The per-cell integrals of a BSDF over the (cos theta, phi) grid ([`integrate`]).
struct Integrals {
    /// f·|cos|.
    f: Vec<f64>,
    /// The density the renderer reports (its MIS density, what it weighs samples by).
    reported: Vec<f64>,
    /// The density the sampling has (the reported one except where Mitsuba approximates:
    /// `sampling_density_factor`).
    density: Vec<f64>,
    /// Directions evaluated, and the finest sub-grid used (points per cell and axis).
    points: usize,
    finest: usize,
}

impl Integrals {
    /// What the weights average to per cell: f·|cos| scaled by the sampling's density over
    /// the reported one (the renderer weighs by the reported density, as Mitsuba does; the
    /// same as f·|cos| where the two agree). Where they disagree (Beckmann's rational G1),
    /// the renderer's estimator is biased by that factor, as Mitsuba's is
    /// ([`Integrals::deviation_note`] says by how much).
    fn weights_expected(&self) -> Vec<f64> {
        (0..self.f.len())
            .map(|c| {
                if self.reported[c] > 0.0 {
                    self.f[c] * self.density[c] / self.reported[c]
                } else {
                    self.f[c]
                }
            })
            .collect()
    }

    /// Where the reported density is not the sampling's, by how much (the directions are
    /// tested against the sampling's), and how fine the quadrature went.
    fn deviation_note(&self) -> String {
        let (r, d): (f64, f64) = (self.reported.iter().sum(), self.density.iter().sum());
        let mut note = format!(
            "; quadrature {} points, to {1}x{1} per cell",
            self.points, self.finest
        );
        if (r - d).abs() > 1e-7 {
            note.push_str(&format!(
                "; known deviation (Mitsuba's rational Beckmann G1): the reported density \
                 integrates to {r:.4}, {:+.3} % off the sampling's, and the weights' \
                 expectation is f·cos scaled by {:.5}",
                (r / d - 1.0) * 100.0,
                d / r
            ));
        }
        note
    }
}

/// The integrals of f·|cos| and the densities over each cell of the `tb` x `pb` grid, by the
/// midpoint rule on a sub-grid refined per cell until it is accurate enough for `n` samples:
/// from `sub` / 2 and `sub` points per axis, each cell whose estimate moved by more than a
/// tenth of its standard deviation at `n` samples (the error of the finer estimate being a
/// third of the move, for a smooth integrand) is integrated again on a sub-grid twice as
/// fine, up to 8 `sub`. So is a cell whose error matters to the count of failed samples
/// (whose expectation is 1 minus the density's integral): while the errors of all cells
/// add up to more than a tenth of that count's deviation, the cells of largest error are
/// refined. A sharp lobe (a rough dielectric's transmission, concentrated near a pole of
/// the grid) needs it; smooth cells stop at `sub`.
fn integrate(
    device: &Device,
    spec: &cohort::Spec,
    p: &BsdfParams,
    pr: &cohort::runtime::GpuBuffer<Principled>,
    (tb, pb): (usize, usize),
    sub: usize,
    n: u32,
) -> Result<Integrals, ValidateError> {
    let cells = tb * pb;
    let dcos = 2.0 / tb as f64;
    let dphi = 2.0 * std::f64::consts::PI / pb as f64;
    let mut points = 0usize;
    // The midpoint rule on an s x s sub-grid of each cell of `which`: [f, reported, density].
    let mut eval = |which: &[usize], s: usize| -> Result<Vec<[f64; 3]>, ValidateError> {
        let mut dirs = Vec::with_capacity(which.len() * s * s);
        for &c in which {
            let (r, col) = (c / pb, c % pb);
            for i in 0..s {
                for j in 0..s {
                    let cos = 1.0 - (r as f64 + (i as f64 + 0.5) / s as f64) * dcos;
                    let phi = (col as f64 + (j as f64 + 0.5) / s as f64) * dphi;
                    dirs.push(polar_dir(cos as f32, phi as f32).extend(0.0));
                }
            }
        }
        points += dirs.len();
        let mut q = *p;
        q.n = dirs.len() as u32;
        let buf = device.upload(&dirs)?;
        let res = device.alloc::<Vec4>(dirs.len().max(1))?;
        eval_bsdf::launch_spec(device, spec, q.n, &q, pr, &buf, &res)?;
        let v = device.read(&res)?;
        let area = dcos * dphi / (s * s) as f64;
        Ok(which
            .iter()
            .enumerate()
            .map(|(k, _)| {
                let mut acc = [0.0f64; 3];
                for e in &v[k * s * s..(k + 1) * s * s] {
                    acc[0] += e.x.max(0.0) as f64 * area;
                    acc[1] += e.y.max(0.0) as f64 * area;
                    acc[2] += e.z.max(0.0) as f64 * area;
                }
                acc
            })
            .collect())
    };
    let nf = n.max(1) as f64;
    // A tenth of the standard deviation of a count of expectation n v, in units of v.
    let tol = |v: f64| 0.1 * (v.abs().max(1.0 / nf) / nf).sqrt();
    let all: Vec<usize> = (0..cells).collect();
    let mut s = (sub / 2).max(1);
    let mut coarse = eval(&all, s)?;
    s = sub.max(2);
    let mut fine = eval(&all, s)?;
    let mut active = all;
    let mut finest = s;
    let max_sub = 8 * sub.max(2);
    loop {
        // The error of the finer estimate, per cell and quantity.
        let err = |c: usize, k: usize| (fine[c][k] - coarse[c][k]).abs() / 3.0;
        let mut refine: Vec<usize> = active
            .iter()
            .copied()
            .filter(|&c| (0..3).any(|k| err(c, k) > tol(fine[c][k])))
            .collect();
        // The count of failed samples: 1 minus the density's integral.
        let total: f64 = fine.iter().map(|v| v[2]).sum();
        let budget = tol(1.0 - total.min(1.0));
        let mut by_err: Vec<usize> = active.clone();
        by_err.sort_by(|&a, &b| err(b, 2).total_cmp(&err(a, 2)));
        let mut sum: f64 = active.iter().map(|&c| err(c, 2)).sum();
        for &c in &by_err {
            if sum <= budget || err(c, 2) == 0.0 {
                break;
            }
            sum -= err(c, 2);
            if !refine.contains(&c) {
                refine.push(c);
            }
        }
        if refine.is_empty() || 2 * s > max_sub {
            break;
        }
        s *= 2;
        finest = s;
        let finer = eval(&refine, s)?;
        for (k, &c) in refine.iter().enumerate() {
            coarse[c] = fine[c];
            fine[c] = finer[k];
        }
        active = refine;
    }
    Ok(Integrals {
        f: fine.iter().map(|v| v[0]).collect(),
        reported: fine.iter().map(|v| v[1]).collect(),
        density: fine.iter().map(|v| v[2]).collect(),
        points,
        finest,
    })
}

/// Tests each of `cases` at each incident direction of `opts` (module documentation).
pub fn bsdf(
    device: &Device,
    cases: &[BsdfCase],
    opts: &BsdfOptions,
) -> Result<Report, ValidateError> {
    let mut report = Report::new(device_name(device), opts.alpha);
    let (tb, pb, sub) = (opts.cos_bins, opts.phi_bins, opts.sub.max(1));
    let cells = tb * pb;
    let n = opts.samples.max(1);
    let out = device.alloc::<Vec4>(n as usize)?;
    let evals = device.alloc::<Vec2>(n as usize)?;
    let eval_spec = eval_bsdf::spec(device, None);
    for case in cases {
        let pr = device.upload(&[case.principled])?;
        let sample_spec = sample_bsdf::spec(device, Some(case.level));
        // Rays per unit of the tests: one group.
        let per_draw = match case.level {
            Group::Warp => 32,
            Group::Block(b) => b as usize,
            _ => 1,
        };
        for (ii, &cos_o) in opts.incident.iter().enumerate() {
            let wo = polar_dir(cos_o, 0.3);
            let mut p = case.params;
            p.wo = wo;
            p.seed = opts.seed.wrapping_add(ii as u32 * 0x9e37);
            let quad = integrate(device, &eval_spec, &p, &pr, (tb, pb), sub, n)?;
            // The directions are tested against the density the sampling has; the weights
            // against f·|cos| (what an unbiased estimator needs).
            let pdf_int = &quad.density;
            let f_int = &quad.weights_expected();
            p.n = n;
            sample_bsdf::launch_spec(device, &sample_spec, n, &p, &pr, &out, &evals)?;
            let s = device.read(&out)?;
            let e = device.read(&evals)?;
            let mut counts = vec![0.0f64; cells + 1];
            let mut weights = MeanTest::new(cells);
            let mut indicators = MeanTest::new(cells + 1);
            let mut mismatch = 0u64;
            let mut first_mismatch = String::new();
            let mut invalid_value = None;
            let mut unit_w: Vec<(usize, f64)> = Vec::new();
            let mut unit_i: Vec<(usize, f64)> = Vec::new();
            for g0 in (0..s.len()).step_by(per_draw) {
                let g1 = (g0 + per_draw).min(s.len());
                let scale = 1.0 / (g1 - g0) as f64;
                unit_w.clear();
                unit_i.clear();
                for k in g0..g1 {
                    let (si, ei) = (s[k], e[k]);
                    if si.w == 0.0 || !si.is_finite() || si.w < 0.0 {
                        if si.w != 0.0 {
                            invalid_value.get_or_insert(format!("sample {k}: {si}"));
                        }
                        counts[cells] += 1.0;
                        unit_i.push((cells, scale));
                        continue;
                    }
                    let d = si.truncate();
                    let c = cell(d, tb, pb);
                    counts[c] += 1.0;
                    unit_w.push((c, si.w as f64 * scale));
                    unit_i.push((c, scale));
                    if case.params.kind != VALIDATE_ROUGH_PLASTIC && ei.y > 0.0 {
                        let ratio = ei.x / ei.y;
                        if (si.w - ratio).abs() > 1e-3 * ratio.abs().max(1.0) {
                            mismatch += 1;
                            if first_mismatch.is_empty() {
                                first_mismatch =
                                    format!("sample {k}: weight {} vs f/pdf {ratio}", si.w);
                            }
                        }
                    }
                }
                weights.add(&unit_w);
                if per_draw > 1 {
                    indicators.add(&unit_i);
                }
            }
            let total: f64 = pdf_int.iter().sum();
            let mut expected: Vec<f64> = pdf_int.iter().map(|p| p * n as f64).collect();
            expected.push((1.0 - total).max(0.0) * n as f64);
            // Independent samples: Pearson's test; a group's samples share their cell of
            // the unit square, so there each group is one unit of the test of means.
            let mut dirs: Outcome = if per_draw > 1 {
                let p: Vec<f64> = expected.iter().map(|e| e / n as f64).collect();
                indicators.finish(&p, opts.min_draws)
            } else {
                pearson(&counts, &expected, opts.min_expected)
            };
            // A quadrature cell that saw no density where samples fell: only a failure
            // where the density is 0 on the whole cell (the rule above).
            if total > 1.02 {
                dirs.failure = Some(format!("the density integrates to {total:.4}"));
                dirs.p_value = 0.0;
            }
            if let Some(v) = &invalid_value {
                dirs.failure = Some(format!("invalid sample, {v}"));
                dirs.p_value = 0.0;
            }
            let config = format!("cos wo={cos_o}");
            report.tests.push(TestResult {
                subject: case.name.clone(),
                config: config.clone(),
                test: "directions".into(),
                outcome: dirs,
                informational: false,
                note: format!(
                    "{n} samples, {} failed; density integrates to {total:.4}{}",
                    counts[cells],
                    quad.deviation_note()
                ),
                table: Some(Table {
                    rows: tb,
                    cols: pb,
                    observed: counts[..cells].to_vec(),
                    expected: expected[..cells].to_vec(),
                }),
            });
            // Independent samples: the variance of each cell under the hypothesis (a cell
            // that few samples happened to land in does not shrink its own variance).
            let mut w = if per_draw > 1 {
                weights.finish(f_int, opts.min_draws)
            } else {
                weights.finish_independent(f_int, opts.min_draws)
            };
            let albedo: f64 = quad.f.iter().sum();
            let mut note = format!("albedo {albedo:.4}");
            let mean_w: f64 = f_int.iter().sum();
            if (mean_w - albedo).abs() > 1e-7 {
                note.push_str(&format!(
                    "; known deviation (Mitsuba's rational Beckmann G1): tested against the \
                     weights' expectation {mean_w:.4}, {:+.3} % off the albedo",
                    (mean_w / albedo - 1.0) * 100.0
                ));
            }
            if mismatch > 0 {
                note.push_str(&format!(
                    "; {mismatch} weights differ from f/pdf, first {first_mismatch}"
                ));
                if mismatch as f64 > 1e-3 * n as f64 {
                    w.failure = Some(format!("{mismatch} weights differ from f/pdf"));
                    w.p_value = 0.0;
                }
            }
            let g = n as f64;
            report.tests.push(TestResult {
                subject: case.name.clone(),
                config,
                test: "weights".into(),
                outcome: w,
                informational: false,
                note,
                table: Some(Table {
                    rows: tb,
                    cols: pb,
                    observed: weights.mean().iter().map(|m| m * g).collect(),
                    expected: f_int.iter().map(|f| f * g).collect(),
                }),
            });
        }
    }
    if let Some(dir) = &opts.out {
        report.write_failure_images(dir)?;
    }
    Ok(report)
}
