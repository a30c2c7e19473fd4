//! Stage 1: plausibility of the data-sheet values, and what the later stages
//! need from them before the axis moves: the safety supervisor, the stop
//! limits and the bootstrap controller (designed from the data sheet alone).

use super::super::bootstrap_margin::bootstrap_for_data_sheet;
use super::super::safety::{
    SafetyLimits, SafetySupervisor, StopCapability, STOP_JERK_PER_DECELERATION,
};
use super::super::{positioning_limits, CommissioningConfig, DataSheet};
use crate::axis::AxisInfo;
use crate::Result;
use beltune_rt::control::CascadeConfig;
use beltune_rt::trajectory::Limits;

/// What stage 1 hands on.
pub struct Plausibility {
    /// Torque limit of the commissioning: the smaller of the data sheet's and
    /// the axis', N m.
    pub torque_max_nm: f64,
    /// Rigid-body inertia from the data sheet, kg m^2.
    pub rigid_inertia_kg_m2: f64,
    /// The supervisor for all later stages.
    pub supervisor: SafetySupervisor,
    /// The bootstrap controller (data-sheet inertia, no offset yet).
    pub bootstrap: CascadeConfig<f64>,
    /// Limits of the supervisor's stop trajectory.
    pub stop_limits: Limits,
    /// The stage's log line.
    pub line: String,
}

/// Stage 1: validate the data sheet and derive the supervisor, the stop
/// limits and the bootstrap controller.
pub fn plausibility(
    info: &AxisInfo,
    datasheet: &DataSheet,
    cfg: &CommissioningConfig,
) -> Result<Plausibility> {
    datasheet.validate()?;
    let ts = info.ts_s;
    let torque_max = datasheet.torque_max_nm.min(info.torque_max_nm);
    let j_ds = datasheet.rigid_inertia();
    let limits = SafetyLimits {
        travel_min_m: datasheet.travel_min_m,
        travel_max_m: datasheet.travel_max_m,
        torque_max_nm: torque_max,
        velocity_max_m_s: datasheet.velocity_max_m_s,
        following_error_max_m: cfg.following_error_max_m,
    };
    // Stop deceleration: what 60 % of the torque limit gives on the data-sheet
    // inertia, at most 20 m/s^2; gravity and friction are not known yet (the
    // later stages replace it with what the axis really has).
    let capability = StopCapability::from_axis(torque_max, j_ds, datasheet.i_t_m, 0.0, 0.0)?;
    let a_stop = capability.worst_deceleration_m_s2();
    let supervisor = SafetySupervisor::with_capability(limits, capability)?;
    let (bootstrap, band_margins) = bootstrap_for_data_sheet(datasheet, ts, torque_max, 0.0)?;
    let stop_limits = Limits {
        a_max: a_stop,
        a_min: -a_stop,
        j_max: STOP_JERK_PER_DECELERATION * a_stop,
        j_min: -STOP_JERK_PER_DECELERATION * a_stop,
        ..positioning_limits(datasheet)
    };
    let mut line = format!(
        "data sheet ok: Theta_e {:.2} kg mm^2, i_t {:.3} mm/rad, rigid inertia {:.3e} kg m^2, torque limit {:.2} N m, travel [{:.0}, {:.0}] mm",
        datasheet.theta_e_kg_m2 * 1e6,
        datasheet.i_t_m * 1e3,
        j_ds,
        torque_max,
        datasheet.travel_min_m * 1e3,
        datasheet.travel_max_m * 1e3
    );
    let rule_hz =
        super::super::bootstrap::bootstrap_crossover_rad_s(j_ds, datasheet.i_t_m, torque_max)
            / (2.0 * std::f64::consts::PI);
    // said where the band changed the loop or the loop cannot keep its margins
    let band = band_margins.filter(|m| !m.kept() || m.crossover_hz < rule_hz * (1.0 - 1e-9));
    if let (Some(m), Some([lo, hi])) = (band, datasheet.antiresonance_band_hz) {
        line.push_str(&format!(
            "; bootstrap loop lowered to {:.2} Hz: gain margin {:.1} dB, phase margin {:.0} deg over f_z {:.1}-{:.0} Hz",
            m.crossover_hz, m.gain_margin_db, m.phase_margin_deg, lo, hi
        ));
    }
    Ok(Plausibility {
        torque_max_nm: torque_max,
        rigid_inertia_kg_m2: j_ds,
        supervisor,
        bootstrap,
        stop_limits,
        line,
    })
}
