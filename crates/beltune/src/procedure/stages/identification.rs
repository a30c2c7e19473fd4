//! Stage 5: open-loop PRBS identification (thesis 3.2-3.5): one transient
//! period and the averaged periods around the holding torque, the FRF with
//! Clary's method II and coherence, the two-mass fit and the current-loop dead
//! time.

use super::super::commission::{DataSheet, ExcitationConfig};
use super::super::motion::move_to;
use super::super::result::IdentifiedModel;
use super::Stages;
use crate::ident::dead_time::{estimate_dead_time, DeadTime};
use crate::ident::etfe::{etfe, EtfeConfig, Frf};
use crate::ident::fit::{fit_two_mass, FitConfig, TwoMassFit};
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::prbs::Prbs;
use beltune_rt::trajectory::Limits;

/// Longest dead time looked for, s.
const MAX_DEAD_TIME_S: f64 = 10e-3;

/// What stage 5 hands on.
pub struct Identification {
    /// FRF from the torque command to the motor angle.
    pub frf: Frf,
    /// The two-mass fit.
    pub fit: TwoMassFit,
    /// The current-loop dead time.
    pub dead_time: DeadTime,
    /// The model summary.
    pub identified: IdentifiedModel,
    /// Time of each excitation sample since the axis was taken, s.
    pub excitation_time_s: Vec<f64>,
    /// Torque command of each sample (holding torque plus PRBS), N m.
    pub excitation_torque_nm: Vec<f64>,
    /// Motor-side position of each sample, m.
    pub excitation_position_m: Vec<f64>,
}

/// Stage 5: excite around `holding_nm` with amplitude `amplitude_nm` at
/// `center_m` (held there by `hold` between the moves) and identify.
#[allow(clippy::too_many_arguments)]
pub fn identification(
    st: &mut Stages,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    amplitude_nm: f64,
    ex: &ExcitationConfig,
    datasheet: &DataSheet,
) -> Result<Identification> {
    let ts = st.runner.info().ts_s;
    let clock = ex.clock_samples(ts);
    let mut prbs = Prbs::new(ex.prbs_order, clock, amplitude_nm)?;
    let period = prbs.period_samples() as usize;
    let n = period * (ex.periods + ex.skip_periods);
    st.start("identification (open loop)", n as u64);
    move_to(st.runner, hold, center_m, limits, 0.05)?;
    let mut cmd = Vec::with_capacity(n);
    let mut act = Vec::with_capacity(n);
    let mut ang = Vec::with_capacity(n);
    let mut pos = Vec::with_capacity(n);
    let t_start = st.runner.busy_time_s();
    for _ in 0..n {
        let tau = holding_nm + prbs.step();
        let s = st.runner.step(tau, None)?;
        cmd.push(s.torque_command_nm);
        act.push(s.torque_actual_nm);
        ang.push(s.motor_angle_rad);
        pos.push(s.position_m);
    }
    let (frf, fit, dead_time) = st.compute(|| -> Result<_> {
        // Below 0.4 f_s the PRBS spectrum and the Tustin/ZOH effects stay mild.
        let f_max = 0.4 / ts;
        let ecfg = EtfeConfig {
            ts_s: ts,
            period_samples: period,
            skip_periods: ex.skip_periods,
            integrator: true,
            band_hz: Some((ex.fit_band_min_hz, f_max.min(1.0 / (clock as f64 * ts)))),
            ..EtfeConfig::default()
        };
        let frf = etfe(&cmd, &ang, &ecfg)?;
        let frf_actual = etfe(&act, &ang, &ecfg)?;
        let fcfg = FitConfig {
            theta_e: Some(datasheet.theta_e_kg_m2),
            i_t: datasheet.i_t_m,
            n_log_lines: ex.n_log_lines,
            ..FitConfig::default()
        };
        let fit = fit_two_mass(&frf, &fcfg)?;
        let f_band = ecfg.band_hz.map(|b| b.1).unwrap_or(0.5 / ts);
        if !(fit.f_z_hz.is_finite()
            && fit.f_r_hz.is_finite()
            && fit.f_r_hz < f_band
            && fit.f_z_hz > 0.0)
        {
            return Err(Error::FitFailed {
                reason: format!(
                    "the fitted model (f_r {:.3e} Hz, f_z {:.3e} Hz) has no resonance inside the measured band up to {:.0} Hz; check the excitation and the data sheet",
                    fit.f_r_hz, fit.f_z_hz, f_band
                ),
            });
        }
        let max_dt = (MAX_DEAD_TIME_S / ts) as usize;
        let dead_time = estimate_dead_time(&frf, &frf_actual, fit.f_r_hz, max_dt)?;
        Ok((frf, fit, dead_time))
    })?;
    let identified = IdentifiedModel::from_fit(&fit, &frf, dead_time.seconds, center_m);
    let p = fit.params;
    let line = format!(
        "f_r {:.2} Hz, f_z {:.2} Hz, m_c {:.2} kg, c {:.1} kN/m, d_m {:.2} N s/m, d_c {:.2} N s/m, dead time {:.2} ms, fit {:.2} dB rms, coherence {:.3}",
        fit.f_r_hz,
        fit.f_z_hz,
        p.m_c,
        p.c / 1e3,
        p.d_m,
        p.d_c,
        dead_time.seconds * 1e3,
        fit.fit_rms_db,
        identified.mean_coherence
    );
    st.finish("identification", line);
    Ok(Identification {
        frf,
        fit,
        dead_time,
        identified,
        excitation_time_s: (0..n).map(|k| t_start + k as f64 * ts).collect(),
        excitation_torque_nm: cmd,
        excitation_position_m: pos,
    })
}
