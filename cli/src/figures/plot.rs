//! The plots: per scene, Fig. 4 (paths per pixel vs N), Fig. 5 (RMS % vs N) and Fig. 7
//! (RMS % vs N with D > 1), one panel per column, as SVG and PNG, drawn from the rows of
//! a run or of merged shards.

use std::path::{Path, PathBuf};

use cohort_render::output;
use plotters::backend::BitMapBackend;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::plan::{Column, Plan};
use super::text_bitmap::TextBitmap;

/// What the plots need of a row of figures.csv: taken from a measured row, or read back
/// from a shard's CSV by the merge.
#[derive(Clone)]
pub struct PlotRow {
    pub scene: String,
    pub config: String,
    /// `None` for `normal`, which does not depend on N.
    pub n: Option<u32>,
    /// N of the group the point was measured in.
    pub group_n: u32,
    pub column: Column,
    pub interleave: u32,
    pub paths_per_pixel: f64,
    pub rms_percent: f64,
}

/// Line colours of the coherent configurations, in the order given (tab10).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(214, 39, 40),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

struct Panel {
    title: &'static str,
    /// (N of the group, value), sorted by N: `normal` is measured in every group.
    normal: Vec<(f64, f64)>,
    curves: Vec<Curve>,
}

struct Curve {
    name: String,
    color: RGBColor,
    /// (N, value), sorted by N.
    points: Vec<(f64, f64)>,
}

struct Figure {
    title: String,
    y_label: &'static str,
    /// Legend corner: where curves are unlikely to be (paths grow with N, RMS falls).
    legend: SeriesLabelPosition,
    y_from_zero: bool,
    panels: Vec<Panel>,
}

/// Font sizes: larger in the PNG, whose 8x8 bitmap glyphs are wider than the layout
/// estimate of small sizes.
struct Fonts {
    title: u32,
    caption: u32,
    desc: u32,
    label: u32,
}
const SVG_FONTS: Fonts = Fonts {
    title: 24,
    caption: 17,
    desc: 15,
    label: 13,
};
const PNG_FONTS: Fonts = Fonts {
    title: 36,
    caption: 36,
    desc: 18,
    label: 18,
};
/// Size of one panel (one column of the figure).
const PANEL_SIZE: (u32, u32) = (650, 650);

pub fn write_scene_figures(
    plan: &Plan,
    scene: &str,
    rows: &[PlotRow],
) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    let mut figs: Vec<(String, Figure)> = Vec::new();
    let fig =
        |d: u32, metric: fn(&PlotRow) -> f64, title: String, y_label, legend, y_from_zero| Figure {
            title,
            y_label,
            legend,
            y_from_zero,
            panels: plan
                .columns
                .iter()
                .map(|col| {
                    let sel =
                        |r: &&PlotRow| r.scene == scene && r.interleave == d && r.column == *col;
                    let mut normal: Vec<(f64, f64)> = rows
                        .iter()
                        .filter(sel)
                        .filter(|r| r.n.is_none())
                        .map(|r| (r.group_n as f64, metric(r)))
                        .collect();
                    normal.sort_by(|a, b| a.0.total_cmp(&b.0));
                    let curves = plan
                        .configs_of(col)
                        .iter()
                        .enumerate()
                        .map(|(i, alg)| {
                            let mut pts: Vec<(f64, f64)> = rows
                                .iter()
                                .filter(sel)
                                .filter(|r| r.config == alg.name())
                                .filter_map(|r| Some((r.n? as f64, metric(r))))
                                .collect();
                            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                            Curve {
                                name: format!("{}{}", alg.name(), col.suffix),
                                color: PALETTE[i % PALETTE.len()],
                                points: pts,
                            }
                        })
                        .collect();
                    Panel {
                        title: col.title,
                        normal,
                        curves,
                    }
                })
                .collect(),
        };
    let budget = format!(
        "{:.3} s kernel time per point, round-robin per N",
        plan.time.as_secs_f64()
    );
    figs.push((
        format!("fig4_{scene}"),
        fig(
            1,
            |r| r.paths_per_pixel,
            format!("Fig. 4, {scene}: completed paths per pixel vs N ({budget})"),
            "paths per pixel",
            SeriesLabelPosition::UpperLeft,
            true,
        ),
    ));
    figs.push((
        format!("fig5_{scene}"),
        fig(
            1,
            |r| r.rms_percent,
            format!("Fig. 5, {scene}: RMS error vs N ({budget})"),
            "RMS error vs reference (%)",
            SeriesLabelPosition::UpperRight,
            false,
        ),
    ));
    for &d in plan.interleaves.iter().filter(|&&d| d > 1) {
        figs.push((
            format!("fig7_{scene}_d{d}"),
            fig(
                d,
                |r| r.rms_percent,
                format!("Fig. 7, {scene}: RMS error vs N, interleaved D = {d} ({budget})"),
                "RMS error vs reference (%)",
                SeriesLabelPosition::UpperRight,
                false,
            ),
        ));
    }
    for (stem, fig) in &figs {
        let x = x_range(&plan.ns);
        let mut ticks: Vec<f64> = plan.ns.iter().map(|&n| n as f64).collect();
        ticks.sort_by(f64::total_cmp);
        let y = y_range(fig);
        let size = (PANEL_SIZE.0 * fig.panels.len().max(1) as u32, PANEL_SIZE.1);
        let svg_path = plan.out_dir.join(format!("{stem}.svg"));
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
            draw_figure(root, fig, x, &ticks, y, &SVG_FONTS)
                .map_err(|e| format!("cannot draw {}: {e}", svg_path.display()))?;
        }
        output::write_text(&svg_path, &svg).map_err(|e| e.to_string())?;
        written.push(svg_path);

        let png_path = plan.out_dir.join(format!("{stem}.png"));
        let (w, h) = size;
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let root = TextBitmap(BitMapBackend::with_buffer(&mut buf, size)).into_drawing_area();
            draw_figure(root, fig, x, &ticks, y, &PNG_FONTS)
                .map_err(|e| format!("cannot draw {}: {e}", png_path.display()))?;
        }
        write_png_rgb(&png_path, size, &buf)?;
        written.push(png_path);
    }
    Ok(written)
}

fn x_range(ns: &[u32]) -> (f64, f64) {
    let lo = ns.iter().copied().min().unwrap_or(1) as f64;
    let hi = ns.iter().copied().max().unwrap_or(1000) as f64;
    if hi / lo < 2.0 {
        (lo / 1.5, hi * 1.5)
    } else {
        (lo / 1.1, hi * 1.1)
    }
}

fn y_range(fig: &Figure) -> (f64, f64) {
    let values = fig
        .panels
        .iter()
        .flat_map(|p| {
            p.normal
                .iter()
                .chain(p.curves.iter().flat_map(|c| c.points.iter()))
                .map(|v| v.1)
        })
        .filter(|v| v.is_finite());
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let lo = if fig.y_from_zero { 0.0 } else { lo };
    let pad = ((hi - lo) * 0.08).max(hi.abs() * 0.02).max(1e-6);
    ((lo - pad).max(0.0), hi + pad)
}

/// Draws the three panels; the x axis is logarithmic with a tick at every N of the sweep.
fn draw_figure<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    fig: &Figure,
    (x0, x1): (f64, f64),
    ticks: &[f64],
    (y0, y1): (f64, f64),
    fonts: &Fonts,
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    // Enough decimals to tell the y ticks apart: 1 for a span of ~10, 0 from ~100.
    let decimals = (1 - (y1 - y0).log10().floor() as i32).clamp(0, 4) as usize;
    root.fill(&WHITE).map_err(e)?;
    let root = root
        .titled(&fig.title, ("sans-serif", fonts.title))
        .map_err(e)?;
    for (area, panel) in root
        .split_evenly((1, fig.panels.len()))
        .iter()
        .zip(&fig.panels)
    {
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title, ("sans-serif", fonts.caption))
            .margin(14)
            .x_label_area_size(fonts.label * 3 + 6)
            .y_label_area_size(fonts.label * 5)
            .build_cartesian_2d((x0..x1).log_scale().with_key_points(ticks.to_vec()), y0..y1)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("N (hemisphere split into N x 4N patches, log scale)")
            .y_desc(fig.y_label)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.decimals$}"))
            .label_style(("sans-serif", fonts.label))
            .axis_desc_style(("sans-serif", fonts.desc))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(e)?;
        let normal: Vec<(f64, f64)> = panel
            .normal
            .iter()
            .copied()
            .filter(|p| p.1.is_finite())
            .collect();
        if !normal.is_empty() {
            // `normal` does not depend on N, but it is measured in every group, alongside the
            // configurations it is compared with: its line goes through those values (flat
            // across the panel when the sweep has one N).
            let dashed = if normal.len() == 1 {
                vec![(x0, normal[0].1), (x1, normal[0].1)]
            } else {
                normal.clone()
            };
            chart
                .draw_series(normal.iter().map(|&p| Circle::new(p, 3, BLACK.filled())))
                .map_err(e)?;
            chart
                .draw_series(DashedLineSeries::new(dashed, 10, 6, line(BLACK)))
                .map_err(e)?
                .label("normal")
                .legend(|(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (8, 0)], line(BLACK))
                        + PathElement::new(vec![(13, 0), (20, 0)], line(BLACK))
                });
        }
        for Curve {
            name,
            color,
            points,
        } in &panel.curves
        {
            let color = *color;
            let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
            chart
                .draw_series(LineSeries::new(pts, line(color)).point_size(3))
                .map_err(e)?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line(color)));
        }
        chart
            .configure_series_labels()
            .position(fig.legend.clone())
            .label_font(("sans-serif", fonts.label))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
    }
    root.present().map_err(e)
}

/// A 2-pixel line style (`Color::stroke_width`, named in full: `BackendStyle` has one too).
fn line(color: RGBColor) -> ShapeStyle {
    Color::stroke_width(&color, 2)
}

fn write_png_rgb(path: &Path, (w, h): (u32, u32), rgb: &[u8]) -> Result<(), String> {
    output::write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(rgb).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })
    .map_err(|e| e.to_string())
}
