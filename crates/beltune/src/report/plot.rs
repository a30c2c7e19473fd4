//! SVG plots with `plotters` (text rendered with the embedded DejaVu Sans, so
//! the output does not depend on the fonts installed on the machine).

use super::data::{BodeCurve, BodePlot, FrequencyMarker, FrfPlot, FrictionPlot, MovePlot};
use crate::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

const WIDTH: u32 = 900;
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(23, 190, 207),
];
const GREY: RGBColor = RGBColor(170, 170, 170);

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

/// Draw magnitude and phase panels of Bode curves on `areas[0]`, `areas[1]`.
fn draw_bode_panels(
    mag_area: &DrawingArea<SVGBackend, Shift>,
    phase_area: &DrawingArea<SVGBackend, Shift>,
    title: &str,
    curves: &[(&BodeCurve, RGBColor)],
    markers: &[FrequencyMarker],
) -> Result<()> {
    let refs: Vec<&BodeCurve> = curves.iter().map(|(c, _)| *c).collect();
    let fr = freq_range(&refs);
    let mag = range_of(refs.iter().flat_map(|c| c.magnitude_db.iter()), -60.0..20.0);
    let ph = range_of(refs.iter().flat_map(|c| c.phase_deg.iter()), -360.0..0.0);

    let mut chart = ChartBuilder::on(mag_area)
        .caption(title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(20)
        .y_label_area_size(55)
        .build_cartesian_2d(fr.clone().log_scale(), mag.clone())
        .map_err(err)?;
    chart
        .configure_mesh()
        .y_desc("magnitude / dB")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(err)?;
    for (c, color) in curves {
        chart
            .draw_series(LineSeries::new(
                points(&c.freq_hz, &c.magnitude_db),
                color.stroke_width(2),
            ))
            .map_err(err)?
            .label(c.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
    }
    for m in markers
        .iter()
        .filter(|m| m.freq_hz > fr.start && m.freq_hz < fr.end)
    {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(m.freq_hz, mag.start), (m.freq_hz, mag.end)],
                5,
                4,
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                m.label.clone(),
                (m.freq_hz, mag.end - 0.08 * (mag.end - mag.start)),
                ("sans-serif", 12),
            )))
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(("sans-serif", 12))
        .draw()
        .map_err(err)?;

    let mut chart = ChartBuilder::on(phase_area)
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(fr.clone().log_scale(), ph.clone())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("frequency / Hz")
        .y_desc("phase / deg")
        .label_style(("sans-serif", 12))
        .draw()
        .map_err(err)?;
    for (c, color) in curves {
        chart
            .draw_series(LineSeries::new(
                points(&c.freq_hz, &c.phase_deg),
                color.stroke_width(2),
            ))
            .map_err(err)?;
    }
    for m in markers
        .iter()
        .filter(|m| m.freq_hz > fr.start && m.freq_hz < fr.end)
    {
        chart
            .draw_series(DashedLineSeries::new(
                vec![(m.freq_hz, ph.start), (m.freq_hz, ph.end)],
                5,
                4,
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(err)?;
    }
    Ok(())
}

/// A Bode diagram (magnitude over phase) as an SVG document.
pub fn bode_svg(plot: &BodePlot) -> Result<String> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (WIDTH, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (top, bottom) = root.split_vertically(300);
        let curves: Vec<(&BodeCurve, RGBColor)> = plot
            .curves
            .iter()
            .enumerate()
            .map(|(i, c)| (c, PALETTE[i % PALETTE.len()]))
            .collect();
        draw_bode_panels(&top, &bottom, &plot.title, &curves, &plot.markers)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// The measured FRF (usable lines in colour, excluded lines grey), the fitted
/// model, and the coherence below, as an SVG document.
pub fn frf_svg(plot: &FrfPlot) -> Result<String> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (WIDTH, 720)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (top, rest) = root.split_vertically(300);
        let (middle, bottom) = rest.split_vertically(240);
        // Split the measured curve into used and excluded lines.
        let pick = |keep: bool| BodeCurve {
            label: if keep {
                format!("{} (used by the fit)", plot.measured.label)
            } else {
                "excluded lines".to_string()
            },
            freq_hz: filter_by(&plot.measured.freq_hz, &plot.usable, keep),
            magnitude_db: filter_by(&plot.measured.magnitude_db, &plot.usable, keep),
            phase_deg: filter_by(&plot.measured.phase_deg, &plot.usable, keep),
        };
        let used = pick(true);
        let excluded = pick(false);
        let curves = [
            (&excluded, GREY),
            (&used, PALETTE[0]),
            (&plot.model, PALETTE[1]),
        ];
        draw_bode_panels(
            &top,
            &middle,
            "Measured frequency response and fitted model",
            &curves,
            &plot.markers,
        )?;
        let fr = freq_range(&[&plot.measured]);
        let mut chart = ChartBuilder::on(&bottom)
            .margin(8)
            .x_label_area_size(35)
            .y_label_area_size(55)
            .build_cartesian_2d(fr.log_scale(), 0.0..1.05)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("frequency / Hz")
            .y_desc("coherence")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(
                points(&plot.measured.freq_hz, &plot.coherence)
                    .into_iter()
                    .map(|p| Circle::new(p, 2, PALETTE[2].filled())),
            )
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

fn filter_by(xs: &[f64], mask: &[bool], keep: bool) -> Vec<f64> {
    xs.iter()
        .zip(mask.iter().chain(std::iter::repeat(&false)))
        .map(|(x, m)| if *m == keep { *x } else { f64::NAN })
        .collect()
}

/// The friction curve: measured torque per constant-velocity run and the fitted
/// `tau = d_v omega + tau_c sign(omega)` (3.36), as an SVG document.
pub fn friction_svg(plot: &FrictionPlot) -> Result<String> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (WIDTH, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let vr = range_of(plot.velocity_rad_s.iter(), -100.0..100.0);
        let model = |w: f64| plot.viscous_nm_s_per_rad * w + plot.coulomb_nm * w.signum();
        let tr = range_of(
            plot.torque_nm
                .iter()
                .chain([model(vr.start), model(vr.end)].iter()),
            -1.0..1.0,
        );
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Friction: measured torque and fitted model (3.36)",
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(vr.clone(), tr)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("motor velocity / (rad/s)")
            .y_desc("torque / N m")
            .label_style(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(
                points(&plot.velocity_rad_s, &plot.torque_nm)
                    .into_iter()
                    .map(|p| Circle::new(p, 4, PALETTE[0].filled())),
            )
            .map_err(err)?
            .label("measured (mean torque per run)")
            .legend(|(x, y)| Circle::new((x + 8, y), 4, PALETTE[0].filled()));
        let n = 400;
        let curve: Vec<(f64, f64)> = (0..=n)
            .map(|i| vr.start + (vr.end - vr.start) * i as f64 / n as f64)
            .filter(|w| *w != 0.0)
            .map(|w| (w, model(w)))
            .collect();
        let (neg, pos): (Vec<_>, Vec<_>) = curve.into_iter().partition(|p| p.0 < 0.0);
        let label = format!(
            "fit: d_v = {:.3e} N m s/rad, tau_c = {:.4} N m",
            plot.viscous_nm_s_per_rad, plot.coulomb_nm
        );
        chart
            .draw_series(LineSeries::new(pos, PALETTE[1].stroke_width(2)))
            .map_err(err)?
            .label(label)
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], PALETTE[1].stroke_width(2))
            });
        chart
            .draw_series(LineSeries::new(neg, PALETTE[1].stroke_width(2)))
            .map_err(err)?;
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.3))
            .label_font(("sans-serif", 12))
            .draw()
            .map_err(err)?;
        root.present().map_err(err)?;
    }
    Ok(out)
}

/// One panel of time series sharing the time axis.
fn draw_time_panel(
    area: &DrawingArea<SVGBackend, Shift>,
    title: Option<&str>,
    y_desc: &str,
    t_range: Range<f64>,
    series: &[(String, &[f64], &[f64], RGBColor)],
    scale: f64,
    x_label: bool,
) -> Result<()> {
    let yr = range_of(
        series
            .iter()
            .flat_map(|s| s.2.iter())
            .map(|v| v * scale)
            .collect::<Vec<_>>()
            .iter(),
        -1.0..1.0,
    );
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(8)
        .x_label_area_size(if x_label { 35 } else { 20 })
        .y_label_area_size(65);
    if let Some(t) = title {
        builder.caption(t, ("sans-serif", 18));
    }
    let mut chart = builder.build_cartesian_2d(t_range, yr).map_err(err)?;
    let mut mesh = chart.configure_mesh();
    mesh.y_desc(y_desc).label_style(("sans-serif", 12));
    if x_label {
        mesh.x_desc("time / s");
    }
    mesh.draw().map_err(err)?;
    for (label, t, y, color) in series {
        let pts: Vec<(f64, f64)> = points(t, y)
            .into_iter()
            .map(|(a, b)| (a, b * scale))
            .collect();
        let color = *color;
        chart
            .draw_series(LineSeries::new(pts, color.stroke_width(2)))
            .map_err(err)?
            .label(label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The validation moves: desired position, cart and motor-side tracking errors
/// (mm) and torque, one colour per feedforward variant, as an SVG document.
pub fn moves_svg(moves: &[MovePlot]) -> Result<String> {
    register_font();
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (WIDTH, 900)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let panels = root.split_evenly((4, 1));
        let t_range = range_of(moves.iter().flat_map(|m| m.time_s.iter()), 0.0..1.0);
        let t_range = t_range.start.max(0.0)..t_range.end;
        let color = |i: usize| PALETTE[i % PALETTE.len()];
        let desired: Vec<(String, &[f64], &[f64], RGBColor)> = moves
            .iter()
            .take(1)
            .map(|m| {
                (
                    "desired".to_string(),
                    &m.time_s[..],
                    &m.desired_m[..],
                    BLACK,
                )
            })
            .collect();
        draw_time_panel(
            &panels[0],
            Some("Validation move 0 -> 500 mm"),
            "position / m",
            t_range.clone(),
            &desired,
            1.0,
            false,
        )?;
        let cart: Vec<_> = moves
            .iter()
            .enumerate()
            .filter(|(_, m)| !m.cart_error_m.is_empty())
            .map(|(i, m)| {
                (
                    m.label.clone(),
                    &m.time_s[..],
                    &m.cart_error_m[..],
                    color(i),
                )
            })
            .collect();
        draw_time_panel(
            &panels[1],
            None,
            "cart error / mm",
            t_range.clone(),
            &cart,
            1e3,
            false,
        )?;
        let motor: Vec<_> = moves
            .iter()
            .enumerate()
            .map(|(i, m)| {
                (
                    m.label.clone(),
                    &m.time_s[..],
                    &m.motor_error_m[..],
                    color(i),
                )
            })
            .collect();
        draw_time_panel(
            &panels[2],
            None,
            "motor-side error / mm",
            t_range.clone(),
            &motor,
            1e3,
            false,
        )?;
        let torque: Vec<_> = moves
            .iter()
            .enumerate()
            .map(|(i, m)| (m.label.clone(), &m.time_s[..], &m.torque_nm[..], color(i)))
            .collect();
        draw_time_panel(
            &panels[3],
            None,
            "torque / N m",
            t_range,
            &torque,
            1.0,
            true,
        )?;
        root.present().map_err(err)?;
    }
    Ok(out)
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
        }
    }

    #[test]
    fn bode_svg_contains_a_path_per_curve_and_the_labels() {
        let svg = bode_svg(&BodePlot {
            title: "open loop".into(),
            curves: vec![curve()],
            markers: vec![FrequencyMarker {
                label: "w_c".into(),
                freq_hz: 10.0,
            }],
        })
        .unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("<polyline"), "no curve drawn");
        assert!(svg.contains("open loop") && svg.contains("w_c"));
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
        })
        .is_ok());
        assert!(friction_svg(&FrictionPlot::default()).is_ok());
        assert!(moves_svg(&[]).is_ok());
    }
}
