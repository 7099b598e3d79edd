//! Figures with plotters, as SVG and PNG: Figure 3 (fps per data set and
//! structure, grouped bars), Figure 4 (build rate, log axis) and the
//! error-against-time plot. Text uses the embedded DejaVu Sans, so no system
//! fonts are needed.

use super::record::{ErrorPoint, Record};
use crate::error::{Error, Result};
use crate::frame::write_atomically;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

fn color(i: usize) -> RGBColor {
    const P: [RGBColor; 12] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(57, 59, 121),
        RGBColor(173, 73, 74),
    ];
    P[i % P.len()]
}

fn err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::format(path, format!("cannot draw plot: {e}"))
}

/// Something that draws itself on any plotters backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()>;
}

/// Draws `fig` into `stem`.svg and `stem`.png (rendered in memory, then
/// written atomically).
fn both(stem: &Path, size: (u32, u32), fig: &impl Figure) -> Result<()> {
    register_font();
    let mut svg = String::new();
    fig.draw(SVGBackend::with_string(&mut svg, size).into_drawing_area())?;
    let svg_path = stem.with_extension("svg");
    write_atomically(&svg_path, |tmp| {
        std::fs::write(tmp, svg.as_bytes()).map_err(|e| Error::io(&svg_path, e))
    })?;
    let mut rgb = vec![0u8; size.0 as usize * size.1 as usize * 3];
    fig.draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area())?;
    let png_path = stem.with_extension("png");
    write_atomically(&png_path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| Error::io(&png_path, e))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), size.0, size.1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().map_err(|e| err(&png_path, e))?;
        w.write_image_data(&rgb).map_err(|e| err(&png_path, e))?;
        w.finish().map_err(|e| err(&png_path, e))
    })
}

struct Groups {
    datasets: Vec<String>,
    structures: Vec<String>,
}

fn groups(records: &[Record], skip_naive: bool) -> Groups {
    let mut g = Groups {
        datasets: Vec::new(),
        structures: Vec::new(),
    };
    for r in records {
        if skip_naive && r.accel == "naive" {
            continue;
        }
        if !g.datasets.contains(&r.dataset) {
            g.datasets.push(r.dataset.clone());
        }
        if !g.structures.contains(&r.structure) {
            g.structures.push(r.structure.clone());
        }
    }
    g
}

fn grouped_bars<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, bars: &Bars) -> Result<()> {
    let Bars {
        path,
        title,
        y_label,
        records,
        value,
        log,
        skip_naive,
        range,
        tag,
    } = *bars;
    let g = groups(records, skip_naive);
    // Colours follow the structure's place among all structures, so a
    // structure has the same colour in every figure.
    let all = groups(records, false).structures;
    let colour_of = |s: &str| color(all.iter().position(|a| a == s).unwrap_or(0));
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let values: Vec<f64> = records
        .iter()
        .filter(|r| !(skip_naive && r.accel == "naive"))
        .flat_map(|r| {
            let (lo, hi) = range.map_or((value(r), value(r)), |f| f(r));
            [value(r), lo, hi]
        })
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let max = values.iter().cloned().fold(1e-9, f64::max);
    let min = values.iter().cloned().fold(f64::INFINITY, f64::min).min(max);
    // Log axes span whole decades, so they carry labels.
    let (bottom, top) = if log {
        (10f64.powf(min.log10().floor()), 10f64.powf((max * 1.01).log10().ceil()))
    } else {
        (0.0, max * 1.15)
    };
    let n = g.datasets.len().max(1) as f64;
    let k = g.structures.len().max(1) as f64;
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, (FONT, 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64);
    // The legend sits right of the bars.
    let legend_w = 0.28 * n;
    macro_rules! draw_bars {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .disable_x_mesh()
                .x_labels(0)
                .y_desc(y_label)
                .label_style((FONT, 13))
                .draw()
                .map_err(|e| err(path, e))?;
            for (si, s) in g.structures.iter().enumerate() {
                let c = colour_of(s);
                let bars: Vec<Rectangle<(f64, f64)>> = g
                    .datasets
                    .iter()
                    .enumerate()
                    .filter_map(|(di, d)| {
                        let r = records.iter().find(|r| &r.dataset == d && &r.structure == s)?;
                        let v = value(r);
                        (v.is_finite() && v > 0.0).then(|| {
                            let x0 = di as f64 + 0.1 + 0.8 * si as f64 / k;
                            Rectangle::new([(x0, if log { bottom } else { 0.0 }), (x0 + 0.8 / k, v)], c.filled())
                        })
                    })
                    .collect();
                chart
                    .draw_series(bars)
                    .map_err(|e| err(path, e))?
                    .label(s.as_str())
                    .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 10, y + 5)], c.filled()));
                // Whiskers (the spread) and a tag above each bar.
                for (di, d) in g.datasets.iter().enumerate() {
                    let Some(r) = records.iter().find(|r| &r.dataset == d && &r.structure == s) else {
                        continue;
                    };
                    let x = di as f64 + 0.1 + 0.8 * (si as f64 + 0.5) / k;
                    let mut top_of_bar = value(r);
                    if let Some((lo, hi)) = range
                        .map(|f| f(r))
                        .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && *lo > 0.0)
                    {
                        chart
                            .draw_series(std::iter::once(PathElement::new(
                                vec![(x, lo), (x, hi)],
                                BLACK.stroke_width(1),
                            )))
                            .map_err(|e| err(path, e))?;
                        top_of_bar = top_of_bar.max(hi);
                    }
                    if let (Some(tag), true) = (tag, top_of_bar.is_finite() && top_of_bar > 0.0) {
                        // Vertical, so neighbouring bars' tags do not overlap.
                        let style = TextStyle::from((FONT, 10).into_font())
                            .transform(FontTransform::Rotate270)
                            .pos(plotters::style::text_anchor::Pos::new(
                                plotters::style::text_anchor::HPos::Left,
                                plotters::style::text_anchor::VPos::Center,
                            ));
                        let (px, py) = chart.backend_coord(&(x, top_of_bar));
                        root.draw(&Text::new(tag(r), (px, py - 3), style))
                            .map_err(|e| err(path, e))?;
                    }
                }
            }
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font((FONT, 12))
                .draw()
                .map_err(|e| err(path, e))?;
            // Data set names under their groups, in pixel coordinates.
            let floor = if log { bottom } else { 0.0 };
            for (di, d) in g.datasets.iter().enumerate() {
                let (x, y) = chart.backend_coord(&(di as f64 + 0.5, floor));
                let style = TextStyle::from((FONT, 14).into_font()).pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Center,
                    plotters::style::text_anchor::VPos::Top,
                ));
                root.draw(&Text::new(d.clone(), (x, y + 8), style))
                    .map_err(|e| err(path, e))?;
            }
        }};
    }
    if log {
        draw_bars!(builder
            .build_cartesian_2d(0.0..n + legend_w, (bottom..top).log_scale())
            .map_err(|e| err(path, e))?);
    } else {
        draw_bars!(builder
            .build_cartesian_2d(0.0..n + legend_w, 0.0..top)
            .map_err(|e| err(path, e))?);
    }
    root.present().map_err(|e| err(path, e))
}

/// A low and a high value per record.
type Span = fn(&Record) -> (f64, f64);

#[derive(Clone, Copy)]
struct Bars<'a> {
    path: &'a Path,
    title: &'a str,
    y_label: &'a str,
    records: &'a [Record],
    value: fn(&Record) -> f64,
    log: bool,
    skip_naive: bool,
    /// A whisker from .0 to .1 over each bar.
    range: Option<Span>,
    /// Text above each bar.
    tag: Option<fn(&Record) -> String>,
}

impl Figure for Bars<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()> {
        grouped_bars(root, self)
    }
}

/// Figure 3: frames per second per data set and structure (bar: median
/// frame; whisker: slowest to fastest frame; tag: speed-up over naive, †
/// when unstable).
pub fn figure3(records: &[Record], stem: &Path) -> Result<()> {
    let fig = Bars {
        path: stem,
        title: "Figure 3: frames per second (whiskers: min-max; labels: speed-up over naive, † unstable)",
        y_label: "fps",
        records,
        value: |r| r.fps,
        log: false,
        skip_naive: false,
        range: Some(|r| (1000.0 / r.frame.max_ms, 1000.0 / r.frame.min_ms)),
        tag: Some(|r| format!("{:.2}x{}", r.speedup, if r.unstable { "†" } else { "" })),
    };
    both(stem, (1100, 560), &fig)
}

/// Figure 4: build rate (builds per second, log axis), skipping naive.
pub fn figure4(records: &[Record], stem: &Path) -> Result<()> {
    let fig = Bars {
        path: stem,
        title: "Figure 4: builds per second (TF change), log scale",
        y_label: "builds / s",
        records,
        value: |r| 1000.0 / r.build_ms,
        log: true,
        skip_naive: true,
        range: Some(|r| (1000.0 / r.build_max_ms, 1000.0 / r.build_min_ms)),
        tag: None,
    };
    both(stem, (1100, 560), &fig)
}

struct ErrorFigure<'a> {
    path: &'a Path,
    points: &'a [ErrorPoint],
}

impl Figure for ErrorFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<()> {
        error_plot(root, self.path, self.points)
    }
}

fn error_plot<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, path: &Path, points: &[ErrorPoint]) -> Result<()> {
    root.fill(&WHITE).map_err(|e| err(path, e))?;
    let xs: Vec<f64> = points
        .iter()
        .map(|p| p.frame.median_ms)
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let ys: Vec<f64> = points.iter().map(|p| p.error.rmse.max(1e-9)).collect();
    let decades = |lo: f64, hi: f64| (10f64.powf(lo.log10().floor()), 10f64.powf((hi * 1.01).log10().ceil()));
    let (x0, x1) = decades(
        xs.iter().cloned().fold(f64::INFINITY, f64::min),
        xs.iter().cloned().fold(1e-9, f64::max),
    );
    let (y0, y1) = decades(
        ys.iter().cloned().fold(f64::INFINITY, f64::min),
        ys.iter().cloned().fold(1e-9, f64::max),
    );
    let mut chart = ChartBuilder::on(&root)
        .caption("Speed against error (log-log)", (FONT, 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("ms per frame")
        .y_desc("rmse against the fine reference")
        .label_style((FONT, 13))
        .draw()
        .map_err(|e| err(path, e))?;
    // A colour per data set, ERT and jitter; the hardware filter's line thin, with crosses.
    let mut series: Vec<(String, Option<f32>, String, bool)> = Vec::new();
    for p in points {
        let key = (p.dataset.clone(), p.ert, p.filter.clone(), p.jitter);
        if !series.contains(&key) {
            series.push(key);
        }
    }
    let mut colours: Vec<(&str, Option<f32>, bool)> = Vec::new();
    for (d, ert, filter, jitter) in &series {
        let i = colours
            .iter()
            .position(|k| *k == (d.as_str(), *ert, *jitter))
            .unwrap_or_else(|| {
                colours.push((d.as_str(), *ert, *jitter));
                colours.len() - 1
            });
        let c = color(i);
        let mut pts: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| &p.dataset == d && &p.ert == ert && &p.filter == filter && p.jitter == *jitter)
            .map(|p| (p.frame.median_ms, p.error.rmse.max(1e-9)))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let label = format!(
            "{d}, ERT {}, {filter}{}",
            ert.map_or("off".into(), |e| e.to_string()),
            if *jitter { ", jitter" } else { "" }
        );
        let width = if filter == "manual" { 2 } else { 1 };
        chart
            .draw_series(LineSeries::new(pts.clone(), c.stroke_width(width)))
            .map_err(|e| err(path, e))?
            .label(label)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c.stroke_width(width)));
        if filter == "manual" {
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, c.filled())))
        } else {
            chart.draw_series(pts.into_iter().map(|p| Cross::new(p, 4, c.stroke_width(1))))
        }
        .map_err(|e| err(path, e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, 11))
        .draw()
        .map_err(|e| err(path, e))?;
    root.present().map_err(|e| err(path, e))
}

/// Error against time: one line per data set, ERT threshold and filter, over steps.
pub fn error_figure(points: &[ErrorPoint], stem: &Path) -> Result<()> {
    both(stem, (1000, 640), &ErrorFigure { path: stem, points })
}
