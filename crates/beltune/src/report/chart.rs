//! The report's figures as interactive charts: the data `beltune-plot.js`
//! ([`super::web`]) draws with uPlot on screen (zoom, read-out on hover, log
//! frequency axes), beside the static SVG of [`super::plot`] that the page
//! prints. Built from the same [`Report`] data as the SVG, panel for panel:
//! the measured FRF (magnitude, phase, coherence), every Bode plot (controller,
//! open loops with margins, closed loops and sensitivities, overlays) and the
//! validation moves. Numbers are rounded to [`DIGITS`] significant digits
//! (the report stays small; a plot needs no more).

use super::data::{BodePlot, FrfPlot, MovePlot, Panel, Report};
use serde::Serialize;

/// Significant digits of the values in a chart.
pub const DIGITS: usize = 6;

const PALETTE: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#17becf",
];
const GREY: &str = "#aaaaaa";
const BLACK: &str = "#222222";

/// One curve of a panel: x in the panel's `xunit`, y in its `yunit`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ChartSeries {
    /// Stable name (for tests and tools).
    pub name: String,
    /// Legend label.
    pub label: String,
    /// x values, in the panel's `xunit` (finite; ascending).
    pub x: Vec<f64>,
    /// y values, in the panel's `yunit` (`None`: no value, a gap).
    pub y: Vec<Option<f64>>,
    /// Colour, CSS.
    pub color: String,
    /// Drawn as dots (measured lines).
    pub dots: bool,
    /// Drawn dashed.
    pub dashed: bool,
    /// Left out when the y range is chosen (grey excluded lines).
    pub norange: bool,
}

/// A vertical marker (resonance, crossover) at `x` in the panel's `xunit`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ChartMarker {
    /// Position, in the panel's `xunit`.
    pub x: f64,
    /// Stable name.
    pub name: String,
    /// Label beside it (empty: none).
    pub label: String,
    /// Style class: `marker`, `ref`, `filter`.
    pub cls: String,
}

/// A horizontal reference line (0 dB, -180 deg, a limit) at `y` in the panel's `yunit`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ChartLevel {
    /// Position, in the panel's `yunit`.
    pub y: f64,
    /// Stable name.
    pub name: String,
    /// Label above its right end (empty: none).
    pub label: String,
    /// Style class: `ref`, `limit`, or empty (a solid grey line).
    pub cls: String,
    /// Left out when the y range is chosen (a far limit is then not drawn).
    pub norange: bool,
}

/// A labelled point (gain or phase margin), in the panel's units.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ChartPoint {
    /// x, in the panel's `xunit`.
    pub x: f64,
    /// y, in the panel's `yunit`.
    pub y: f64,
    /// Label.
    pub label: String,
}

/// One panel: axes, curves, markers.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ChartPanel {
    /// Caption above the panel.
    pub title: String,
    /// Logarithmic x axis (a frequency axis).
    pub xlog: bool,
    /// x axis description with unit, e.g. "frequency / Hz".
    pub xlabel: String,
    /// Unit of x in the hover read-out ("Hz", "s").
    pub xunit: String,
    /// Name of x in the read-out ("frequency", "time").
    pub xname: String,
    /// y axis description with unit, e.g. "magnitude / dB".
    pub ylabel: String,
    /// Unit of y in the hover read-out ("dB", "deg", "mm", "N m"; empty: none).
    pub yunit: String,
    /// Curves.
    pub series: Vec<ChartSeries>,
    /// Vertical markers.
    pub vlines: Vec<ChartMarker>,
    /// Horizontal reference lines.
    pub hlines: Vec<ChartLevel>,
    /// Labelled points.
    pub points: Vec<ChartPoint>,
}

/// The interactive version of one figure of the report (`<figure id>`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FigureChart {
    /// The figure's id in the page.
    pub figure_id: String,
    /// Its panels, top to bottom (they zoom together).
    pub panels: Vec<ChartPanel>,
}

/// `v` rounded to [`DIGITS`] significant digits (its shortest decimal form then
/// has at most that many).
fn round(v: f64) -> f64 {
    format!("{v:.*e}", DIGITS - 1).parse().unwrap_or(v)
}

/// The points of `x`, `y` with a finite x (and x > 0 on a log axis); a
/// non-finite y is a gap.
fn xy(x: &[f64], y: &[f64], scale: f64, log: bool) -> (Vec<f64>, Vec<Option<f64>>) {
    x.iter()
        .zip(y)
        .filter(|(x, _)| x.is_finite() && (!log || **x > 0.0))
        .map(|(x, y)| {
            let v = y * scale;
            (round(*x), v.is_finite().then(|| round(v)))
        })
        .unzip()
}

fn freq_panel(title: &str, ylabel: &str, yunit: &str) -> ChartPanel {
    ChartPanel {
        title: title.into(),
        xlog: true,
        xlabel: "frequency / Hz".into(),
        xunit: "Hz".into(),
        xname: "frequency".into(),
        ylabel: ylabel.into(),
        yunit: yunit.into(),
        ..ChartPanel::default()
    }
}

fn time_panel(title: &str, ylabel: &str, yunit: &str) -> ChartPanel {
    ChartPanel {
        title: title.into(),
        xlabel: "time / s".into(),
        xunit: "s".into(),
        xname: "time".into(),
        ylabel: ylabel.into(),
        yunit: yunit.into(),
        ..ChartPanel::default()
    }
}

#[allow(clippy::too_many_arguments)]
fn series(
    name: &str,
    label: &str,
    x: &[f64],
    y: &[f64],
    scale: f64,
    log: bool,
    color: &str,
    dots: bool,
) -> ChartSeries {
    let (x, y) = xy(x, y, scale, log);
    ChartSeries {
        name: name.into(),
        label: label.into(),
        x,
        y,
        color: color.into(),
        dots,
        ..ChartSeries::default()
    }
}

fn level(y: f64, label: String, cls: &str) -> ChartLevel {
    ChartLevel {
        y,
        name: String::new(),
        label,
        cls: cls.into(),
        norange: false,
    }
}

/// The measured FRF: magnitude, phase (used lines in colour, excluded grey,
/// the fitted model) and coherence.
pub fn frf_chart(plot: &FrfPlot) -> FigureChart {
    let unit = if plot.input_unit.is_empty() {
        "N m"
    } else {
        plot.input_unit.as_str()
    };
    let m = &plot.measured;
    let pick = |v: &[f64], keep: bool| -> Vec<f64> {
        v.iter()
            .enumerate()
            .map(|(i, v)| {
                if plot.usable.get(i).copied().unwrap_or(false) == keep {
                    *v
                } else {
                    f64::NAN
                }
            })
            .collect()
    };
    let bode = |panel: Panel| {
        let (values, model, title, ylabel, yunit): (&[f64], &[f64], String, String, &str) =
            match panel {
                Panel::Magnitude => (
                    &m.magnitude_db,
                    &plot.model.magnitude_db,
                    format!("Magnitude, dB re 1 rad/({unit})"),
                    format!("magnitude / dB re 1 rad/({unit})"),
                    "dB",
                ),
                Panel::Phase => (
                    &m.phase_deg,
                    &plot.model.phase_deg,
                    "Phase".into(),
                    "phase / deg".into(),
                    "deg",
                ),
            };
        let mut excluded = series(
            "measured-excluded",
            "excluded lines (noisy or outside the band)",
            &m.freq_hz,
            &pick(values, false),
            1.0,
            true,
            GREY,
            true,
        );
        excluded.norange = true;
        ChartPanel {
            series: vec![
                excluded,
                series(
                    "measured",
                    "measured, used by the fit",
                    &m.freq_hz,
                    &pick(values, true),
                    1.0,
                    true,
                    PALETTE[0],
                    true,
                ),
                series(
                    "model",
                    &plot.model.label,
                    &plot.model.freq_hz,
                    model,
                    1.0,
                    true,
                    PALETTE[1],
                    false,
                ),
            ],
            vlines: markers(&plot.markers, panel == Panel::Magnitude),
            ..freq_panel(&title, &ylabel, yunit)
        }
    };
    let coherence = ChartPanel {
        series: vec![
            ChartSeries {
                norange: true,
                ..series(
                    "coherence-excluded",
                    "coherence, excluded lines",
                    &m.freq_hz,
                    &pick(&plot.coherence, false),
                    1.0,
                    true,
                    GREY,
                    true,
                )
            },
            series(
                "coherence",
                "coherence, used lines",
                &m.freq_hz,
                &pick(&plot.coherence, true),
                1.0,
                true,
                PALETTE[2],
                true,
            ),
        ],
        hlines: vec![
            level(0.0, String::new(), ""),
            level(1.0, String::new(), "ref"),
        ],
        vlines: markers(&plot.markers, false),
        ..freq_panel("Coherence (0..1)", "coherence", "")
    };
    FigureChart {
        figure_id: "frf".into(),
        panels: vec![bode(Panel::Magnitude), bode(Panel::Phase), coherence],
    }
}

fn markers(m: &[super::FrequencyMarker], labelled: bool) -> Vec<ChartMarker> {
    m.iter()
        .enumerate()
        .map(|(i, m)| ChartMarker {
            x: m.freq_hz,
            name: format!("marker-{i}"),
            label: if labelled {
                m.label.clone()
            } else {
                String::new()
            },
            cls: "ref".into(),
        })
        .collect()
}

/// A Bode plot: magnitude (and phase unless magnitude only) with its markers,
/// reference lines (labelled, but 0 dB / 0 deg) and margin points.
pub fn bode_chart(figure_id: &str, plot: &BodePlot) -> FigureChart {
    let panel = |p: Panel| {
        let (title, ylabel, yunit, lines) = match p {
            Panel::Magnitude => (
                "Magnitude",
                "magnitude / dB",
                "dB",
                &plot.magnitude_lines_db,
            ),
            Panel::Phase => ("Phase", "phase / deg", "deg", &plot.phase_lines_deg),
        };
        ChartPanel {
            series: plot
                .curves
                .iter()
                .enumerate()
                .map(|(i, c)| {
                    let v = match p {
                        Panel::Magnitude => &c.magnitude_db,
                        Panel::Phase => &c.phase_deg,
                    };
                    ChartSeries {
                        dashed: c.dashed,
                        ..series(
                            &format!("curve-{i}"),
                            &c.label,
                            &c.freq_hz,
                            v,
                            1.0,
                            true,
                            PALETTE[c.color_index.unwrap_or(i) % PALETTE.len()],
                            c.dots,
                        )
                    }
                })
                .collect(),
            vlines: markers(&plot.markers, p == Panel::Magnitude),
            hlines: lines
                .iter()
                .map(|h| {
                    let label = if *h == 0.0 {
                        String::new()
                    } else {
                        format!("{h} {yunit}")
                    };
                    level(*h, label, if *h == 0.0 { "" } else { "ref" })
                })
                .collect(),
            points: plot
                .points
                .iter()
                .filter(|q| q.panel == p)
                .map(|q| ChartPoint {
                    x: q.freq_hz,
                    y: q.value,
                    label: q.label.clone(),
                })
                .collect(),
            ..freq_panel(title, ylabel, yunit)
        }
    };
    let mut panels = vec![panel(Panel::Magnitude)];
    if !plot.magnitude_only {
        panels.push(panel(Panel::Phase));
    }
    FigureChart {
        figure_id: figure_id.into(),
        panels,
    }
}

/// The validation moves: desired position, cart errors (all moves and the
/// delivered one on its own scale) with the 1 mm limit, motor-side errors,
/// torque with its limit; one colour per move, as in the SVG.
pub fn moves_chart(moves: &[MovePlot], torque_limit_nm: Option<f64>) -> FigureChart {
    let color = |i: usize| PALETTE[i % PALETTE.len()];
    let limit_mm = crate::verdict::MAX_TRACKING_ERROR_M * 1e3;
    let limits = |norange: bool| {
        [1.0, -1.0]
            .iter()
            .map(|s| ChartLevel {
                y: s * limit_mm,
                name: "limit".into(),
                label: format!("limit {:+} mm", s * limit_mm),
                cls: "limit".into(),
                norange,
            })
            .collect::<Vec<_>>()
    };
    let of = |name: &str, f: &dyn Fn(&MovePlot) -> &[f64], scale: f64| -> Vec<ChartSeries> {
        moves
            .iter()
            .enumerate()
            .filter(|(_, m)| !f(m).is_empty())
            .map(|(i, m)| {
                series(
                    &format!("{name}-{i}"),
                    &m.label,
                    &m.time_s,
                    f(m),
                    scale,
                    false,
                    color(i),
                    false,
                )
            })
            .collect()
    };
    let mut panels = Vec::new();
    if let Some(m) = moves.first() {
        panels.push(ChartPanel {
            series: vec![series(
                "desired",
                "desired position",
                &m.time_s,
                &m.desired_m,
                1e3,
                false,
                BLACK,
                false,
            )],
            ..time_panel("Desired cart position", "position / mm", "mm")
        });
    }
    let cart = of("cart-error", &|m| &m.cart_error_m, 1e3);
    if cart.len() > 1 {
        panels.push(ChartPanel {
            series: cart.clone(),
            hlines: limits(false),
            ..time_panel("Cart tracking error, every move", "cart error / mm", "mm")
        });
    }
    if let Some(last) = cart.last() {
        // the delivered controller on its own scale: a far limit is not drawn
        panels.push(ChartPanel {
            series: vec![last.clone()],
            hlines: limits(true),
            ..time_panel(
                "Cart tracking error, delivered controller",
                "cart error / mm",
                "mm",
            )
        });
    }
    let motor = of("motor-error", &|m| &m.motor_error_m, 1e3);
    if !motor.is_empty() {
        panels.push(ChartPanel {
            series: motor,
            ..time_panel("Motor-side tracking error", "motor-side error / mm", "mm")
        });
    }
    let torque = of("torque", &|m| &m.torque_nm, 1.0);
    if !torque.is_empty() {
        panels.push(ChartPanel {
            series: torque,
            hlines: torque_limit_nm
                .map(|t| {
                    vec![
                        level(t, format!("torque limit {t:.2} N m"), "limit"),
                        level(-t, format!("torque limit -{t:.2} N m"), "limit"),
                    ]
                })
                .unwrap_or_default(),
            ..time_panel("Torque command", "torque / N m", "N m")
        });
    }
    FigureChart {
        figure_id: "moves".into(),
        panels,
    }
}

/// The interactive charts of a report, one per figure that has one (the
/// identification experiment, friction and trends stay SVG only).
pub fn report_charts(report: &Report) -> Vec<FigureChart> {
    let mut out = Vec::new();
    if let Some(frf) = &report.frf {
        out.push(frf_chart(frf));
    }
    if let Some(c) = &report.controller {
        out.push(bode_chart("controller", c));
    }
    for (i, p) in report.open_loops.iter().enumerate() {
        out.push(bode_chart(&format!("open-loop-{i}"), p));
    }
    for (i, p) in report.closed_loops.iter().enumerate() {
        out.push(bode_chart(&format!("closed-loop-{i}"), p));
    }
    for (i, p) in report.overlays.iter().enumerate() {
        out.push(bode_chart(&format!("overlay-{i}"), p));
    }
    if !report.moves.is_empty() {
        let limit = report.excitation.as_ref().map(|e| e.torque_limit_nm);
        out.push(moves_chart(&report.moves, limit));
    }
    out.retain(|c| c.panels.iter().any(|p| !p.series.is_empty()));
    out
}

/// `charts` as JSON that is safe inside a `<script type="application/json">`
/// element (no `<`, so no `</script>`; no `&`).
pub fn charts_json(charts: &[FigureChart]) -> crate::Result<String> {
    let text = serde_json::to_string(charts).map_err(|e| crate::Error::Report {
        reason: e.to_string(),
    })?;
    Ok(text
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::{BodeCurve, FrequencyMarker};

    /// Rounding keeps 6 significant digits (the relative error of a plotted
    /// value is at most 5e-6, far below a pixel of a 1000 px plot).
    #[test]
    fn values_keep_six_significant_digits() {
        for v in [
            std::f64::consts::PI,
            -1234.56789,
            1.23456789e-7,
            987654321.0,
        ] {
            let r = round(v);
            assert!(((r - v) / v).abs() <= 5e-6, "{v} -> {r}");
            assert!(format!("{r:e}").len() <= "-1.23456e-7".len() + 1, "{r:e}");
        }
    }

    /// A label with `</script>` cannot end the script element it sits in, and
    /// the JSON still parses back to the same text.
    #[test]
    fn json_cannot_close_its_script_element() {
        let plot = BodePlot {
            curves: vec![BodeCurve {
                label: "</script><b>&".into(),
                freq_hz: vec![1.0, 10.0],
                magnitude_db: vec![0.0, -20.0],
                phase_deg: vec![-90.0, f64::NAN],
                ..BodeCurve::default()
            }],
            markers: vec![FrequencyMarker {
                label: "f_r 7.6 Hz".into(),
                freq_hz: 7.6,
            }],
            ..BodePlot::default()
        };
        let charts = vec![bode_chart("x", &plot)];
        let text = charts_json(&charts).unwrap();
        assert!(!text.contains('<') && !text.contains('&'));
        let back: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(back[0]["panels"][0]["series"][0]["label"], "</script><b>&");
        // a phase that is not a number is a gap, not a string or 0
        assert_eq!(
            back[0]["panels"][1]["series"][0]["y"][1],
            serde_json::Value::Null
        );
    }
}
