//! The test of a [`DiffuseSampler`]: its own kernel ([`sample_sampler`]) draws directions
//! for many rays about a set of normals, over many group draws, at each group level asked
//! for; the host histograms them on a (cos theta, phi) grid in each normal's frame.
//!
//! - **marginal** (counted): the rays' weights per cell, each draw's rays one unit, against
//!   the cosine density integrated over the cell (analytic), by the test of weighted means
//!   (`stats`). This is what unbiasedness needs: E[w 1(d in c)] = ∫_c cos/π for every cell.
//!   A direction below the horizon, not of unit length, or a weight that is negative or not
//!   finite fails it outright.
//! - **within draw** (for information): each of a few draws' rays, unweighted, against the
//!   cosine density by Pearson's test, and how much of the cosine mass the cells they reach
//!   hold. A coherent strategy is expected to fail it (its draw's rays share a patch).
//! - **grouped** (counted; a strategy with `GROUP_PARAMS`): on the host, `sample_grouped`
//!   given `group_params` returns `sample`'s bits for every group draw, normal and random
//!   pair tried. The renderer calls either, so a strategy whose two forms disagree would
//!   render differently by backend and group level.

use std::path::PathBuf;

use cohort::runtime::Device;
use cohort::Group;
use cohort_kernels::rng::hash;
use cohort_kernels::sampling::{frame, DiffuseSampler};
use cohort_kernels::validate::{sample_sampler, SamplerParams};
use glam::{Vec3, Vec4};

use super::report::{Report, Table, TestResult};
use super::stats::{pearson, pool_grid, MeanTest, Outcome};
use super::{device_name, ValidateError};

/// What [`sampler`] tests, and how hard.
#[derive(Clone, Debug)]
pub struct SamplerOptions {
    /// The name in the report (the type's name when `None`).
    pub name: Option<String>,
    /// The group levels to test.
    pub levels: Vec<Group>,
    /// Rays per level (about: a multiple of the rays per draw).
    pub samples: u32,
    /// Draws at grid level (one launch each; `samples / grid_draws` rays per draw).
    pub grid_draws: u32,
    /// N of the N x 4N patches.
    pub patches_n: u32,
    /// The normals (ray `i` samples about normal `i % len`); each is tested on its own.
    pub normals: Vec<Vec3>,
    /// Bands of cos theta in [0, 1] and sectors of phi of the histogram.
    pub cos_bins: usize,
    pub phi_bins: usize,
    pub seed: u32,
    /// Overall significance (Sidak-corrected over the report's tests).
    pub alpha: f64,
    /// Pooling: the least expected number of draws landing in a cell of the marginal test.
    pub min_draws: f64,
    /// Draws looked at one by one for the within-draw information.
    pub info_draws: usize,
    /// Where to write the observed and expected tables of failed tests (PNG).
    pub out: Option<PathBuf>,
}

impl Default for SamplerOptions {
    fn default() -> Self {
        SamplerOptions {
            name: None,
            levels: vec![Group::Thread, Group::Warp, Group::Block(256), Group::Grid],
            samples: 1 << 18,
            grid_draws: 512,
            patches_n: 16,
            normals: vec![
                Vec3::Z,
                Vec3::new(1.0, 2.0, 3.0).normalize(),
                Vec3::new(-0.3, 0.9, -0.2).normalize(),
            ],
            cos_bins: 8,
            phi_bins: 16,
            seed: 1,
            alpha: 0.01,
            min_draws: 10.0,
            info_draws: 32,
            out: None,
        }
    }
}

/// The level's name as the renderer's algorithms name it.
pub fn level_name(g: Group) -> String {
    match g {
        Group::Thread => "thread".into(),
        g => g.label(),
    }
}

/// The cell of local direction `l` (z up) on the grid, `None` below the horizon.
fn cell(l: Vec3, cos_bins: usize, phi_bins: usize) -> Option<usize> {
    if l.z.is_nan() || l.z < 0.0 {
        return None;
    }
    let row = (((1.0 - l.z as f64) * cos_bins as f64) as usize).min(cos_bins - 1);
    let mut phi = (l.y as f64).atan2(l.x as f64);
    if phi < 0.0 {
        phi += 2.0 * std::f64::consts::PI;
    }
    let col = ((phi / (2.0 * std::f64::consts::PI) * phi_bins as f64) as usize).min(phi_bins - 1);
    Some(row * phi_bins + col)
}

/// The cosine density integrated over each cell.
pub fn cosine_cells(cos_bins: usize, phi_bins: usize) -> Vec<f64> {
    let mut p = Vec::with_capacity(cos_bins * phi_bins);
    for r in 0..cos_bins {
        let hi = 1.0 - r as f64 / cos_bins as f64;
        let lo = 1.0 - (r + 1) as f64 / cos_bins as f64;
        for _ in 0..phi_bins {
            p.push((hi * hi - lo * lo) / phi_bins as f64);
        }
    }
    p
}

/// Tests strategy `S` on `device` (module documentation); one marginal test per level and
/// normal, one informational row per level above thread.
pub fn sampler<S: DiffuseSampler + 'static>(
    device: &Device,
    opts: &SamplerOptions,
) -> Result<Report, ValidateError> {
    let name = opts.name.clone().unwrap_or_else(|| {
        let full = std::any::type_name::<S>();
        full.rsplit("::").next().unwrap_or(full).to_string()
    });
    if opts.normals.is_empty() || opts.cos_bins == 0 || opts.phi_bins == 0 {
        return Err(ValidateError::Options(
            "at least one normal and one cell".into(),
        ));
    }
    let mut report = Report::new(device_name(device), opts.alpha);
    for &level in &opts.levels {
        level_tests::<S>(device, opts, &name, level, &mut report)?;
    }
    if S::GROUP_PARAMS {
        report.tests.push(grouped_test::<S>(opts, &name));
    }
    if let Some(dir) = &opts.out {
        report.write_failure_images(dir)?;
    }
    Ok(report)
}

fn level_tests<S: DiffuseSampler + 'static>(
    device: &Device,
    opts: &SamplerOptions,
    name: &str,
    level: Group,
    report: &mut Report,
) -> Result<(), ValidateError> {
    let k = opts.normals.len();
    let (tb, pb) = (opts.cos_bins, opts.phi_bins);
    let cells = tb * pb;
    let expected = cosine_cells(tb, pb);
    // Rays per draw and the launches: (rays, draws) per launch.
    let per_draw = match level {
        Group::Thread => 1,
        Group::Warp => 32,
        Group::Block(n) => n,
        Group::Grid => (opts.samples / opts.grid_draws.max(1)).max(1),
    };
    let launches: Vec<u32> = match level {
        Group::Grid => vec![per_draw; opts.grid_draws.max(1) as usize],
        _ => {
            let unit = per_draw.max(64);
            let total = (opts.samples / unit).max(1) * unit;
            let chunk = ((1u32 << 18) / unit).max(1) * unit;
            let mut v = Vec::new();
            let mut left = total;
            while left > 0 {
                let n = left.min(chunk);
                v.push(n);
                left -= n;
            }
            v
        }
    };
    let frames: Vec<glam::Mat3> = opts.normals.iter().map(|&n| frame(n).transpose()).collect();
    let normals: Vec<Vec4> = opts.normals.iter().map(|n| n.extend(0.0)).collect();
    let normals_buf = device.upload(&normals)?;
    let spec = sample_sampler::spec(device, Some(level));
    let max_n = *launches.iter().max().unwrap_or(&1);
    let out = device.alloc::<Vec4>(max_n as usize)?;
    let mut tests: Vec<MeanTest> = (0..k).map(|_| MeanTest::new(cells)).collect();
    let mut bad: Vec<(u64, Option<String>)> = vec![(0, None); k];
    let mut info: Vec<(f64, usize, f64, f64)> = Vec::new();
    let mut unit: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    for (draw, &n) in launches.iter().enumerate() {
        let params = SamplerParams {
            n,
            seed: opts.seed,
            draw: draw as u32,
            patches_n: opts.patches_n,
            normals_n: k as u32,
            ..Default::default()
        };
        sample_sampler::launch_spec::<S>(device, &spec, n, &params, &normals_buf, &out)?;
        let got = device.read(&out)?;
        for g0 in (0..n).step_by(per_draw as usize) {
            let g1 = (g0 + per_draw).min(n);
            for u in unit.iter_mut() {
                u.clear();
            }
            let mut hist = vec![0.0f64; cells];
            for i in g0..g1 {
                let kk = (i as usize) % k;
                let s = got[i as usize];
                let d = s.truncate();
                let l = frames[kk] * d;
                let len = d.length();
                let problem = if !s.is_finite() {
                    Some(format!("ray {i}: not finite: {s}"))
                } else if (len - 1.0).abs() > 1e-3 {
                    Some(format!("ray {i}: direction of length {len}"))
                } else if s.w < 0.0 {
                    Some(format!("ray {i}: negative weight {}", s.w))
                } else if l.z < -1e-6 {
                    Some(format!("ray {i}: below the horizon (cos {})", l.z))
                } else {
                    None
                };
                if let Some(p) = problem {
                    bad[kk].0 += 1;
                    bad[kk].1.get_or_insert(p);
                    continue;
                }
                let c = cell(Vec3::new(l.x, l.y, l.z.max(0.0)), tb, pb).unwrap_or(0);
                unit[kk].push((c, s.w as f64));
                hist[c] += 1.0;
            }
            for (kk, u) in unit.iter_mut().enumerate() {
                // Rays of normal kk in this draw.
                let of_k = (g0..g1).filter(|i| (*i as usize) % k == kk).count();
                if of_k == 0 {
                    continue;
                }
                for v in u.iter_mut() {
                    v.1 /= of_k as f64;
                }
                tests[kk].add(u);
            }
            if per_draw > 1 && info.len() < opts.info_draws && g1 - g0 == per_draw {
                let m = (g1 - g0) as f64;
                let e: Vec<f64> = expected.iter().map(|p| p * m).collect();
                let o = pearson(&hist, &e, 5.0);
                let mass: f64 = (0..cells)
                    .filter(|&c| hist[c] > 0.0)
                    .map(|c| expected[c])
                    .sum();
                info.push((o.statistic, o.dof, o.p_value, mass));
            }
        }
    }
    let lname = level_name(level);
    for (kk, t) in tests.iter().enumerate() {
        let n = opts.normals[kk];
        let counts: Vec<f64> = expected.iter().map(|p| p * t.units() as f64).collect();
        let (map, pooled) = pool_grid(&counts, tb, pb, opts.min_draws);
        let mut outcome = t.finish_pooled(&expected, &map, pooled);
        if bad[kk].0 > 0 {
            outcome.failure = Some(format!(
                "{} invalid samples, first: {}",
                bad[kk].0,
                bad[kk].1.clone().unwrap_or_default()
            ));
            outcome.p_value = 0.0;
        }
        let g = t.units() as f64;
        let mean = t.mean();
        report.tests.push(TestResult {
            subject: name.to_string(),
            config: format!("{lname}, n=({:.2},{:.2},{:.2})", n.x, n.y, n.z),
            test: "marginal".into(),
            outcome,
            informational: false,
            note: format!("{} draws x {} rays", t.units(), per_draw),
            table: Some(Table {
                rows: tb,
                cols: pb,
                observed: mean.iter().map(|m| m * g).collect(),
                expected: expected.iter().map(|p| p * g).collect(),
            }),
        });
    }
    if !info.is_empty() {
        let mut ps: Vec<f64> = info.iter().map(|i| i.2).collect();
        ps.sort_by(f64::total_cmp);
        let mut xs: Vec<f64> = info.iter().map(|i| i.0).collect();
        xs.sort_by(f64::total_cmp);
        let mass = info.iter().map(|i| i.3).sum::<f64>() / info.len() as f64;
        report.tests.push(TestResult {
            subject: name.to_string(),
            config: lname,
            test: "within draw".into(),
            outcome: Outcome {
                statistic: xs[xs.len() / 2],
                dof: info[0].1,
                p_value: ps[ps.len() / 2],
                failure: None,
            },
            informational: true,
            note: format!(
                "median of {} draws of {per_draw} rays; their cells hold {:.1} % of the cosine mass",
                info.len(),
                100.0 * mass
            ),
            table: None,
        });
    }
    Ok(())
}

/// Group draws, and random pairs per side of a grid, that the grouped test tries.
const GROUPED_DRAWS: u32 = 256;
const GROUPED_GRID: u32 = 16;

/// The grouped test (module documentation), on the host: the first disagreement fails it.
fn grouped_test<S: DiffuseSampler>(opts: &SamplerOptions, name: &str) -> TestResult {
    let pn = opts.patches_n;
    let mut tried = 0u64;
    let mut failure = None;
    let cell = |c: u32| (c as f32 + 0.5) / GROUPED_GRID as f32;
    'draws: for draw in 0..GROUPED_DRAWS {
        let value = S::group_value(hash(opts.seed ^ hash(draw)), pn);
        let params = S::group_params(value, pn);
        for &n in &opts.normals {
            for k in 0..GROUPED_GRID * GROUPED_GRID {
                let u = glam::Vec2::new(cell(k % GROUPED_GRID), cell(k / GROUPED_GRID));
                let plain = S::sample(n, u, value, pn);
                let grouped = S::sample_grouped(n, u, value, params, pn);
                tried += 1;
                if plain.to_array().map(f32::to_bits) != grouped.to_array().map(f32::to_bits) {
                    failure = Some(format!(
                        "group value {value}, normal {n}, u {u}: sample gives {plain}, \
                         sample_grouped {grouped}"
                    ));
                    break 'draws;
                }
            }
        }
    }
    TestResult {
        subject: name.to_string(),
        config: "host".into(),
        test: "grouped".into(),
        outcome: Outcome {
            statistic: 0.0,
            dof: 0,
            p_value: if failure.is_some() { 0.0 } else { 1.0 },
            failure,
        },
        informational: false,
        note: format!("{tried} samples compared bit for bit"),
        table: None,
    }
}
