//! The statistics of the tests: the chi-square distribution's upper tail (the regularised
//! upper incomplete gamma function), Pearson's test with pooled cells, a test of weighted
//! means, and the Sidak correction.
//!
//! **Pearson's test** (directions against a density, as Mitsuba's `chi2` and pbrt-v4's
//! `bsdfs_test` run it): independent samples counted per cell, `O_c`, against the expected
//! counts `E_c` = samples x the density integrated over the cell. Cells whose expected count
//! is below a minimum (5) are pooled into one, in increasing order of expected count, until
//! the pool reaches it; a sample in a cell of expected count exactly 0 fails the test
//! outright. X² = Σ (O − E)² / E over the cells left has, for a correct density and many
//! samples, a chi-square distribution with (cells − 1) degrees of freedom, whose upper tail
//! at X² is the p-value.
//!
//! **The test of weighted means** ([`MeanTest`]), for what Pearson's test cannot see: samples
//! that carry weights, or that are not independent (a coherent strategy's rays share their
//! group's draw). What must hold is that the weight-times-indicator of a cell has the right
//! expectation: E[w 1(d in c)] = p_c, the integral over cell c of the target (the cosine
//! density for a diffuse strategy, f·cos for a BSDF). The independent unit is one *draw*: a
//! group's draw with all the rays that used it (one sample where samples are independent).
//! Each unit gives a vector h (its rays' weights summed per cell, over its rays), so
//! E[h] = p, and the units' mean m has covariance S / G, with S the units' sample
//! covariance and G their number. The statistic is Hotelling's
//! T² = G (m − p)ᵀ S⁻¹ (m − p), which for many units is chi-square with as many degrees of
//! freedom as cells (Σ's rank: one cell is left out, since with weight 1 the cells of a unit
//! sum to 1 and S is singular; dependent cells found by the factorisation are left out too).
//! Unlike Pearson's, its variance is estimated from the samples, so weights and the
//! correlation between rays of a group are accounted for, and the correlation between
//! cells too. Cells are pooled by the expected number of *units* landing in them
//! (G p_c), with a larger minimum (10 by default), since an estimated variance needs
//! several units in a cell; on a (cos theta, phi) grid into contiguous regions
//! ([`pool_grid`]: bands of cos theta, then runs of phi), so that a coarse test remains
//! where few draws are affordable.
//!
//! **Sidak**: with T tests at overall significance α, each test must have a p-value of at
//! least 1 − (1 − α)^(1/T), so that a correct implementation fails any of them with
//! probability α.

/// ln Γ(x) for x > 0 (Lanczos, g = 7, 9 terms: relative error below 1e-15).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Γ(x) Γ(1 − x) = π / sin(πx).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

const EPS: f64 = 1e-15;
const ITMAX: usize = 10_000;

/// P(a, x) by its series (converges fast for x < a + 1).
fn gamma_p_series(a: f64, x: f64) -> f64 {
    let mut ap = a;
    let mut del = 1.0 / a;
    let mut sum = del;
    for _ in 0..ITMAX {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if del.abs() < sum.abs() * EPS {
            break;
        }
    }
    sum * (-x + a * x.ln() - ln_gamma(a)).exp()
}

/// Q(a, x) by its continued fraction, evaluated by the modified Lentz method (converges
/// fast for x > a + 1).
fn gamma_q_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    for i in 1..ITMAX {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let del = d * c;
        h *= del;
        if (del - 1.0).abs() < EPS {
            break;
        }
    }
    (-x + a * x.ln() - ln_gamma(a)).exp() * h
}

/// The regularised upper incomplete gamma function Q(a, x) = Γ(a, x) / Γ(a), for a > 0 and
/// x ≥ 0 (Numerical Recipes' `gammq`: the series below a + 1, the continued fraction above).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0, "gamma_q: a = {a} must be positive");
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    if x < a + 1.0 {
        (1.0 - gamma_p_series(a, x)).max(0.0)
    } else {
        gamma_q_fraction(a, x)
    }
}

/// The upper tail of the chi-square distribution with `dof` degrees of freedom at `x`: the
/// p-value of a statistic `x`.
pub fn chi2_p_value(x: f64, dof: usize) -> f64 {
    if dof == 0 {
        return 1.0;
    }
    if x.is_infinite() {
        return 0.0;
    }
    gamma_q(dof as f64 / 2.0, x / 2.0)
}

/// The significance one of `tests` tests must pass so that all pass with probability
/// 1 − `alpha` when all are correct (Sidak).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests.max(1) as f64)
}

/// The outcome of one statistical test.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// A failure that needs no statistic (a sample where none can be), with why.
    pub failure: Option<String>,
}

/// Which pooled cell each cell goes to: cells of expected count below `min` are pooled (in
/// increasing order of expected count, with further cells while the pool stays below
/// `min`); cells of expected count 0 go nowhere (`None`). Returns the map and the number of
/// pooled cells.
pub fn pool(expected: &[f64], min: f64) -> (Vec<Option<usize>>, usize) {
    let mut order: Vec<usize> = (0..expected.len()).filter(|&c| expected[c] > 0.0).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let mut map = vec![None; expected.len()];
    let mut pooled = 0.0;
    let mut pool_members = Vec::new();
    let mut next = 0usize;
    for &c in &order {
        if expected[c] < min || (pooled > 0.0 && pooled < min) {
            pooled += expected[c];
            pool_members.push(c);
        } else {
            map[c] = Some(next);
            next += 1;
        }
    }
    if !pool_members.is_empty() {
        if pooled < min && next > 0 {
            // Too little even with every small cell: into the smallest cell kept.
            let smallest = order.iter().find(|&&c| map[c].is_some()).copied();
            let into = smallest.and_then(|c| map[c]).unwrap_or(0);
            for c in pool_members {
                map[c] = Some(into);
            }
        } else {
            for c in pool_members {
                map[c] = Some(next);
            }
            next += 1;
        }
    }
    (map, next)
}

/// Consecutive indices of `sums` grouped until each group's sum reaches `min` (a remainder
/// joins the last group).
fn runs(sums: &[f64], min: f64) -> Vec<Vec<usize>> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut acc = 0.0;
    for (i, &v) in sums.iter().enumerate() {
        if groups.is_empty() || acc >= min {
            groups.push(Vec::new());
            acc = 0.0;
        }
        groups.last_mut().unwrap().push(i);
        acc += v;
    }
    if groups.len() > 1 && acc < min {
        let last = groups.pop().unwrap();
        groups.last_mut().unwrap().extend(last);
    }
    groups
}

/// Pooling on a `rows` x `cols` grid (row-major cells) into contiguous regions: rows are
/// grouped from the first until each group's expected count reaches `min` (a remainder joins
/// the last group), then, within each group of rows, columns the same way. Cells of expected
/// count 0 go nowhere. Returns the map and the number of regions.
pub fn pool_grid(
    expected: &[f64],
    rows: usize,
    cols: usize,
    min: f64,
) -> (Vec<Option<usize>>, usize) {
    assert_eq!(expected.len(), rows * cols);
    let row_sums: Vec<f64> = (0..rows)
        .map(|r| expected[r * cols..(r + 1) * cols].iter().sum())
        .collect();
    let row_groups = runs(&row_sums, min);
    let mut map = vec![None; expected.len()];
    let mut next = 0usize;
    for group in &row_groups {
        let col_sums: Vec<f64> = (0..cols)
            .map(|c| group.iter().map(|&r| expected[r * cols + c]).sum())
            .collect();
        for run in runs(&col_sums, min) {
            for c in run {
                for &r in group {
                    if expected[r * cols + c] > 0.0 {
                        map[r * cols + c] = Some(next);
                    }
                }
            }
            next += 1;
        }
    }
    (map, next)
}

/// Pearson's chi-square test of `observed` counts against `expected` counts (same cells),
/// cells of expected count below `min_expected` pooled. A count in a cell of expected count
/// exactly 0 is a failure.
pub fn pearson(observed: &[f64], expected: &[f64], min_expected: f64) -> Outcome {
    assert_eq!(observed.len(), expected.len());
    for (c, (&o, &e)) in observed.iter().zip(expected).enumerate() {
        if e <= 0.0 && o > 0.0 {
            return Outcome {
                statistic: f64::INFINITY,
                dof: 0,
                p_value: 0.0,
                failure: Some(format!(
                    "{o} samples in cell {c}, where the expected count is 0"
                )),
            };
        }
    }
    let (map, cells) = pool(expected, min_expected);
    let mut o_p = vec![0.0; cells];
    let mut e_p = vec![0.0; cells];
    for c in 0..observed.len() {
        if let Some(j) = map[c] {
            o_p[j] += observed[c];
            e_p[j] += expected[c];
        }
    }
    let statistic: f64 = o_p
        .iter()
        .zip(&e_p)
        .map(|(o, e)| (o - e) * (o - e) / e)
        .sum();
    let dof = cells.saturating_sub(1);
    Outcome {
        statistic,
        dof,
        p_value: chi2_p_value(statistic, dof),
        failure: None,
    }
}

/// The test of weighted means (module documentation): units (draws) are added one at a
/// time as sparse vectors of per-cell values; [`finish`](Self::finish) compares their mean
/// with the expected means.
#[derive(Clone, Debug)]
pub struct MeanTest {
    cells: usize,
    units: u64,
    sum: Vec<f64>,
    /// Σ h hᵀ, lower triangle, row-major (`c * (c + 1) / 2 + c'`, c' ≤ c).
    sum2: Vec<f64>,
    scratch: Vec<(usize, f64)>,
}

impl MeanTest {
    pub fn new(cells: usize) -> MeanTest {
        MeanTest {
            cells,
            units: 0,
            sum: vec![0.0; cells],
            sum2: vec![0.0; cells * (cells + 1) / 2],
            scratch: Vec::new(),
        }
    }

    pub fn units(&self) -> u64 {
        self.units
    }

    /// Adds one unit: `values` as (cell, value) pairs, a cell may repeat (its values add).
    pub fn add(&mut self, values: &[(usize, f64)]) {
        self.units += 1;
        self.scratch.clear();
        self.scratch.extend_from_slice(values);
        self.scratch.sort_by_key(|v| v.0);
        // Merge repeated cells.
        let mut merged: Vec<(usize, f64)> = Vec::with_capacity(self.scratch.len());
        for &(c, v) in &self.scratch {
            match merged.last_mut() {
                Some(last) if last.0 == c => last.1 += v,
                _ => merged.push((c, v)),
            }
        }
        for (i, &(c, v)) in merged.iter().enumerate() {
            self.sum[c] += v;
            let row = c * (c + 1) / 2;
            for &(c2, v2) in &merged[..=i] {
                self.sum2[row + c2] += v * v2;
            }
        }
    }

    /// The units' mean per cell.
    pub fn mean(&self) -> Vec<f64> {
        let g = self.units.max(1) as f64;
        self.sum.iter().map(|s| s / g).collect()
    }

    /// Hotelling's T² of the units' mean against `expected` (the expected mean per cell),
    /// cells pooled where fewer than `min_units` units are expected in them (`expected`
    /// x units). A nonzero mean in a cell of expected mean 0 is a failure.
    pub fn finish(&self, expected: &[f64], min_units: f64) -> Outcome {
        let counts: Vec<f64> = expected.iter().map(|e| e * self.units as f64).collect();
        let (map, pooled) = pool(&counts, min_units);
        self.finish_pooled(expected, &map, pooled)
    }

    /// [`finish`](Self::finish) with the cells pooled as `map` says (`pooled` regions).
    pub fn finish_pooled(&self, expected: &[f64], map: &[Option<usize>], pooled: usize) -> Outcome {
        self.finish_with(expected, map, pooled, false)
    }

    /// [`finish`](Self::finish) for units of one sample each (independent samples, every
    /// unit's values in one cell at most), with the covariance of the mean taken under the
    /// hypothesis rather than from the units: Var(h_c) = q_c − p_c², Cov(h_c, h_c') =
    /// −p_c p_c', where q_c = E[w² 1(d in c)] = p_c E[w² | c] / E[w | c], the weight's
    /// moments in the cell estimated from the samples that landed there (from all samples
    /// where none did). The units' own covariance estimates the variance of a cell from how
    /// many samples landed in it: where far fewer land than expected (a cell of 11 expected
    /// with 1 sample, which happens with probability 2e-4), it is far too small, and the
    /// statistic explodes (the p-value 1e-12); this one stays a Pearson-like test of counts,
    /// scaled by the weights.
    pub fn finish_independent(&self, expected: &[f64], min_units: f64) -> Outcome {
        let counts: Vec<f64> = expected.iter().map(|e| e * self.units as f64).collect();
        let (map, pooled) = pool(&counts, min_units);
        self.finish_with(expected, &map, pooled, true)
    }

    fn finish_with(
        &self,
        expected: &[f64],
        map: &[Option<usize>],
        pooled: usize,
        independent: bool,
    ) -> Outcome {
        assert_eq!(expected.len(), self.cells);
        let g = self.units as f64;
        let mean = self.mean();
        for c in 0..self.cells {
            if expected[c] <= 0.0 && self.sum[c] != 0.0 {
                return Outcome {
                    statistic: f64::INFINITY,
                    dof: 0,
                    p_value: 0.0,
                    failure: Some(format!(
                        "weight {:.3e} in cell {c}, where the expected value is 0",
                        mean[c]
                    )),
                };
            }
        }
        if self.units < 2 {
            return Outcome {
                statistic: 0.0,
                dof: 0,
                p_value: 1.0,
                failure: Some("fewer than 2 draws".into()),
            };
        }
        // Leave out one cell (the last pooled one): with constant unit sums S is singular.
        let k = pooled.saturating_sub(1);
        if k == 0 {
            return Outcome {
                statistic: 0.0,
                dof: 0,
                p_value: 1.0,
                failure: Some(format!(
                    "{} draws leave fewer than 2 cells after pooling: more samples needed",
                    self.units
                )),
            };
        }
        let mut x = vec![0.0; k];
        let mut s1 = vec![0.0; k];
        let mut cov = vec![0.0; k * k];
        for c in 0..self.cells {
            let Some(j) = map[c].filter(|&j| j < k) else {
                continue;
            };
            x[j] += mean[c] - expected[c];
            s1[j] += self.sum[c];
            let row = c * (c + 1) / 2;
            for (c2, m2) in map.iter().enumerate().take(c + 1) {
                let Some(j2) = m2.filter(|&j2| j2 < k) else {
                    continue;
                };
                let v = self.sum2[row + c2];
                cov[j * k + j2] += v;
                if c2 != c {
                    cov[j2 * k + j] += v;
                }
            }
        }
        if independent {
            // Under the hypothesis: (diag(q) − p pᵀ) / G, pooled.
            let diag = |c: usize| self.sum2[c * (c + 1) / 2 + c];
            let (all_w, all_w2) =
                (0..self.cells).fold((0.0, 0.0), |(a, b), c| (a + self.sum[c], b + diag(c)));
            let fallback = if all_w > 0.0 { all_w2 / all_w } else { 1.0 };
            let mut q = vec![0.0; k];
            let mut p = vec![0.0; k];
            for c in 0..self.cells {
                let Some(j) = map[c].filter(|&j| j < k) else {
                    continue;
                };
                let ratio = if self.sum[c] > 0.0 {
                    diag(c) / self.sum[c]
                } else {
                    fallback
                };
                q[j] += expected[c] * ratio;
                p[j] += expected[c];
            }
            for a in 0..k {
                for b in 0..k {
                    let d = if a == b { q[a] } else { 0.0 };
                    cov[a * k + b] = (d - p[a] * p[b]) / g;
                }
            }
        } else {
            // Covariance of the mean: (Σ h hᵀ − G m mᵀ) / (G − 1) / G.
            for a in 0..k {
                for b in 0..k {
                    let m = s1[a] * s1[b] / g;
                    cov[a * k + b] = (cov[a * k + b] - m) / (g - 1.0) / g;
                }
            }
        }
        let (statistic, dof, failure) = mahalanobis(&cov, &x, k);
        Outcome {
            statistic,
            dof,
            p_value: if failure.is_some() {
                0.0
            } else {
                chi2_p_value(statistic, dof)
            },
            failure,
        }
    }
}

/// xᵀ A⁻¹ x for the symmetric positive semi-definite `a` (k x k) by a Cholesky factorisation
/// that leaves out dimensions dependent on earlier ones (a pivot below 1e-10 of the
/// diagonal); returns (the form, the rank, a failure where a dimension without variance has
/// a deviation).
fn mahalanobis(a: &[f64], x: &[f64], k: usize) -> (f64, usize, Option<String>) {
    let mut l = vec![0.0; k * k];
    let mut kept = vec![false; k];
    let mut y = vec![0.0; k];
    let mut form = 0.0;
    let mut rank = 0;
    for j in 0..k {
        let mut d = a[j * k + j];
        for m in 0..j {
            if kept[m] {
                d -= l[j * k + m] * l[j * k + m];
            }
        }
        // The deviation's component along this dimension, after the earlier ones.
        let mut r = x[j];
        for m in 0..j {
            if kept[m] {
                r -= l[j * k + m] * y[m];
            }
        }
        let diag = a[j * k + j];
        if diag <= 0.0 || d <= 1e-10 * diag {
            if r.abs() > 1e-9 * (x[j].abs() + 1e-12) && diag <= 0.0 && x[j].abs() > 1e-12 {
                return (
                    f64::INFINITY,
                    rank,
                    Some(format!(
                        "pooled cell {j} deviates by {:.3e} with no variance",
                        x[j]
                    )),
                );
            }
            continue;
        }
        let ljj = d.sqrt();
        l[j * k + j] = ljj;
        for i in j + 1..k {
            let mut s = a[i * k + j];
            for m in 0..j {
                if kept[m] {
                    s -= l[i * k + m] * l[j * k + m];
                }
            }
            l[i * k + j] = s / ljj;
        }
        kept[j] = true;
        y[j] = r / ljj;
        form += y[j] * y[j];
        rank += 1;
    }
    (form, rank, None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) {
        assert!(
            (a - b).abs() <= rel * b.abs(),
            "{a} vs {b} (relative {})",
            (a - b).abs() / b.abs()
        );
    }

    #[test]
    fn ln_gamma_known_values() {
        close(ln_gamma(1.0).exp(), 1.0, 1e-14);
        close(ln_gamma(5.0).exp(), 24.0, 1e-13);
        close(ln_gamma(0.5).exp(), std::f64::consts::PI.sqrt(), 1e-13);
        close(ln_gamma(100.0), 359.134_205_369_575_4, 1e-13);
    }

    #[test]
    fn gamma_q_known_values() {
        // Q(1, x) = e^-x; Q(1/2, x) = erfc(sqrt x).
        close(gamma_q(1.0, 2.0), (-2.0f64).exp(), 1e-13);
        close(gamma_q(1.0, 0.1), (-0.1f64).exp(), 1e-13);
        close(gamma_q(0.5, 1.0), 0.157_299_207_050_285_1, 1e-12);
        close(gamma_q(0.5, 9.0), 2.209_049_699_858_544e-5, 1e-10);
        // Q(n, x) = e^-x Σ_{k<n} x^k / k! for integer n.
        let q3 = (-4.0f64).exp() * (1.0 + 4.0 + 8.0);
        close(gamma_q(3.0, 4.0), q3, 1e-13);
        assert_eq!(gamma_q(2.0, 0.0), 1.0);
    }

    #[test]
    fn chi2_p_values_match_tables() {
        // Upper critical values of the chi-square distribution (NIST handbook, 1.3.6.7.4),
        // rounded to 3 decimals there.
        close(chi2_p_value(3.841, 1), 0.05, 1e-3);
        close(chi2_p_value(18.307, 10), 0.05, 1e-3);
        close(chi2_p_value(23.209, 10), 0.01, 1e-3);
        close(chi2_p_value(124.342, 100), 0.05, 1e-3);
        close(chi2_p_value(135.807, 100), 0.01, 1e-3);
        // Far in the tail (the continued fraction): Q(n, x) = e^-x Σ_{k<n} x^k / k!.
        close(gamma_q(1.0, 50.0), (-50.0f64).exp(), 1e-12);
        let mut term = 1.0;
        let mut sum = 1.0;
        for k in 1..10 {
            term *= 30.0 / k as f64;
            sum += term;
        }
        close(gamma_q(10.0, 30.0), (-30.0f64).exp() * sum, 1e-12);
        assert_eq!(chi2_p_value(5.0, 0), 1.0);
    }

    #[test]
    fn sidak_of_one_is_alpha() {
        close(sidak(0.01, 1), 0.01, 1e-12);
        close(sidak(0.01, 100), 1.005_02e-4, 1e-4);
    }

    #[test]
    fn pooling_keeps_every_pooled_cell_above_the_minimum() {
        let e = [1.0, 2.0, 3.0, 10.0, 0.0, 40.0];
        let (map, cells) = pool(&e, 5.0);
        assert_eq!(map[4], None);
        assert_eq!(cells, 3);
        let mut sums = vec![0.0; cells];
        for c in 0..e.len() {
            if let Some(j) = map[c] {
                sums[j] += e[c];
            }
        }
        assert!(sums.iter().all(|&s| s >= 5.0), "{sums:?}");
    }

    #[test]
    fn pearson_rejects_a_sample_where_none_is_expected() {
        let o = pearson(&[10.0, 1.0], &[11.0, 0.0], 5.0);
        assert!(o.failure.is_some());
    }

    #[test]
    fn mean_test_of_independent_samples_is_pearson_like() {
        // Four cells of probability 1/4, samples spread exactly evenly: T² = 0.
        let mut t = MeanTest::new(4);
        for i in 0..400 {
            t.add(&[(i % 4, 1.0)]);
        }
        let o = t.finish(&[0.25; 4], 5.0);
        assert_eq!(o.dof, 3);
        assert!(o.statistic < 1e-9, "{o:?}");
        // A cycle of 12 samples: right against its own frequencies, wrong against others.
        let mut t = MeanTest::new(4);
        for i in 0..3996 {
            let c = [0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 3, 3][i % 12];
            t.add(&[(c, 1.0)]);
        }
        let o = t.finish(&[5.0 / 12.0, 0.25, 2.0 / 12.0, 2.0 / 12.0], 5.0);
        assert!(o.p_value > 0.1, "{o:?}");
        let o = t.finish(&[0.3, 0.3, 0.2, 0.2], 5.0);
        assert!(o.p_value < 1e-6, "{o:?}");
    }
}
