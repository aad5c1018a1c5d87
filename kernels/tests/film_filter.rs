//! The camera's reconstruction filter as `extend::filter_offset` samples it: for every Mitsuba
//! filter and every way the film's edge can cut it, the weighted mean of a function of the
//! offset over the sampled offsets equals the filter-weighted mean of that function, computed
//! directly from Mitsuba's tabulated filter (`FilmFilter::eval_discretized`). That is what
//! makes a pixel's mean Mitsuba's splatted pixel.

use cohort_kernels::extend::filter_offset;
use cohort_scenes::FilmFilter;

/// A named function of the offset.
type Named = (&'static str, fn(f64) -> f64);

/// Test functions of the offset: a constant, odd and even moments, a step (an edge in the
/// image) and a narrow bump.
fn functions() -> Vec<Named> {
    vec![
        ("1", |_| 1.0),
        ("t", |t| t),
        ("t^2", |t| t * t),
        ("step at 0.3", |t| if t > 0.3 { 1.0 } else { 0.0 }),
        ("bump at -0.7", |t| (-(t + 0.7) * (t + 0.7) * 20.0).exp()),
    ]
}

/// `integral f g / integral f` over `[lo, hi]` by the midpoint rule on a fine grid.
fn filtered_mean(filter: &FilmFilter, lo: f32, hi: f32, g: fn(f64) -> f64) -> f64 {
    let n = 400_000;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..n {
        let t = lo as f64 + (hi - lo) as f64 * (i as f64 + 0.5) / n as f64;
        let f = filter.eval_discretized(t as f32) as f64;
        num += f * g(t);
        den += f;
    }
    num / den
}

#[test]
fn sampled_offsets_give_the_filtered_mean() {
    let filters = [
        FilmFilter::gaussian(0.5),
        FilmFilter::gaussian(0.8),
        FilmFilter::tent(1.0),
        FilmFilter::tent(1.25),
        FilmFilter::mitchell(1.0 / 3.0, 1.0 / 3.0),
        FilmFilter::catmull_rom(),
        FilmFilter::lanczos(3),
    ];
    for filter in filters {
        let table = filter.table();
        let r = filter.radius;
        let positive = filter.values.iter().all(|&v| v >= 0.0);
        // The whole filter, and the film's edge half a pixel and 1.5 pixels away on either side.
        for (lo, hi) in [(-r, r), (-0.5, r), (-1.5, r), (-r, 0.5), (-0.5, 1.5)] {
            let (lo, hi) = (lo.max(-r), hi.min(r));
            // Stratified u: the sums below are quadratures of the sampling map.
            let n = 200_000;
            let samples: Vec<(f64, f64)> = (0..n)
                .map(|i| {
                    let u = (i as f32 + 0.5) / n as f32;
                    let s = filter_offset(&table, r, lo, hi, u);
                    assert!(
                        s.x >= lo && s.x <= hi,
                        "{filter:?}: offset {} outside [{lo}, {hi}]",
                        s.x
                    );
                    if positive {
                        assert_eq!(s.y, 1.0, "{:?}: a positive filter weighs 1", filter.kind);
                    }
                    (s.x as f64, s.y as f64)
                })
                .collect();
            for (name, g) in functions() {
                let ours = samples.iter().map(|&(t, w)| w * g(t)).sum::<f64>() / n as f64;
                let exact = filtered_mean(&filter, lo, hi, g);
                assert!(
                    (ours - exact).abs() < 2e-3 * (1.0 + exact.abs()),
                    "{:?} on [{lo}, {hi}], g = {name}: sampled {ours}, filtered {exact}",
                    filter.kind
                );
            }
        }
    }
}

/// The sampled density follows the filter's steps: with the gaussian, offsets near the centre
/// are far more frequent than near the radius, in the ratio of the filter's values.
#[test]
fn offsets_follow_the_filter_steps() {
    let filter = FilmFilter::gaussian(0.5);
    let table = filter.table();
    let n = 100_000;
    let (mut centre, mut edge) = (0, 0);
    let step = filter.radius / 31.0;
    for i in 0..n {
        let t = filter_offset(&table, 2.0, -2.0, 2.0, (i as f32 + 0.5) / n as f32).x;
        if t >= 0.0 && t < step {
            centre += 1;
        }
        if t >= 25.0 * step && t < 26.0 * step {
            edge += 1;
        }
    }
    let expected = filter.values[0] / filter.values[25];
    let ratio = centre as f32 / edge as f32;
    assert!(
        (ratio / expected - 1.0).abs() < 0.05,
        "{ratio} vs {expected}"
    );
}
