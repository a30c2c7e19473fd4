//! The Bode plots of a design: the controller, the open loops with their
//! crossovers and margins marked, the closed loops and the sensitivities, all
//! from [`super::plot_data::loop_data`] (the numbers the tuning page shows).

use super::plot_data::{loop_data, resonance_markers, LoopData};
use super::{BodeCurve, BodePlot, FrequencyMarker, MarginPoint, Panel};
use crate::design::ControllerDesign;
use crate::Result;
use std::f64::consts::PI;

pub(super) fn hz(w_rad_s: f64) -> f64 {
    w_rad_s / (2.0 * PI)
}

/// `y(x)` interpolated linearly in `log10 x`.
fn at(c: &BodeCurve, f: f64, phase: bool) -> f64 {
    let y = if phase { &c.phase_deg } else { &c.magnitude_db };
    match c.freq_hz.iter().position(|v| *v >= f) {
        None => y.last().copied().unwrap_or(f64::NAN),
        Some(0) => y.first().copied().unwrap_or(f64::NAN),
        Some(i) => {
            let (a, b) = (c.freq_hz[i - 1].log10(), c.freq_hz[i].log10());
            let t = (f.log10() - a) / (b - a);
            y[i - 1] + t * (y[i] - y[i - 1])
        }
    }
}

/// The -180 deg line (plus whole turns) that the phase margin at `f_c` refers to.
fn minus_180_near(c: &BodeCurve, f_c_hz: f64, pm_deg: f64) -> f64 {
    let reference = at(c, f_c_hz, true) - pm_deg;
    -180.0 + 360.0 * ((reference + 180.0) / 360.0).round()
}

/// An open-loop Bode plot with 0 dB / -180 deg lines, the crossover marker and
/// the phase- and gain-margin points.
fn open_loop_plot(
    title: String,
    curve: &BodeCurve,
    m: &crate::lti::StabilityMargins,
    extra_markers: Vec<FrequencyMarker>,
) -> BodePlot {
    let f_c = hz(m.crossover_rad_s);
    let line = minus_180_near(curve, f_c, m.phase_margin_deg);
    let mut points = vec![MarginPoint {
        label: format!("PM {:.1} deg", m.phase_margin_deg),
        freq_hz: f_c,
        value: line + m.phase_margin_deg,
        panel: Panel::Phase,
    }];
    if m.gain_margin_db.is_finite() && m.phase_crossover_rad_s.is_finite() {
        points.push(MarginPoint {
            label: format!("GM {:.1} dB", m.gain_margin_db),
            freq_hz: hz(m.phase_crossover_rad_s),
            value: -m.gain_margin_db,
            panel: Panel::Magnitude,
        });
    }
    let mut markers = vec![FrequencyMarker {
        label: format!("f_c {}", hz_text(f_c)),
        freq_hz: f_c,
    }];
    markers.extend(extra_markers);
    BodePlot {
        title,
        curves: vec![curve.clone()],
        markers,
        magnitude_lines_db: vec![0.0],
        phase_lines_deg: vec![line],
        points,
        magnitude_only: false,
    }
}

/// "7.63 Hz", "0.52 Hz", "111 Hz".
pub fn hz_text(f: f64) -> String {
    if f >= 100.0 {
        format!("{f:.0} Hz")
    } else if f >= 1.0 {
        format!("{f:.1} Hz")
    } else {
        format!("{f:.2} Hz")
    }
}

/// Controller, open loops, closed loops and sensitivities of a design, from
/// [`loop_data`] (the same numbers the tuning page shows).
pub struct LoopPlots {
    /// The loop data the plots are drawn from.
    pub data: LoopData,
    /// `G_pre G_PI`.
    pub controller: BodePlot,
    /// Velocity and position open loops.
    pub open_loops: Vec<BodePlot>,
    /// Closed loops and sensitivities (magnitude).
    pub closed_loops: Vec<BodePlot>,
}

/// The loop plots of `des` with resonance markers at `f_z_hz`, `f_r_hz`.
pub fn loop_plots(des: &ControllerDesign, f_z_hz: f64, f_r_hz: f64) -> Result<LoopPlots> {
    let data = loop_data(des)?;
    let vm = &des.velocity_margins;
    let pm = &des.position_margins;
    let f_r = FrequencyMarker {
        label: format!("f_r {}", hz_text(f_r_hz)),
        freq_hz: f_r_hz,
    };
    let mut controller_markers = resonance_markers(f_z_hz, f_r_hz);
    // the prefilter's corner (Butterworth cut-off; a notch sits at its centre frequency)
    match des.prefilter {
        crate::design::Prefilter::Butterworth { omega_bw_rad_s } => {
            controller_markers.push(FrequencyMarker {
                label: format!("filter corner f_bw {}", hz_text(hz(omega_bw_rad_s))),
                freq_hz: hz(omega_bw_rad_s),
            })
        }
        crate::design::Prefilter::Notch { omega_r_rad_s, .. } => {
            controller_markers.push(FrequencyMarker {
                label: format!("notch {}", hz_text(hz(omega_r_rad_s))),
                freq_hz: hz(omega_r_rad_s),
            })
        }
        crate::design::Prefilter::None => {}
    }
    let controller = BodePlot {
        title: "Controller G_pre G_PI (velocity error -> torque)".into(),
        curves: vec![data.controller.clone()],
        markers: controller_markers,
        ..BodePlot::default()
    };
    let open_loops = vec![
        open_loop_plot(
            format!(
                "Velocity open loop: crossover {}, phase margin {:.1} deg, gain margin {:.1} dB, {:.1} dB at f_r",
                hz_text(hz(vm.crossover_rad_s)),
                vm.phase_margin_deg,
                vm.gain_margin_db,
                des.gain_at_resonance_db
            ),
            &data.velocity_open_loop,
            vm,
            vec![f_r.clone()],
        ),
        open_loop_plot(
            format!(
                "Position open loop: crossover {}, phase margin {:.1} deg",
                hz_text(hz(pm.crossover_rad_s)),
                pm.phase_margin_deg
            ),
            &data.position_open_loop,
            pm,
            vec![],
        ),
    ];
    let closed_loops = vec![
        BodePlot {
            title: "Closed loops (reference -> output), magnitude".into(),
            curves: vec![
                data.velocity_closed_loop.clone(),
                data.position_closed_loop.clone(),
            ],
            markers: vec![f_r.clone()],
            magnitude_lines_db: vec![0.0, -3.0],
            magnitude_only: true,
            ..BodePlot::default()
        },
        BodePlot {
            title: "Sensitivity 1/(1+L) (disturbance -> error), magnitude; 6 dB is the usual limit"
                .into(),
            curves: vec![
                data.velocity_sensitivity.clone(),
                data.position_sensitivity.clone(),
            ],
            markers: vec![f_r],
            magnitude_lines_db: vec![0.0, 6.0],
            magnitude_only: true,
            ..BodePlot::default()
        },
    ];
    Ok(LoopPlots {
        data,
        controller,
        open_loops,
        closed_loops,
    })
}
