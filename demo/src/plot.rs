//! Thin helpers over `plotters` that write PNG charts.
//!
//! Two kinds of chart cover most needs of the report:
//! - [`line_chart`]: lines and markers on linear or base-10 logarithmic axes ([`Scale`]);
//! - [`histogram_grid`]: a grid of panels, each a histogram drawn against a curve.
//!
//! Rendering is pure Rust: `plotters` draws into an RGB buffer (its `ab_glyph` text backend, not
//! the system-font `ttf` one), and the `image` crate encodes the PNG. Text uses DejaVu Sans,
//! embedded in the binary by the `dejavu` crate and registered by [`register_fonts`], which
//! [`crate::run`] calls once before any section draws.
//!
//! Log axes are drawn as linear axes over log₁₀ of the data, with tick labels written as powers
//! of ten (`10⁻⁸`); the helpers take and return data in its own units.

use std::ops::Range;
use std::path::Path;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

pub use plotters::chart::SeriesLabelPosition;
pub use plotters::style::RGBColor;

use crate::Result;

/// Font family name under which the embedded font is registered; plotters' default.
pub const FONT_FAMILY: &str = "sans-serif";

/// Colours for series, in order of use (the matplotlib "tab10" hues, which stay distinguishable
/// for most readers with colour-vision deficiency).
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),  // blue
    RGBColor(214, 39, 40),   // red
    RGBColor(255, 127, 14),  // orange
    RGBColor(44, 160, 44),   // green
    RGBColor(148, 103, 189), // purple
    RGBColor(127, 127, 127), // grey
];

/// Registers the embedded DejaVu Sans (regular and bold) as [`FONT_FAMILY`].
///
/// Must run before anything draws text; calling it again does nothing.
pub fn register_fonts() -> Result<()> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            for (style, bytes) in [
                (FontStyle::Normal, dejavu::sans::regular()),
                (FontStyle::Bold, dejavu::sans::bold()),
            ] {
                plotters::style::register_font(FONT_FAMILY, style, bytes)
                    .map_err(|_| "the embedded DejaVu Sans font could not be parsed".to_owned())?;
            }
            Ok(())
        })
        .clone()
        .map_err(Into::into)
}

/// How an axis maps data to the page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Base-10 logarithmic axis; values ≤ 0 or non-finite are left out.
    Log10,
}

/// One axis: its label, its range in data units and its scale.
#[derive(Clone, Debug)]
pub struct Axis {
    /// Axis label (plain text, Unicode welcome: the font has Greek letters and superscripts).
    pub label: String,
    /// Shown range in data units; for [`Scale::Log10`] both ends must be > 0.
    pub range: Range<f64>,
    /// Linear or logarithmic.
    pub scale: Scale,
}

impl Axis {
    /// A linear axis over `range`.
    pub fn linear(label: &str, range: Range<f64>) -> Self {
        Self {
            label: label.to_owned(),
            range,
            scale: Scale::Linear,
        }
    }

    /// A base-10 logarithmic axis over `range` (both ends > 0).
    pub fn log10(label: &str, range: Range<f64>) -> Self {
        Self {
            label: label.to_owned(),
            range,
            scale: Scale::Log10,
        }
    }

    /// Maps a data value to the plotting coordinate (log₁₀ for log axes); `None` if it cannot be
    /// shown on this axis.
    fn to_plot(&self, v: f64) -> Option<f64> {
        match self.scale {
            Scale::Linear => v.is_finite().then_some(v),
            Scale::Log10 => (v.is_finite() && v > 0.0).then(|| v.log10()),
        }
    }

    fn plot_range(&self) -> Range<f64> {
        match self.scale {
            Scale::Linear => self.range.clone(),
            Scale::Log10 => self.range.start.log10()..self.range.end.log10(),
        }
    }

    /// Number of tick labels to ask plotters for: one per decade on log axes.
    fn tick_count(&self) -> usize {
        match self.scale {
            Scale::Linear => 8,
            Scale::Log10 => {
                let decades = (self.range.end / self.range.start).log10().abs().round() as usize;
                // Label every decade up to 16 of them, every second one beyond.
                if decades <= 16 {
                    decades + 1
                } else {
                    decades / 2 + 1
                }
            }
        }
    }

    fn tick_label(&self, v: f64) -> String {
        match self.scale {
            Scale::Linear => format_number(v),
            Scale::Log10 => {
                let k = v.round();
                if (v - k).abs() < 1e-6 {
                    power_of_ten(k as i32)
                } else {
                    String::new()
                }
            }
        }
    }
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SeriesStyle {
    /// A polyline through the points, `width` pixels wide.
    Line {
        /// Stroke width in pixels.
        width: u32,
    },
    /// A filled circle of radius `size` pixels at each point.
    Dots {
        /// Radius in pixels.
        size: u32,
    },
    /// A filled triangle of `size` pixels at each point (used to flag special values).
    Triangles {
        /// Size in pixels.
        size: u32,
    },
}

/// A named set of points in data units.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend entry; an empty label keeps the series out of the legend.
    pub label: String,
    /// Colour.
    pub color: RGBColor,
    /// Drawing style.
    pub style: SeriesStyle,
    /// Points `(x, y)` in data units; points that an axis cannot show are skipped (a line is
    /// broken there).
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A line series of width 2.
    pub fn line(label: &str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.to_owned(),
            color,
            style: SeriesStyle::Line { width: 2 },
            points,
        }
    }

    /// A series of dots of radius 3.
    pub fn dots(label: &str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.to_owned(),
            color,
            style: SeriesStyle::Dots { size: 3 },
            points,
        }
    }

    /// A series of triangle markers.
    pub fn triangles(label: &str, color: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.to_owned(),
            color,
            style: SeriesStyle::Triangles { size: 7 },
            points,
        }
    }
}

/// A chart of lines and markers.
#[derive(Clone, Debug)]
pub struct LineChart {
    /// Title drawn above the plot.
    pub title: String,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Series, drawn in order (later ones on top).
    pub series: Vec<Series>,
    /// Where the legend goes.
    pub legend: SeriesLabelPosition,
}

/// One panel of a [`histogram_grid`]: a histogram as bars and a curve over it.
#[derive(Clone, Debug)]
pub struct HistogramPanel {
    /// Panel title.
    pub title: String,
    /// Horizontal axis (linear).
    pub x_label: String,
    /// Vertical axis label (the y range is fitted to the data).
    pub y_label: String,
    /// Bin edges, increasing; one more than `heights`.
    pub edges: Vec<f64>,
    /// Bar heights (for example densities: count / (N · bin width)).
    pub heights: Vec<f64>,
    /// Legend entry of the bars.
    pub bars_label: String,
    /// The curve `(x, y)` drawn over the bars.
    pub curve: Vec<(f64, f64)>,
    /// Legend entry of the curve.
    pub curve_label: String,
}

/// Draws `chart` into a `width × height` PNG at `path`.
pub fn line_chart(path: &Path, (width, height): (u32, u32), chart: &LineChart) -> Result<()> {
    save_png(path, (width, height), |root| {
        let x_range = chart.x.plot_range();
        let y_range = chart.y.plot_range();
        let mut ctx = ChartBuilder::on(root)
            .caption(
                &chart.title,
                (FONT_FAMILY, 22).into_font().style(FontStyle::Bold),
            )
            .margin(14)
            .x_label_area_size(52)
            .y_label_area_size(78)
            .build_cartesian_2d(x_range.clone(), y_range.clone())?;
        let x_fmt = |v: &f64| chart.x.tick_label(*v);
        let y_fmt = |v: &f64| chart.y.tick_label(*v);
        let mut mesh = ctx.configure_mesh();
        mesh.x_desc(chart.x.label.as_str())
            .y_desc(chart.y.label.as_str())
            .x_labels(chart.x.tick_count())
            .y_labels(chart.y.tick_count())
            .x_label_formatter(&x_fmt)
            .y_label_formatter(&y_fmt)
            .label_style((FONT_FAMILY, 15))
            .axis_desc_style((FONT_FAMILY, 17))
            .light_line_style(RGBColor(238, 238, 238));
        if chart.x.scale == Scale::Log10 {
            mesh.x_max_light_lines(0);
        }
        if chart.y.scale == Scale::Log10 {
            mesh.y_max_light_lines(0);
        }
        mesh.draw()?;

        let mut any_label = false;
        for series in &chart.series {
            let mapped: Vec<Option<(f64, f64)>> = series
                .points
                .iter()
                .map(|&(x, y)| Some((chart.x.to_plot(x)?, chart.y.to_plot(y)?)))
                .map(|p| p.filter(|&(x, y)| contains(&x_range, x) && contains(&y_range, y)))
                .collect();
            let color = series.color;
            let annotation = match series.style {
                SeriesStyle::Line { width } => {
                    let style = color.stroke_width(width);
                    // Break the line wherever a point cannot be shown.
                    for run in mapped.split(Option::is_none) {
                        if run.len() >= 2 {
                            ctx.draw_series(LineSeries::new(run.iter().flatten().copied(), style))?;
                        }
                    }
                    ctx.draw_series(std::iter::empty::<PathElement<(f64, f64)>>())?
                }
                SeriesStyle::Dots { size } => ctx.draw_series(
                    mapped
                        .iter()
                        .flatten()
                        .map(|&p| Circle::new(p, size, color.filled())),
                )?,
                SeriesStyle::Triangles { size } => ctx.draw_series(
                    mapped
                        .iter()
                        .flatten()
                        .map(|&p| TriangleMarker::new(p, size, color.filled())),
                )?,
            };
            if !series.label.is_empty() {
                any_label = true;
                let style = series.style;
                annotation
                    .label(series.label.as_str())
                    .legend(move |(x, y)| legend_glyph(style, color, x, y));
            }
        }
        if any_label {
            ctx.configure_series_labels()
                .position(chart.legend.clone())
                .label_font((FONT_FAMILY, 15))
                .background_style(WHITE.mix(0.9))
                .border_style(RGBColor(180, 180, 180))
                .margin(10)
                .draw()?;
        }
        Ok(())
    })
}

/// Draws `panels` in a grid with `columns` columns into a `width × height` PNG at `path`.
///
/// Each panel fits its own axes: x spans the bin edges, y runs from 0 to a bit above the
/// highest bar or curve point. Empty cells of the last row stay blank.
pub fn histogram_grid(
    path: &Path,
    (width, height): (u32, u32),
    columns: usize,
    panels: &[HistogramPanel],
) -> Result<()> {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns).max(1);
    save_png(path, (width, height), |root| {
        for (area, panel) in root.split_evenly((rows, columns)).iter().zip(panels) {
            histogram_panel(area, panel)?;
        }
        Ok(())
    })
}

fn histogram_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    panel: &HistogramPanel,
) -> Result<()> {
    let (Some(&x0), Some(&x1)) = (panel.edges.first(), panel.edges.last()) else {
        return Err("histogram panel without bin edges".into());
    };
    if panel.edges.len() != panel.heights.len() + 1 {
        return Err("histogram panel: need one more edge than heights".into());
    }
    let top = panel
        .heights
        .iter()
        .copied()
        .chain(
            panel
                .curve
                .iter()
                .filter(|p| p.0 >= x0 && p.0 <= x1)
                .map(|p| p.1),
        )
        .filter(|v| v.is_finite())
        .fold(0.0_f64, f64::max);
    let y1 = if top > 0.0 { top * 1.18 } else { 1.0 };

    let mut ctx = ChartBuilder::on(area)
        .caption(
            &panel.title,
            (FONT_FAMILY, 19).into_font().style(FontStyle::Bold),
        )
        .margin(10)
        .x_label_area_size(44)
        .y_label_area_size(62)
        .build_cartesian_2d(x0..x1, 0.0..y1)?;
    let fmt = |v: &f64| format_number(*v);
    ctx.configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .x_labels(6)
        .y_labels(6)
        .x_label_formatter(&fmt)
        .y_label_formatter(&fmt)
        .label_style((FONT_FAMILY, 13))
        .axis_desc_style((FONT_FAMILY, 15))
        .light_line_style(RGBColor(240, 240, 240))
        .draw()?;

    // Opaque light bars (a blend of the first palette colour with white), so the grid stays behind.
    let bar_color = RGBColor(165, 200, 225);
    ctx.draw_series(
        panel
            .edges
            .windows(2)
            .zip(&panel.heights)
            .map(|(e, &h)| Rectangle::new([(e[0], 0.0), (e[1], h)], bar_color.filled())),
    )?
    .label(panel.bars_label.as_str())
    .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 18, y + 5)], bar_color.filled()));

    let curve_color = PALETTE[1];
    let curve = panel
        .curve
        .iter()
        .copied()
        .filter(|&(x, y)| x >= x0 && x <= x1 && y.is_finite());
    ctx.draw_series(LineSeries::new(curve, curve_color.stroke_width(2)))?
        .label(panel.curve_label.as_str())
        .legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 18, y)], curve_color.stroke_width(2))
        });

    ctx.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT_FAMILY, 13))
        .background_style(WHITE.mix(0.9))
        .border_style(RGBColor(180, 180, 180))
        .draw()?;
    Ok(())
}

/// Renders with `draw` into an RGB buffer and writes it as PNG to `path`.
fn save_png(
    path: &Path,
    (width, height): (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    let mut buffer = vec![0_u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, (width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        draw(&root)?;
        root.present()?;
    }
    write_rgb_png(path, &buffer, width, height)
}

/// Writes a `width × height` RGB8 buffer (rows top to bottom) as PNG to `path`.
pub fn write_rgb_png(path: &Path, buffer: &[u8], width: u32, height: u32) -> Result<()> {
    image::save_buffer_with_format(
        path,
        buffer,
        width,
        height,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(())
}

fn legend_glyph<DB: DrawingBackend>(
    style: SeriesStyle,
    color: RGBColor,
    x: i32,
    y: i32,
) -> DynElement<'static, DB, (i32, i32)> {
    match style {
        SeriesStyle::Line { width } => {
            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(width)).into_dyn()
        }
        SeriesStyle::Dots { size } => Circle::new((x + 10, y), size, color.filled()).into_dyn(),
        SeriesStyle::Triangles { size } => {
            TriangleMarker::new((x + 10, y), size, color.filled()).into_dyn()
        }
    }
}

fn contains(range: &Range<f64>, v: f64) -> bool {
    let (lo, hi) = if range.start <= range.end {
        (range.start, range.end)
    } else {
        (range.end, range.start)
    };
    // A little slack so that points on the frame (e.g. markers at the top) are kept.
    let slack = (hi - lo) * 1e-9;
    v >= lo - slack && v <= hi + slack
}

/// `10` raised to `k`, written with Unicode superscripts: `1`, `10`, `10²`, `10⁻⁸`.
pub fn power_of_ten(k: i32) -> String {
    const SUPERSCRIPTS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    match k {
        0 => "1".to_owned(),
        1 => "10".to_owned(),
        _ => {
            let mut s = String::from("10");
            if k < 0 {
                s.push('⁻');
            }
            for digit in k.unsigned_abs().to_string().bytes() {
                s.push(SUPERSCRIPTS[usize::from(digit - b'0')]);
            }
            s
        }
    }
}

/// A short label for a number: up to four decimals in [10⁻³, 10⁴), scientific notation with
/// three significant digits outside, trailing zeros removed (`0.25`, `8e-5`, `1.5e6`).
pub fn format_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return if v == 0.0 {
            "0".to_owned()
        } else {
            v.to_string()
        };
    }
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        trim_zeros(&format!("{v:.4}")).to_owned()
    } else {
        let s = format!("{v:.2e}");
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        format!("{}e{exponent}", trim_zeros(mantissa))
    }
}

fn trim_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_labels() {
        assert_eq!(format_number(0.0), "0");
        assert_eq!(format_number(0.25), "0.25");
        assert_eq!(format_number(2.0), "2");
        assert_eq!(format_number(8e-5), "8e-5");
        assert_eq!(format_number(2e-5 * (1.0 + f64::EPSILON)), "2e-5");
        assert_eq!(format_number(1.5e6), "1.5e6");
        assert_eq!(format_number(-0.001), "-0.001");
    }

    #[test]
    fn power_labels() {
        assert_eq!(power_of_ten(0), "1");
        assert_eq!(power_of_ten(1), "10");
        assert_eq!(power_of_ten(2), "10²");
        assert_eq!(power_of_ten(-8), "10⁻⁸");
        assert_eq!(power_of_ten(-10), "10⁻¹⁰");
    }

    #[test]
    fn log_axis_maps_and_labels() {
        let axis = Axis::log10("κ", 1e-8..1e6);
        assert_eq!(axis.to_plot(100.0), Some(2.0));
        assert_eq!(axis.to_plot(0.0), None);
        assert_eq!(axis.to_plot(f64::NAN), None);
        assert_eq!(axis.tick_label(-3.0), "10⁻³");
        assert_eq!(axis.tick_label(-2.5), "");
        assert_eq!(axis.tick_count(), 15);
    }
}
