//! Plotting: plotters draws the lines; all text comes from the font8x8 bitmap font, so no
//! font feature (and no system font) is needed.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::Res;

/// A chart colour.
pub const BLUE_: RGBColor = RGBColor(31, 119, 180);
/// A chart colour.
pub const RED_: RGBColor = RGBColor(214, 39, 40);
/// A chart colour.
pub const GREEN_: RGBColor = RGBColor(44, 160, 44);
/// A chart colour.
pub const ORANGE: RGBColor = RGBColor(255, 127, 14);
/// A chart colour.
pub const BLACK_: RGBColor = RGBColor(0, 0, 0);
/// A chart colour.
pub const GREY: RGBColor = RGBColor(140, 140, 140);
const GRID: RGBColor = RGBColor(225, 225, 225);
/// Distinct line colours (matplotlib's tab10 without grey), one per joint of a panel.
pub const PALETTE: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
];

/// One line of a chart (also used by the `whole_body` example).
pub struct Series {
    /// Legend text (empty: no legend entry).
    pub label: &'static str,
    /// Line colour.
    pub color: RGBColor,
    /// Dashed instead of solid.
    pub dashed: bool,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A solid line.
    pub fn line(label: &'static str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label,
            color,
            dashed: false,
            points,
        }
    }

    /// A dashed line.
    pub fn dashed(label: &'static str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label,
            color,
            dashed: true,
            points,
        }
    }
}

/// One chart of a figure: title, y-axis label (time is the x axis) and lines.
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// The y-axis label, with units.
    pub y_label: &'static str,
    /// The lines.
    pub series: Vec<Series>,
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Pixel scale of the 8×8 glyphs.
const TEXT: i32 = 2;

fn glyph(c: char) -> [u8; 8] {
    use font8x8::UnicodeFonts;
    font8x8::BASIC_FONTS
        .get(c)
        .or_else(|| font8x8::LATIN_FONTS.get(c))
        .or_else(|| font8x8::GREEK_FONTS.get(c))
        .unwrap_or([0; 8])
}

fn text_width(s: &str) -> i32 {
    s.chars().count() as i32 * 8 * TEXT
}

/// Draws `s` with its top-left corner at `(x, y)` (absolute pixels of `root`).
fn text(root: &Area, s: &str, (x, y): (i32, i32), color: &RGBColor) -> Res<()> {
    for (n, c) in s.chars().enumerate() {
        let x0 = x + n as i32 * 8 * TEXT;
        for (row, bits) in glyph(c).iter().enumerate() {
            for col in 0..8 {
                if bits & (1 << col) != 0 {
                    let px = x0 + col * TEXT;
                    let py = y + row as i32 * TEXT;
                    for dy in 0..TEXT {
                        for dx in 0..TEXT {
                            root.draw_pixel((px + dx, py + dy), color)?;
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// About five round tick values covering `[lo, hi]`, and the step.
fn ticks(lo: f64, hi: f64) -> (Vec<f64>, f64) {
    let raw = (hi - lo) / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    ((first..=last).map(|i| i as f64 * step).collect(), step)
}

fn tick_label(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if step < 1e-3 || v.abs() >= 1e5 {
        let s = format!("{v:.1e}");
        return s.replace(".0e", "e");
    }
    // Decimals of the step: 0.25 needs two, 0.2 one, 5 none.
    let k = step.log10().floor();
    let mantissa = step / 10f64.powf(k);
    let extra = usize::from((mantissa - 2.5).abs() < 1e-9);
    let decimals = (-k).max(0.0) as usize + extra;
    format!("{v:.decimals$}")
}

/// Writes `panels`, stacked, as a PNG of `size` pixels (time on the x axis).
pub fn figure(path: &Path, size: (u32, u32), panels: &[Panel]) -> Res<()> {
    figure_over(path, size, panels, "time (s)")
}

/// Writes `panels`, stacked, as a PNG of `size` pixels, with `x_label` under each x axis.
pub fn figure_over(path: &Path, size: (u32, u32), panels: &[Panel], x_label: &str) -> Res<()> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE)?;
    let areas = root.split_evenly((panels.len(), 1));
    for (panel, area) in panels.iter().zip(&areas) {
        draw_panel(&root, area, panel, x_label)?;
    }
    root.present()?;
    Ok(())
}

/// Legend entries laid out in rows below the plot, within `width` pixels: `(row, x offset)`
/// of each labelled series.
fn legend_layout(panel: &Panel, width: i32) -> Vec<(&Series, i32, i32)> {
    let (mut row, mut x) = (0, 0);
    let mut out = Vec::new();
    for s in panel.series.iter().filter(|s| !s.label.is_empty()) {
        let w = text_width(s.label) + 64;
        if x > 0 && x + w > width {
            (row, x) = (row + 1, 0);
        }
        out.push((s, row, x));
        x += w;
    }
    out
}

/// One panel: the plot, its axes, and the legend in rows below the time axis (outside the
/// data).
fn draw_panel(root: &Area, area: &Area, panel: &Panel, x_label: &str) -> Res<()> {
    let (ax, ay) = area.get_base_pixel();
    let (aw, _) = area.dim_in_pixel();
    // Data ranges.
    let (mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut x0, mut x1) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &panel.series {
        for &(x, y) in &s.points {
            if y.is_finite() {
                y0 = y0.min(y);
                y1 = y1.max(y);
            }
            x0 = x0.min(x);
            x1 = x1.max(x);
        }
    }
    if (y1 - y0).abs() < 1e-300 {
        let m = if y0 == 0.0 { 1.0 } else { y0.abs() * 0.1 };
        y0 -= m;
        y1 += m;
    }
    let pad = 0.06 * (y1 - y0);
    let (y0, y1) = (y0 - pad, y1 + pad);

    // The legend goes in rows below the time axis, outside the data.
    let h = 8 * TEXT;
    let legend = legend_layout(panel, aw as i32 - 180);
    let rows = legend.iter().map(|(_, r, _)| r + 1).max().unwrap_or(0);
    let mut chart = ChartBuilder::on(area)
        .margin_left(150)
        .margin_right(40)
        .margin_top(72)
        .margin_bottom(62 + rows as u32 * (h as u32 + 8))
        .build_cartesian_2d(x0..x1, y0..y1)?;

    let (xt, xs) = ticks(x0, x1);
    let (yt, ys) = ticks(y0, y1);
    for &t in &xt {
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(t, y0), (t, y1)],
            GRID.stroke_width(1),
        )))?;
    }
    for &t in &yt {
        let style = if t == 0.0 { GREY } else { GRID };
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(x0, t), (x1, t)],
            style.stroke_width(1),
        )))?;
    }
    for s in &panel.series {
        let style = s.color.stroke_width(2);
        if s.dashed {
            chart.draw_series(DashedLineSeries::new(
                s.points.iter().copied(),
                10,
                6,
                style,
            ))?;
        } else {
            chart.draw_series(LineSeries::new(s.points.iter().copied(), style))?;
        }
    }
    chart.draw_series(std::iter::once(Rectangle::new(
        [(x0, y0), (x1, y1)],
        BLACK.stroke_width(1),
    )))?;

    // Text: title, tick labels, axis labels, legend.
    text(root, &panel.title, (ax + 16, ay + 12), &BLACK_)?;
    for &t in &xt {
        let (px, py) = chart.backend_coord(&(t, y0));
        let s = tick_label(t, xs);
        text(root, &s, (px - text_width(&s) / 2, py + 8), &BLACK_)?;
    }
    for &t in &yt {
        let (px, py) = chart.backend_coord(&(x0, t));
        let s = tick_label(t, ys);
        text(root, &s, (px - 10 - text_width(&s), py - h / 2), &BLACK_)?;
    }
    let label = x_label;
    let (_, bottom) = chart.backend_coord(&(x0, y0));
    text(
        root,
        label,
        (
            ax + aw as i32 / 2 - text_width(label) / 2 + 60,
            bottom + 14 + h,
        ),
        &BLACK_,
    )?;
    // y label above the tick labels, left-aligned at the panel edge.
    let (_, top) = chart.backend_coord(&(x0, y1));
    text(root, panel.y_label, (ax + 16, top - h - 8), &BLACK_)?;

    // Legend: rows below the time axis label.
    for (s, row, x) in legend {
        let (lx, y) = (ax + 150 + x, bottom + 24 + 2 * h + row * (h + 8));
        root.draw(&PathElement::new(
            vec![(lx, y + h / 2), (lx + 32, y + h / 2)],
            s.color.stroke_width(3),
        ))?;
        text(root, s.label, (lx + 40, y), &BLACK_)?;
    }
    Ok(())
}
