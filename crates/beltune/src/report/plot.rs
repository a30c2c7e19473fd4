//! SVG plots with `plotters` (text measured with the embedded DejaVu Sans, so
//! the layout does not depend on the fonts installed on the machine).
//!
//! Every plot is drawn at [`SCALE`] times its display size and shown at the
//! display size (the SVG keeps the fine `viewBox`): plotters rounds coordinates
//! to whole pixels, which at display size draws staircases. Legends sit above
//! the plot area, never on the data; marker and point labels are placed so that
//! no two text boxes overlap.

use super::data::{
    BodeCurve, BodePlot, ExcitationPlot, FrequencyMarker, FrfPlot, FrictionPlot, MarginPoint,
    MovePlot, Panel, TrendPlot,
};
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Drawing resolution over display resolution.
pub const SCALE: u32 = 4;
/// Display width of every plot, px.
pub const WIDTH: u32 = 900;
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
];
const GREY: RGBColor = RGBColor(170, 170, 170);
/// Font size of tick labels, legends and marker labels (display px).
const SMALL: u32 = 13;
/// Most y tick labels per panel (panels are 150..250 px high: a label
/// every 25 px or more keeps them apart).
const Y_LABELS: usize = 6;
/// Font size of captions (display px).
const CAPTION: u32 = 16;

/// Display px to drawing px.
const fn px(v: u32) -> u32 {
    v * SCALE
}

fn font(size: u32) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", px(size) as f64).into_font())
}

fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is valid; a failure would only mean unreadable labels.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

fn err<E: std::fmt::Display>(e: E) -> Error {
    Error::Report {
        reason: e.to_string(),
    }
}

/// Width and height of `text` at `size` (display px), in drawing px.
fn text_size(text: &str, size: u32) -> (i32, i32) {
    let f = ("sans-serif", px(size) as f64).into_font();
    match f.box_size(text) {
        Ok((w, h)) => (w as i32, h as i32),
        Err(_) => (
            (text.len() as u32 * px(size) * 6 / 10) as i32,
            px(size) as i32,
        ),
    }
}

/// Boxes of the labels placed so far (drawing px); a new label is moved down
/// (then up) by whole rows until it overlaps none of them.
#[derive(Default)]
struct Labels {
    boxes: Vec<[i32; 4]>,
}

impl Labels {
    fn overlaps(&self, b: [i32; 4]) -> bool {
        self.boxes
            .iter()
            .any(|o| b[0] < o[2] && o[0] < b[2] && b[1] < o[3] && o[1] < b[3])
    }

    /// Place a `w` x `h` box near `(x, y)` (top-left) inside `bounds`
    /// `[x0, y0, x1, y1]`; returns its top-left corner.
    fn place(&mut self, x: i32, y: i32, w: i32, h: i32, bounds: [i32; 4]) -> (i32, i32) {
        let x = x.min(bounds[2] - w).max(bounds[0]);
        let row = h + px(2) as i32;
        let mut best = (x, y);
        for k in 0..24 {
            let dy = if k % 2 == 0 {
                k / 2 * row
            } else {
                -(k / 2 + 1) * row
            };
            let yy = y + dy;
            if yy < bounds[1] || yy + h > bounds[3] {
                continue;
            }
            let b = [x - px(1) as i32, yy, x + w + px(1) as i32, yy + h];
            if !self.overlaps(b) {
                best = (x, yy);
                break;
            }
        }
        self.boxes.push([
            best.0 - px(1) as i32,
            best.1,
            best.0 + w + px(1) as i32,
            best.1 + h,
        ]);
        best
    }
}

/// The finished SVG at display size (the drawing-size `viewBox` stays).
fn finish(svg: String, height: u32) -> String {
    let from = format!("<svg width=\"{}\" height=\"{}\"", px(WIDTH), px(height));
    let to = format!("<svg width=\"{WIDTH}\" height=\"{height}\"");
    svg.replacen(&from, &to, 1)
}

/// Finite range of values with a margin; a fallback when there is no data.
fn range_of<'a>(values: impl Iterator<Item = &'a f64>, fallback: Range<f64>) -> Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if !lo.is_finite() || !hi.is_finite() {
        return fallback;
    }
    if hi - lo < 1e-12 * (1.0 + hi.abs()) {
        let pad = 0.5 * (1.0 + hi.abs());
        return (lo - pad)..(hi + pad);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad)..(hi + pad)
}

/// Phase axis: the data range widened to whole multiples of 90 deg.
fn phase_range<'a>(values: impl Iterator<Item = &'a f64>) -> Range<f64> {
    let r = range_of(values, -360.0..0.0);
    let lo = (r.start / 90.0).floor() * 90.0;
    let hi = (r.end / 90.0).ceil() * 90.0;
    let (lo, hi) = if hi - lo < 90.0 {
        (lo, lo + 90.0)
    } else {
        (lo, hi)
    };
    // a little room so the lowest value label does not meet the first frequency label
    let pad = 0.02 * (hi - lo);
    (lo - pad)..(hi + pad)
}

fn freq_range(curves: &[&BodeCurve]) -> Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
    for c in curves {
        for f in c.freq_hz.iter().filter(|f| f.is_finite() && **f > 0.0) {
            lo = lo.min(*f);
            hi = hi.max(*f);
        }
    }
    if !lo.is_finite() || hi <= lo {
        return 1.0..1000.0;
    }
    lo..hi
}

fn points(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter()
        .zip(y)
        .filter(|(a, b)| a.is_finite() && b.is_finite())
        .map(|(a, b)| (*a, *b))
        .collect()
}

/// How one series is drawn.
#[derive(Clone)]
struct Style {
    label: String,
    color: RGBColor,
    dots: bool,
    dashed: bool,
    /// Whether the series sets the axis range (excluded lines do not: they
    /// are drawn where they fall inside it).
    sets_range: bool,
}

/// Legend entries in one or more rows across `area`; returns nothing drawn
/// on the data.
fn draw_legend(area: &DrawingArea<SVGBackend, Shift>, entries: &[Style], left: i32) -> Result<()> {
    let (w, _) = area.dim_in_pixel();
    let mut x = left;
    let mut y = px(4) as i32;
    let row = px(SMALL + 6) as i32;
    for e in entries.iter().filter(|e| !e.label.is_empty()) {
        let (tw, _) = text_size(&e.label, SMALL);
        let need = px(26) as i32 + tw + px(14) as i32;
        if x + need > w as i32 && x > left {
            x = left;
            y += row;
        }
        let mid = y + px(SMALL) as i32 / 2;
        if e.dots {
            area.draw(&Circle::new(
                (x + px(9) as i32, mid),
                px(3),
                e.color.filled(),
            ))
            .map_err(err)?;
        } else if e.dashed {
            for k in 0..3 {
                let x0 = x + k * px(8) as i32;
                area.draw(&PathElement::new(
                    vec![(x0, mid), (x0 + px(5) as i32, mid)],
                    e.color.stroke_width(px(2)),
                ))
                .map_err(err)?;
            }
        } else {
            area.draw(&PathElement::new(
                vec![(x, mid), (x + px(20) as i32, mid)],
                e.color.stroke_width(px(2)),
            ))
            .map_err(err)?;
        }
        area.draw(&Text::new(
            e.label.clone(),
            (x + px(26) as i32, y),
            font(SMALL),
        ))
        .map_err(err)?;
        x += need;
    }
    Ok(())
}

/// Rows the legend needs across `width_px` (drawing px).
fn legend_rows(entries: &[Style], width_px: i32, left: i32) -> u32 {
    let mut x = left;
    let mut rows = 1;
    for e in entries.iter().filter(|e| !e.label.is_empty()) {
        let (tw, _) = text_size(&e.label, SMALL);
        let need = px(26) as i32 + tw + px(14) as i32;
        if x + need > width_px && x > left {
            x = left;
            rows += 1;
        }
        x += need;
    }
    rows
}

type Chart<'a> = ChartContext<
    'a,
    SVGBackend<'a>,
    Cartesian2d<
        plotters::coord::combinators::LogCoord<f64>,
        plotters::coord::types::RangedCoordf64,
    >,
>;

/// Height of a figure's head (title and legend rows), display px; `left` is
/// where the title and the legend start.
fn head_height(legend: &[Style], left: u32) -> u32 {
    let rows = legend_rows(legend, px(WIDTH) as i32, px(left) as i32);
    CAPTION + 12 + rows * (SMALL + 6) + 4
}

/// Draw the title and the legend at the top of `root`; returns the area below them.
fn draw_head<'b>(
    root: &DrawingArea<SVGBackend<'b>, Shift>,
    title: &str,
    legend: &[Style],
    left: u32,
) -> Result<DrawingArea<SVGBackend<'b>, Shift>> {
    root.draw(&Text::new(
        title.to_string(),
        (px(left) as i32, px(6) as i32),
        font(CAPTION),
    ))
    .map_err(err)?;
    let (top, body) = root.split_vertically(px(head_height(legend, left)));
    let (_, leg) = top.split_vertically(px(CAPTION + 12));
    draw_legend(&leg, legend, px(left) as i32)?;
    Ok(body)
}

/// A chart builder on one panel with the report's margins: room for the x
/// tick labels and the axis description (`x_label`) or the ticks only, and
/// `y_label_px` (display px) for the y labels.
fn panel<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, Shift>,
    x_label: bool,
    y_label_px: u32,
) -> ChartBuilder<'a, 'b, SVGBackend<'b>> {
    let mut b = ChartBuilder::on(area);
    b.margin_left(px(8))
        .margin_right(px(16))
        .margin_top(px(4))
        .x_label_area_size(px(if x_label { 36 } else { 18 }))
        .y_label_area_size(px(y_label_px));
    b
}

/// The report's mesh style on a `configure_mesh()`: y tick count, fonts and
/// the grid lines (a macro: plotters' mesh type is generic over both axes).
macro_rules! report_mesh {
    ($mesh:expr) => {
        $mesh
            .y_labels(Y_LABELS)
            .label_style(font(SMALL))
            .axis_desc_style(font(SMALL))
            .bold_line_style(BLACK.mix(0.12).stroke_width(px(1) / 2))
            .light_line_style(BLACK.mix(0.04).stroke_width(px(1) / 2))
    };
}

fn draw_series_on(chart: &mut Chart, pts: Vec<(f64, f64)>, s: &Style) -> Result<()> {
    let color = s.color;
    if s.dots {
        chart
            .draw_series(
                pts.into_iter()
                    // 2.5 display px: a measured line is visible beside a curve
                    .map(|p| Circle::new(p, px(2) + px(1) / 2, color.filled())),
            )
            .map_err(err)?;
    } else if s.dashed {
        chart
            .draw_series(DashedLineSeries::new(
                pts,
                px(6),
                px(4),
                color.stroke_width(px(2)),
            ))
            .map_err(err)?;
    } else {
        chart
            .draw_series(LineSeries::new(pts, color.stroke_width(px(2))))
            .map_err(err)?;
    }
    Ok(())
}

/// Plot area bounds of a chart in drawing px.
fn plot_bounds(chart: &Chart, fr: &Range<f64>, yr: &Range<f64>) -> [i32; 4] {
    let (x0, y1) = chart.backend_coord(&(fr.start, yr.start));
    let (x1, y0) = chart.backend_coord(&(fr.end, yr.end));
    [x0, y0, x1, y1]
}

/// One Bode panel: curves, horizontal reference lines, vertical markers (with
/// labels if `marker_labels`), margin points.
#[allow(clippy::too_many_arguments)]
fn bode_panel(
    root: &DrawingArea<SVGBackend, Shift>,
    area: &DrawingArea<SVGBackend, Shift>,
    curves: &[(&BodeCurve, Style)],
    panel: Panel,
    fr: &Range<f64>,
    hlines: &[f64],
    markers: &[FrequencyMarker],
    points_: &[MarginPoint],
    x_label: bool,
    labels: &mut Labels,
) -> Result<()> {
    let value = |c: &BodeCurve| -> Vec<f64> {
        match panel {
            Panel::Magnitude => c.magnitude_db.clone(),
            Panel::Phase => c.phase_deg.clone(),
        }
    };
    let ranged: Vec<f64> = curves
        .iter()
        .filter(|(_, s)| s.sets_range)
        .flat_map(|(c, _)| value(c))
        .chain(hlines.iter().copied())
        .chain(points_.iter().filter(|p| p.panel == panel).map(|p| p.value))
        .collect();
    let yr = match panel {
        Panel::Magnitude => range_of(ranged.iter(), -60.0..20.0),
        Panel::Phase => phase_range(ranged.iter()),
    };
    let mut chart = self::panel(area, x_label, 62)
        .build_cartesian_2d(fr.clone().log_scale(), yr.clone())
        .map_err(err)?;
    let mut mesh = chart.configure_mesh();
    report_mesh!(mesh.y_desc(match panel {
        Panel::Magnitude => "magnitude / dB",
        Panel::Phase => "phase / deg",
    }))
    .axis_style(BLACK.stroke_width(px(1) / 2))
    // more than the decades: plotters' log axis then labels 1, 2, 5 per decade
    .x_labels(16)
    .x_label_formatter(&|f| format_hz(*f));
    if panel == Panel::Phase {
        mesh.y_label_formatter(&|v| format!("{v:.0}"));
    }
    if x_label {
        mesh.x_desc("frequency / Hz");
    } else {
        mesh.x_label_formatter(&|_| String::new());
    }
    mesh.draw().map_err(err)?;
    let in_range = |v: f64| v >= yr.start && v <= yr.end;
    for (c, s) in curves {
        let pts: Vec<(f64, f64)> = points(&c.freq_hz, &value(c))
            .into_iter()
            .filter(|p| s.sets_range || in_range(p.1))
            .filter(|p| p.0 >= fr.start && p.0 <= fr.end)
            .collect();
        draw_series_on(&mut chart, pts, s)?;
    }
    for h in hlines.iter().filter(|h| in_range(**h)) {
        chart
            .draw_series(LineSeries::new(
                vec![(fr.start, *h), (fr.end, *h)],
                BLACK.mix(0.55).stroke_width(px(1)),
            ))
            .map_err(err)?;
    }
    let bounds = plot_bounds(&chart, fr, &yr);
    let (_, th) = text_size("Hg", SMALL);
    // every reference line but 0 dB / 0 deg says what it is
    for h in hlines.iter().filter(|h| in_range(**h) && **h != 0.0) {
        let label = match panel {
            Panel::Magnitude => format!("{h} dB"),
            Panel::Phase => format!("{h} deg"),
        };
        let (_, y) = chart.backend_coord(&(fr.start, *h));
        let (tw, _) = text_size(&label, SMALL);
        let (lx, ly) = labels.place(
            bounds[2] - tw - px(4) as i32,
            y - th - px(2) as i32,
            tw,
            th,
            bounds,
        );
        root.draw(&Text::new(
            label,
            (lx, ly),
            font(SMALL).color(&BLACK.mix(0.7)),
        ))
        .map_err(err)?;
    }
    let mut sorted: Vec<&FrequencyMarker> = markers
        .iter()
        .filter(|m| m.freq_hz > fr.start && m.freq_hz < fr.end)
        .collect();
    sorted.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    for m in &sorted {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(m.freq_hz, yr.start), (m.freq_hz, yr.end)],
                px(5),
                px(4),
                BLACK.mix(0.5).stroke_width(px(1)),
            ))
            .map_err(err)?;
        if panel == Panel::Magnitude {
            let (x, _) = chart.backend_coord(&(m.freq_hz, yr.end));
            let (tw, _) = text_size(&m.label, SMALL);
            let (lx, ly) = labels.place(x + px(3) as i32, bounds[1] + px(3) as i32, tw, th, bounds);
            root.draw(&Text::new(m.label.clone(), (lx, ly), font(SMALL)))
                .map_err(err)?;
        }
    }
    for p in points_.iter().filter(|p| p.panel == panel) {
        if !(p.freq_hz > fr.start && p.freq_hz < fr.end && in_range(p.value)) {
            continue;
        }
        chart
            .draw_series(std::iter::once(Circle::new(
                (p.freq_hz, p.value),
                px(4),
                BLACK.stroke_width(px(1)),
            )))
            .map_err(err)?;
        let (x, y) = chart.backend_coord(&(p.freq_hz, p.value));
        let (tw, _) = text_size(&p.label, SMALL);
        let (lx, ly) = labels.place(x + px(6) as i32, y + px(4) as i32, tw, th, bounds);
        root.draw(&Text::new(p.label.clone(), (lx, ly), font(SMALL)))
            .map_err(err)?;
    }
    Ok(())
}

/// A frequency tick label: "0.1", "1", "10", "100", "1k".
fn format_hz(f: f64) -> String {
    if f >= 1000.0 {
        format!("{}k", f / 1000.0)
    } else if f >= 1.0 {
        format!("{f:.0}")
    } else {
        format!("{f}")
    }
}

fn styles(plot: &BodePlot) -> Vec<Style> {
    plot.curves
        .iter()
        .enumerate()
        .map(|(i, c)| Style {
            label: c.label.clone(),
            color: PALETTE[c.color_index.unwrap_or(i) % PALETTE.len()],
            dots: c.dots,
            dashed: c.dashed,
            sets_range: true,
        })
        .collect()
}

/// A panel drawn below the Bode panels (the coherence) on the shared frequency range.
type ExtraPanel<'a> = &'a dyn Fn(&DrawingArea<SVGBackend, Shift>, &Range<f64>) -> Result<()>;

/// Caption, legend strip, magnitude and (unless `magnitude_only`) phase.
fn bode_figure(
    plot: &BodePlot,
    curves: &[(&BodeCurve, Style)],
    extra_panel: Option<ExtraPanel>,
) -> Result<(String, u32)> {
    register_font();
    let st: Vec<Style> = curves.iter().map(|(_, s)| s.clone()).collect();
    let head = head_height(&st, 70);
    let mag_h = 250;
    let phase_h = if plot.magnitude_only { 0 } else { 210 };
    let extra_h = if extra_panel.is_some() { 170 } else { 0 };
    let height = head + mag_h + phase_h + extra_h + 20;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (px(WIDTH), px(height))).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let body = draw_head(&root, &plot.title, &st, 70)?;
        let refs: Vec<&BodeCurve> = curves
            .iter()
            .filter(|(_, s)| s.sets_range)
            .map(|(c, _)| *c)
            .collect();
        let fr = freq_range(&refs);
        let mut labels = Labels::default();
        let last_is_mag = plot.magnitude_only && extra_panel.is_none();
        let (mag, rest) = body.split_vertically(px(mag_h + if last_is_mag { 20 } else { 0 }));
        bode_panel(
            &root,
            &mag,
            curves,
            Panel::Magnitude,
            &fr,
            &plot.magnitude_lines_db,
            &plot.markers,
            &plot.points,
            last_is_mag,
            &mut labels,
        )?;
        let rest = if plot.magnitude_only {
            rest
        } else {
            let last = extra_panel.is_none();
            let (phase, rest) = rest.split_vertically(px(phase_h + if last { 20 } else { 0 }));
            bode_panel(
                &root,
                &phase,
                curves,
                Panel::Phase,
                &fr,
                &plot.phase_lines_deg,
                &plot.markers,
                &plot.points,
                last,
                &mut labels,
            )?;
            rest
        };
        if let Some(f) = extra_panel {
            f(&rest, &fr)?;
        }
        root.present().map_err(err)?;
    }
    Ok((out, height))
}

/// A Bode diagram (magnitude over phase, or magnitude only) as an SVG document.
pub fn bode_svg(plot: &BodePlot) -> Result<String> {
    let st = styles(plot);
    let curves: Vec<(&BodeCurve, Style)> = plot.curves.iter().zip(st).collect();
    let (svg, h) = bode_figure(plot, &curves, None)?;
    Ok(finish(svg, h))
}

fn filter_by(xs: &[f64], mask: &[bool], keep: bool) -> Vec<f64> {
    xs.iter()
        .zip(mask.iter().chain(std::iter::repeat(&false)))
        .map(|(x, m)| if *m == keep { *x } else { f64::NAN })
        .collect()
}

/// The measured FRF (lines used by the fit in colour, excluded lines grey),
/// the fitted model, and the coherence below, as an SVG document.
pub fn frf_svg(plot: &FrfPlot) -> Result<String> {
    let pick = |keep: bool| BodeCurve {
        label: String::new(),
        freq_hz: filter_by(&plot.measured.freq_hz, &plot.usable, keep),
        magnitude_db: filter_by(&plot.measured.magnitude_db, &plot.usable, keep),
        phase_deg: filter_by(&plot.measured.phase_deg, &plot.usable, keep),
        dots: true,
        dashed: false,
        color_index: None,
    };
    let used = pick(true);
    let excluded = pick(false);
    let style = |label: &str, color, dots, sets_range| Style {
        label: label.into(),
        color,
        dots,
        dashed: false,
        sets_range,
    };
    let curves = [
        (
            &excluded,
            style(
                "excluded lines (noisy or outside the band)",
                GREY,
                true,
                false,
            ),
        ),
        (
            &used,
            style("measured, used by the fit", PALETTE[0], true, true),
        ),
        (
            &plot.model,
            style(&plot.model.label, PALETTE[1], false, true),
        ),
    ];
    let header = BodePlot {
        title: format!(
            "Measured frequency response (torque command -> motor angle, magnitude in dB re \
             1 rad/({})) and fitted model",
            if plot.input_unit.is_empty() {
                "N m"
            } else {
                plot.input_unit.as_str()
            }
        ),
        markers: plot.markers.clone(),
        ..BodePlot::default()
    };
    let coherence = |area: &DrawingArea<SVGBackend, Shift>, fr: &Range<f64>| -> Result<()> {
        let mut chart = panel(area, true, 62)
            .build_cartesian_2d(fr.clone().log_scale(), 0.0..1.05)
            .map_err(err)?;
        report_mesh!(chart
            .configure_mesh()
            .x_desc("frequency / Hz")
            .y_desc("coherence"))
        .x_label_formatter(&|f| format_hz(*f))
        .draw()
        .map_err(err)?;
        for keep in [false, true] {
            let color = if keep { PALETTE[2] } else { GREY };
            let pts: Vec<(f64, f64)> = points(
                &plot.measured.freq_hz,
                &filter_by(&plot.coherence, &plot.usable, keep),
            )
            .into_iter()
            .filter(|p| p.0 >= fr.start && p.0 <= fr.end)
            .collect();
            chart
                .draw_series(
                    pts.into_iter()
                        // 2.5 display px: a measured line is visible beside a curve
                        .map(|p| Circle::new(p, px(2) + px(1) / 2, color.filled())),
                )
                .map_err(err)?;
        }
        Ok(())
    };
    let (svg, h) = bode_figure(&header, &curves, Some(&coherence))?;
    Ok(finish(svg, h))
}

/// The friction curve: measured torque per constant-velocity run and the fitted
/// `tau = d_v omega + tau_c sign(omega)`, as an SVG document.
pub fn friction_svg(plot: &FrictionPlot) -> Result<String> {
    register_font();
    let height = 440;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (px(WIDTH), px(height))).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let label = format!(
            "fit: viscous d_v = {:.3e} N m s/rad, Coulomb tau_c = {:.4} N m",
            plot.viscous_nm_s_per_rad, plot.coulomb_nm
        );
        let st = [
            Style {
                label: "measured (mean torque per constant-velocity run)".into(),
                color: PALETTE[0],
                dots: true,
                dashed: false,
                sets_range: true,
            },
            Style {
                label: label.clone(),
                color: PALETTE[1],
                dots: false,
                dashed: false,
                sets_range: true,
            },
        ];
        let body = draw_head(&root, "Friction: measured torque and fitted model", &st, 70)?;
        let vr = range_of(plot.velocity_rad_s.iter(), -100.0..100.0);
        let model = |w: f64| plot.viscous_nm_s_per_rad * w + plot.coulomb_nm * w.signum();
        let tr = range_of(
            plot.torque_nm
                .iter()
                .chain([model(vr.start), model(vr.end)].iter()),
            -1.0..1.0,
        );
        let mut chart = panel(&body, true, 62)
            .build_cartesian_2d(vr.clone(), tr)
            .map_err(err)?;
        report_mesh!(chart
            .configure_mesh()
            .x_desc("motor velocity / (rad/s)")
            .y_desc("torque / N m"))
        .draw()
        .map_err(err)?;
        chart
            .draw_series(
                points(&plot.velocity_rad_s, &plot.torque_nm)
                    .into_iter()
                    .map(|p| Circle::new(p, px(4), PALETTE[0].filled())),
            )
            .map_err(err)?;
        let n = 400;
        let curve: Vec<(f64, f64)> = (0..=n)
            .map(|i| vr.start + (vr.end - vr.start) * i as f64 / n as f64)
            .filter(|w| *w != 0.0)
            .map(|w| (w, model(w)))
            .collect();
        let (neg, pos): (Vec<_>, Vec<_>) = curve.into_iter().partition(|p| p.0 < 0.0);
        for part in [pos, neg] {
            chart
                .draw_series(LineSeries::new(part, PALETTE[1].stroke_width(px(2))))
                .map_err(err)?;
        }
        root.present().map_err(err)?;
    }
    Ok(finish(out, height))
}

/// A quantity over an axis' runs: commissionings and health checks (with
/// their one-sigma bars), the latest baseline and its limits as lines.
pub fn trend_svg(plot: &TrendPlot) -> Result<String> {
    register_font();
    let height = 360;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (px(WIDTH), px(height))).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let style = |label: &str, color: RGBColor, dots: bool, dashed: bool| Style {
            label: label.into(),
            color,
            dots,
            dashed,
            sets_range: true,
        };
        let mut st = vec![
            style("commissioning", PALETTE[0], true, false),
            style("health check (one sigma)", PALETTE[2], true, false),
        ];
        if plot.baseline.is_some() {
            st.push(style("baseline", GREY, false, false));
        }
        if !plot.limits.is_empty() {
            st.push(style("limits", PALETTE[1], false, true));
        }
        let body = draw_head(&root, &plot.title, &st, 70)?;
        let runs: Vec<f64> = plot
            .commissioning_run
            .iter()
            .chain(&plot.health_run)
            .copied()
            .collect();
        let xr = range_of(runs.iter(), 0.0..2.0);
        let xr = (xr.start - 0.5)..(xr.end + 0.5);
        let lows: Vec<f64> = plot
            .health_value
            .iter()
            .zip(&plot.health_sigma)
            .flat_map(|(v, s)| [v - s.max(0.0), v + s.max(0.0)])
            .collect();
        let values: Vec<f64> = plot
            .commissioning_value
            .iter()
            .chain(&plot.health_value)
            .chain(&lows)
            .chain(plot.baseline.iter())
            .chain(plot.limits.iter().map(|l| &l.1))
            .copied()
            .collect();
        let yr = range_of(values.iter(), 0.0..1.0);
        let mut chart = panel(&body, true, 80)
            .build_cartesian_2d(xr.clone(), yr)
            .map_err(err)?;
        report_mesh!(chart
            .configure_mesh()
            .x_desc("run (oldest first)")
            .y_desc(format!("{} / {}", "value", plot.unit)))
        .draw()
        .map_err(err)?;
        let hline = |y: f64| vec![(xr.start, y), (xr.end, y)];
        if let Some(b) = plot.baseline {
            chart
                .draw_series(LineSeries::new(hline(b), GREY.stroke_width(px(2))))
                .map_err(err)?;
        }
        for (_, y) in &plot.limits {
            chart
                .draw_series(DashedLineSeries::new(
                    hline(*y),
                    px(8),
                    px(5),
                    PALETTE[1].stroke_width(px(2)),
                ))
                .map_err(err)?;
        }
        for ((x, v), s) in plot
            .health_run
            .iter()
            .zip(&plot.health_value)
            .zip(&plot.health_sigma)
        {
            if s.is_finite() && v.is_finite() {
                chart
                    .draw_series(LineSeries::new(
                        vec![(*x, v - s), (*x, v + s)],
                        PALETTE[2].stroke_width(px(2)),
                    ))
                    .map_err(err)?;
            }
        }
        chart
            .draw_series(
                points(&plot.health_run, &plot.health_value)
                    .into_iter()
                    .map(|p| Circle::new(p, px(4), PALETTE[2].filled())),
            )
            .map_err(err)?;
        chart
            .draw_series(
                points(&plot.commissioning_run, &plot.commissioning_value)
                    .into_iter()
                    .map(|p| Circle::new(p, px(5), PALETTE[0].filled())),
            )
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(finish(out, height))
}

/// One series of a time panel: label, time (s), values, colour, dashed.
type TimeSeries<'a> = (String, &'a [f64], &'a [f64], RGBColor, bool);

/// One panel of time series sharing the time axis; `hlines` are limits drawn
/// as dashed red lines with their label.
#[allow(clippy::too_many_arguments)]
fn draw_time_panel(
    root: &DrawingArea<SVGBackend, Shift>,
    area: &DrawingArea<SVGBackend, Shift>,
    y_desc: &str,
    t_range: Range<f64>,
    series: &[TimeSeries],
    scale: f64,
    hlines: &[(f64, String)],
    x_label: bool,
    labels: &mut Labels,
) -> Result<()> {
    let values: Vec<f64> = series
        .iter()
        .flat_map(|s| s.2.iter().map(|v| v * scale))
        .chain(hlines.iter().map(|h| h.0 * scale))
        .collect();
    let yr = range_of(values.iter(), -1.0..1.0);
    let mut chart = panel(area, x_label, 70)
        .build_cartesian_2d(t_range.clone(), yr.clone())
        .map_err(err)?;
    let mut mesh = chart.configure_mesh();
    report_mesh!(mesh.y_desc(y_desc));
    if x_label {
        mesh.x_desc("time / s");
    } else {
        mesh.x_label_formatter(&|_| String::new());
    }
    mesh.draw().map_err(err)?;
    for (_, t, y, color, dashed) in series {
        let pts: Vec<(f64, f64)> = points(t, y)
            .into_iter()
            .map(|(a, b)| (a, b * scale))
            .collect();
        if *dashed {
            chart
                .draw_series(DashedLineSeries::new(
                    pts,
                    px(6),
                    px(4),
                    color.stroke_width(px(2)),
                ))
                .map_err(err)?;
        } else {
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(px(2))))
                .map_err(err)?;
        }
    }
    let (x0, y1) = chart.backend_coord(&(t_range.start, yr.start));
    let (x1, y0) = chart.backend_coord(&(t_range.end, yr.end));
    let bounds = [x0, y0, x1, y1];
    let (_, th) = text_size("Hg", SMALL);
    for (h, label) in hlines {
        let v = h * scale;
        chart
            .draw_series(DashedLineSeries::new(
                vec![(t_range.start, v), (t_range.end, v)],
                px(6),
                px(4),
                RED.mix(0.8).stroke_width(px(1)),
            ))
            .map_err(err)?;
        let (_, y) = chart.backend_coord(&(t_range.start, v));
        let (tw, _) = text_size(label, SMALL);
        let above = if v > 0.5 * (yr.start + yr.end) {
            y + px(2) as i32
        } else {
            y - th - px(2) as i32
        };
        let (lx, ly) = labels.place(x1 - tw - px(4) as i32, above, tw, th, bounds);
        root.draw(&Text::new(label.clone(), (lx, ly), font(SMALL).color(&RED)))
            .map_err(err)?;
    }
    Ok(())
}

/// Time-series figure: caption, legend, panels (each a list of series, its
/// y description, scale, limit lines).
#[allow(clippy::type_complexity)]
fn time_figure(
    title: &str,
    legend: &[Style],
    panels: &[(&str, Vec<TimeSeries>, f64, Vec<(f64, String)>)],
) -> Result<String> {
    register_font();
    let head = head_height(legend, 78);
    let panel_h = 190;
    let height = head + panel_h * panels.len() as u32 + 20;
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (px(WIDTH), px(height))).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut body = draw_head(&root, title, legend, 78)?;
        let t_range = range_of(
            panels
                .iter()
                .flat_map(|p| p.1.iter().flat_map(|s| s.1.iter())),
            0.0..1.0,
        );
        // (the 5 % pad before the first sample keeps the first time label
        // away from the lowest value label of the bottom panel)
        let mut labels = Labels::default();
        for (i, (desc, series, scale, hl)) in panels.iter().enumerate() {
            let last = i + 1 == panels.len();
            let (area, rest) = body.split_vertically(px(panel_h + if last { 20 } else { 0 }));
            draw_time_panel(
                &root,
                &area,
                desc,
                t_range.clone(),
                series,
                *scale,
                hl,
                last,
                &mut labels,
            )?;
            body = rest;
        }
        root.present().map_err(err)?;
    }
    Ok(finish(out, height))
}

/// The validation moves: desired position, cart and motor-side tracking errors
/// (mm) with the 1 mm limit, and torque, one colour per variant, as an SVG document.
pub fn moves_svg(moves: &[MovePlot], torque_limit_nm: Option<f64>) -> Result<String> {
    let color = |i: usize| PALETTE[i % PALETTE.len()];
    let mut legend = vec![Style {
        label: "desired position".into(),
        color: BLACK,
        dots: false,
        dashed: false,
        sets_range: true,
    }];
    legend.extend(moves.iter().enumerate().map(|(i, m)| Style {
        label: m.label.clone(),
        color: color(i),
        dots: false,
        dashed: false,
        sets_range: true,
    }));
    let desired: Vec<TimeSeries> = moves
        .iter()
        .take(1)
        .map(|m| {
            (
                "desired".to_string(),
                &m.time_s[..],
                &m.desired_m[..],
                BLACK,
                false,
            )
        })
        .collect();
    let series = |f: &dyn Fn(&MovePlot) -> &[f64]| -> Vec<TimeSeries> {
        moves
            .iter()
            .enumerate()
            .filter(|(_, m)| !f(m).is_empty())
            .map(|(i, m)| (m.label.clone(), &m.time_s[..], f(m), color(i), false))
            .collect()
    };
    let limit = crate::verdict::MAX_TRACKING_ERROR_M;
    let error_limits = vec![
        (limit, "limit +1 mm".to_string()),
        (-limit, "limit -1 mm".to_string()),
    ];
    let torque_limits = torque_limit_nm
        .map(|t| {
            vec![
                (t, format!("torque limit {t:.2} N m")),
                (-t, format!("torque limit -{t:.2} N m")),
            ]
        })
        .unwrap_or_default();
    let mut panels = vec![("position / m", desired, 1.0, vec![])];
    let cart = series(&|m| &m.cart_error_m);
    // The delivered controller (the last move, nonlinear feedforward) on a scale
    // of its own: next to the move without feedforward (millimetres) its error
    // (tens of micrometres) would be a flat line. The limit is drawn only where
    // it is within a factor of 3 of the error, else the label names it.
    let delivered: Vec<TimeSeries> = cart.last().cloned().into_iter().collect();
    let delivered_peak = delivered
        .first()
        .map(|s| s.2.iter().fold(0.0f64, |m, v| m.max(v.abs())))
        .unwrap_or(0.0);
    if cart.len() > 1 {
        panels.push(("cart error / mm", cart, 1e3, error_limits.clone()));
    }
    if !delivered.is_empty() {
        let within = 3.0 * delivered_peak >= limit;
        let desc: &'static str = if within {
            "delivered: cart error / mm"
        } else {
            "delivered: cart error / mm (limit 1 mm off scale)"
        };
        panels.push((
            desc,
            delivered,
            1e3,
            if within { error_limits.clone() } else { vec![] },
        ));
    }
    panels.push((
        "motor-side error / mm",
        series(&|m| &m.motor_error_m),
        1e3,
        vec![],
    ));
    panels.push((
        "torque / N m",
        series(&|m| &m.torque_nm),
        1.0,
        torque_limits,
    ));
    let title = match moves.first() {
        Some(m) => {
            let (a, b) = (
                m.desired_m.first().copied().unwrap_or(0.0),
                m.desired_m.last().copied().unwrap_or(0.0),
            );
            format!("Validation move {:.0} -> {:.0} mm", a * 1e3, b * 1e3)
        }
        None => "Validation move".to_string(),
    };
    time_figure(&title, &legend, &panels)
}

/// The identification experiment: torque command with the torque limit and
/// position with the travel window, as an SVG document.
pub fn excitation_svg(plot: &ExcitationPlot) -> Result<String> {
    let legend = [
        Style {
            label: "torque command".into(),
            color: PALETTE[0],
            dots: false,
            dashed: false,
            sets_range: true,
        },
        Style {
            label: "motor-side position".into(),
            color: PALETTE[2],
            dots: false,
            dashed: false,
            sets_range: true,
        },
    ];
    let t = plot.torque_limit_nm;
    let panels = vec![
        (
            "torque / N m",
            vec![(
                "torque".to_string(),
                &plot.time_s[..],
                &plot.torque_nm[..],
                PALETTE[0],
                false,
            )],
            1.0,
            vec![
                (t, format!("torque limit {t:.2} N m")),
                (-t, format!("torque limit -{t:.2} N m")),
            ],
        ),
        (
            "position / mm",
            vec![(
                "position".to_string(),
                &plot.position_time_s[..],
                &plot.position_m[..],
                PALETTE[2],
                false,
            )],
            1e3,
            vec![
                (
                    plot.travel_max_m,
                    format!("travel max {:.0} mm", plot.travel_max_m * 1e3),
                ),
                (
                    plot.travel_min_m,
                    format!("travel min {:.0} mm", plot.travel_min_m * 1e3),
                ),
            ],
        ),
    ];
    time_figure(
        "Identification: PRBS excitation and response, with the limits",
        &legend,
        &panels,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> BodeCurve {
        let freq_hz: Vec<f64> = (0..200).map(|i| 10f64.powf(i as f64 / 50.0)).collect();
        let magnitude_db = freq_hz.iter().map(|f| -40.0 * f.log10()).collect();
        let phase_deg = freq_hz.iter().map(|_| -180.0).collect();
        BodeCurve {
            label: "1/s^2".into(),
            freq_hz,
            magnitude_db,
            phase_deg,
            ..BodeCurve::default()
        }
    }

    #[test]
    fn bode_svg_contains_a_path_per_curve_and_the_labels() {
        let svg = bode_svg(&BodePlot {
            title: "open loop".into(),
            curves: vec![curve()],
            markers: vec![FrequencyMarker {
                label: "f_c".into(),
                freq_hz: 10.0,
            }],
            ..BodePlot::default()
        })
        .unwrap();
        assert!(
            svg.starts_with(&format!("<svg width=\"{WIDTH}\"")),
            "{}",
            &svg[..80]
        );
        assert!(svg.contains("viewBox=\"0 0 3600"), "drawn at SCALE");
        assert!(svg.contains("<polyline"), "no curve drawn");
        assert!(svg.contains("open loop") && svg.contains("f_c"));
    }

    /// Two markers 1 % apart: the second label goes to another row.
    #[test]
    fn marker_labels_do_not_share_a_box() {
        let mut l = Labels::default();
        let b = [0, 0, 4000, 4000];
        let a = l.place(100, 100, 400, 48, b);
        let c = l.place(110, 100, 400, 48, b);
        assert_eq!(a, (100, 100));
        assert!((c.1 - a.1).abs() >= 48, "{c:?}");
        // at the top of the area the next free row is below
        let top = l.place(105, 0, 400, 48, b);
        let top2 = l.place(108, 0, 400, 48, b);
        assert!(top2.1 >= top.1 + 48, "{top:?} {top2:?}");
    }

    #[test]
    fn the_delivered_controllers_error_has_a_panel_on_its_own_scale() {
        let t: Vec<f64> = (0..200).map(|k| k as f64 * 0.01).collect();
        let desired: Vec<f64> = t.iter().map(|x| 0.25 * x).collect();
        let mv = |label: &str, peak: f64| MovePlot {
            label: label.into(),
            time_s: t.clone(),
            desired_m: desired.clone(),
            cart_error_m: t.iter().map(|x| peak * (6.0 * x).sin()).collect(),
            motor_error_m: Vec::new(),
            torque_nm: vec![0.1; t.len()],
        };
        let svg = moves_svg(
            &[
                mv("no feedforward", 7e-3),
                mv("nonlinear feedforward", 42e-6),
            ],
            None,
        )
        .unwrap();
        assert!(svg.contains("delivered: cart error / mm (limit 1 mm off scale)"));
        // its axis is labelled in tens of micrometres, not in millimetres: a
        // small negative tick (only that panel has one; the others span
        // millimetres, metres, seconds or newton metres)
        let ticks: Vec<f64> = svg
            .split('>')
            .filter_map(|t| t.split('<').next()?.trim().parse::<f64>().ok())
            .collect();
        assert!(
            ticks
                .iter()
                .any(|v| *v < 0.0 && v.abs() > 0.005 && v.abs() < 0.045),
            "no tick of the delivered panel's scale among {ticks:?}"
        );
    }

    #[test]
    fn empty_and_non_finite_data_do_not_panic() {
        let mut c = curve();
        c.magnitude_db[3] = f64::NAN;
        assert!(bode_svg(&BodePlot::default()).is_ok());
        assert!(frf_svg(&FrfPlot {
            measured: c.clone(),
            usable: vec![true; 200],
            coherence: vec![1.0; 200],
            model: c,
            markers: vec![],
            input_unit: String::new(),
        })
        .is_ok());
        assert!(friction_svg(&FrictionPlot::default()).is_ok());
        assert!(moves_svg(&[], None).is_ok());
        assert!(excitation_svg(&ExcitationPlot::default()).is_ok());
    }
}
