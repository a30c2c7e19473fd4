//! The controller used before anything is identified: a slow rigid-body P-PI
//! cascade from the data-sheet inertia, for the positioning moves, the holding
//! torque and the safety stops of the early stages.
//!
//! For a rigid inertia `J` with ideal velocity measurement, `K_P = J w_c` puts
//! the velocity-loop crossover at `w_c`; the PI zero at `w_c / 4` costs 14 deg
//! of phase, the Butterworth low-pass at `4 w_c` about 20 deg, dead time and
//! `G_R` a few more: about 50 deg phase margin. `K_PP = w_c / 5` keeps the
//! position loop well inside the velocity loop. The low-pass keeps the
//! unidentified belt resonance (typically near 100 Hz, thesis 2.2) far below
//! 0 dB: with `w_c = 2 pi 4 Hz` it attenuates 100 Hz by 44 dB. The crossover
//! grows for light axes (see [`bootstrap_crossover_rad_s`]) up to 10 Hz.

use crate::error::require_positive;
use crate::Result;
use beltune_rt::control::{AntiWindup, CascadeConfig, CascadeGains, Feedforward};
use beltune_rt::filter::{butterworth_lowpass, SosCoeffs};

/// Lowest crossover of the bootstrap velocity loop, Hz.
pub const BOOTSTRAP_CROSSOVER_MIN_HZ: f64 = 4.0;
/// Highest crossover of the bootstrap velocity loop, Hz (well below the
/// antiresonance of any belt axis the thesis considers, 2.2).
pub const BOOTSTRAP_CROSSOVER_MAX_HZ: f64 = 10.0;
/// Friction assumed before it is identified, as a fraction of the torque limit
/// (EGC-70: 0.125 N m of 3.1 N m = 4 %).
pub const FRICTION_GUESS_FRACTION: f64 = 0.05;
/// Following error the bootstrap loop may show when friction breaks away, m.
pub const BREAKAWAY_ERROR_M: f64 = 5e-3;
/// Largest shift of the PI zero by the plant's damping pole `d / J`, as a
/// fraction of the crossover (see [`bootstrap_with_friction`]).
pub const BOOTSTRAP_ZERO_MAX: f64 = 0.5;

/// The crossover: a friction step `tau_f` makes a following error of about
/// `tau_f / (J w_c^2)`; a light axis therefore needs a faster loop than a heavy
/// one. `w_c = sqrt(tau_f i_t / (J e))`, clamped to the bounds above.
pub fn bootstrap_crossover_rad_s(j_kg_m2: f64, i_t_m: f64, torque_max_nm: f64) -> f64 {
    let tau_f = FRICTION_GUESS_FRACTION * torque_max_nm;
    let w = (tau_f * i_t_m / (j_kg_m2 * BREAKAWAY_ERROR_M)).sqrt();
    let two_pi = 2.0 * std::f64::consts::PI;
    w.clamp(
        two_pi * BOOTSTRAP_CROSSOVER_MIN_HZ,
        two_pi * BOOTSTRAP_CROSSOVER_MAX_HZ,
    )
}

/// The bootstrap cascade for a rigid-body inertia `j_kg_m2` (data sheet:
/// `Theta_e + i_t^2 m_c`) and transmission `i_t_m`, before any friction is
/// known (viscous friction taken as zero).
pub fn bootstrap_controller(
    j_kg_m2: f64,
    i_t_m: f64,
    ts_s: f64,
    torque_max_nm: f64,
) -> Result<CascadeConfig<f64>> {
    bootstrap_with_friction(j_kg_m2, i_t_m, ts_s, torque_max_nm, 0.0)
}

/// The bootstrap cascade for an axis whose viscous friction at the motor,
/// `viscous_nm_s_per_rad` (N m s/rad), has been measured (the holding-torque
/// runs at two speeds). On the damped rigid body `1 / (J s + d)` the PI
/// zero moves up by the plant's pole `d / J`: the open velocity loop is then
/// `K_P (s + w_c / 4 + d / J) / (J s (s + d / J))`, which for `d = 0` is the
/// loop above and for a heavily damped axis stays close to `K_P / (J s)`
/// (crossover `w_c`, phase -90 deg) instead of a velocity loop whose gain
/// sinks to `K_P / d` below the crossover (on sim-b, where
/// `d / J = 155 rad/s` is 3.5 times the crossover, the position loop lagged
/// and overshot its target by 50 mm). The viscous friction is fed forward
/// with the inertia.
pub fn bootstrap_with_friction(
    j_kg_m2: f64,
    i_t_m: f64,
    ts_s: f64,
    torque_max_nm: f64,
    viscous_nm_s_per_rad: f64,
) -> Result<CascadeConfig<f64>> {
    let j = require_positive("rigid inertia [kg m^2]", j_kg_m2)?;
    require_positive("i_t [m/rad]", i_t_m)?;
    require_positive("torque limit [N m]", torque_max_nm)?;
    bootstrap_at_crossover(
        j,
        i_t_m,
        ts_s,
        torque_max_nm,
        viscous_nm_s_per_rad,
        bootstrap_crossover_rad_s(j, i_t_m, torque_max_nm),
    )
}

/// [`bootstrap_with_friction`] with the velocity-loop crossover `w_c_rad_s`
/// given (rad/s; [`super::bootstrap_margin::bootstrap_for_data_sheet`]
/// lowers it for the resonances the data sheet allows).
pub fn bootstrap_at_crossover(
    j_kg_m2: f64,
    i_t_m: f64,
    ts_s: f64,
    torque_max_nm: f64,
    viscous_nm_s_per_rad: f64,
    w_c_rad_s: f64,
) -> Result<CascadeConfig<f64>> {
    let j = require_positive("rigid inertia [kg m^2]", j_kg_m2)?;
    require_positive("i_t [m/rad]", i_t_m)?;
    require_positive("torque limit [N m]", torque_max_nm)?;
    let w_c = require_positive("bootstrap crossover [rad/s]", w_c_rad_s)?;
    let d =
        crate::error::require_non_negative("viscous friction [N m s/rad]", viscous_nm_s_per_rad)?;
    let k_p = j * w_c;
    // The PI zero follows the plant's pole at most up to BOOTSTRAP_ZERO_MAX
    // times the crossover: an overestimated damping (Coulomb friction taken
    // for viscous on a light axis) would otherwise put the zero above the
    // crossover of an undamped plant, `K_P (s + z) / (J s^2)`, with too
    // little phase left.
    let zero = w_c / 4.0 + (d / j).min(BOOTSTRAP_ZERO_MAX * w_c);
    let gains = CascadeGains::new(w_c / 5.0, k_p, k_p * zero);
    let mut cfg = CascadeConfig::new(gains, ts_s, crate::design::DEFAULT_T_R_S, torque_max_nm)?;
    cfg.prefilter = [butterworth_lowpass(4.0 * w_c, ts_s)?, SosCoeffs::IDENTITY];
    cfg.anti_windup = AntiWindup::ConditionalIntegration;
    // The data-sheet inertia is known: accelerate it by feedforward (4.16),
    // with the viscous friction as far as it is known.
    cfg.feedforward = Feedforward::linear(j, d);
    Ok(cfg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commission::motion::{move_to, TrackRecord};
    use crate::commission::progress::NoProgress;
    use crate::commission::runner::Runner;
    use crate::commission::safety::{SafetyLimits, SafetySupervisor};
    use crate::model::rigs;
    use crate::sim::{SimAxis, SimConfig};

    /// Move sim-b (viscous friction 0.031 N m s/rad on 2e-4 kg m^2) 0.45 m at
    /// the positioning limits with `ctrl`; the largest following error, m.
    fn sim_b_move(viscous_nm_s_per_rad: f64) -> crate::Result<f64> {
        let plant = rigs::builtin("sim-b", None).unwrap();
        let info = plant.info();
        let truth = plant.worst_case_two_mass().unwrap();
        let start = 0.05;
        let mut axis = SimAxis::new(
            &plant,
            SimConfig {
                initial_cart_position_m: Some(start),
                ..SimConfig::default()
            },
        )?;
        let (j, i_t) = (truth.rigid_inertia(), truth.i_t);
        let ctrl =
            bootstrap_with_friction(j, i_t, info.ts_s, info.torque_max_nm, viscous_nm_s_per_rad)?;
        let limits = crate::commission::config::positioning_limits_in(-0.01, 0.57);
        let sup = SafetySupervisor::new(
            SafetyLimits {
                travel_min_m: -0.01,
                travel_max_m: 0.57,
                torque_max_nm: info.torque_max_nm,
                velocity_max_m_s: 2.5,
                following_error_max_m: 0.05,
            },
            5.0,
        )?;
        let mut progress = NoProgress;
        let mut runner = Runner::new(&mut axis, &mut progress, sup, i_t, start, ctrl, limits)?;
        let rec: TrackRecord = move_to(&mut runner, &ctrl, 0.5, &limits, 0.3)?;
        Ok(rec
            .desired_m
            .iter()
            .zip(&rec.samples)
            .map(|(d, s)| (d - s.position_m).abs())
            .fold(0.0, f64::max))
    }

    /// Sim-b's bootstrap loop without its viscous friction overshot
    /// the worst-case position by 50 mm (a following-error stop); with the
    /// friction measured (the plant's own 0.0308 N m s/rad, here from the
    /// truth) the following error stays within a few millimetres, a tenth
    /// of the limit.
    #[test]
    fn the_bootstrap_fits_heavy_viscous_friction() {
        let d = rigs::builtin("sim-b", None)
            .unwrap()
            .friction_totals()
            .viscous_nm_s_per_rad;
        assert!(matches!(
            sim_b_move(0.0),
            Err(crate::Error::SafetyStop { .. })
        ));
        let e = sim_b_move(d).unwrap();
        assert!(e < 5e-3, "following error {e} m");
        assert!(bootstrap_with_friction(1e-4, 0.0124, 1e-4, 3.1, -1.0).is_err());
    }
}
