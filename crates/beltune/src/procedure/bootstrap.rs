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
/// Velocity-filter time constant `T_R`, s (Table A.4).
pub const T_R_S: f64 = 2e-3;

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
/// `Theta_e + i_t^2 m_c`) and transmission `i_t_m`.
pub fn bootstrap_controller(
    j_kg_m2: f64,
    i_t_m: f64,
    ts_s: f64,
    torque_max_nm: f64,
) -> Result<CascadeConfig<f64>> {
    let j = require_positive("rigid inertia [kg m^2]", j_kg_m2)?;
    require_positive("i_t [m/rad]", i_t_m)?;
    require_positive("torque limit [N m]", torque_max_nm)?;
    let w_c = bootstrap_crossover_rad_s(j, i_t_m, torque_max_nm);
    let k_p = j * w_c;
    let gains = CascadeGains::new(w_c / 5.0, k_p, k_p * w_c / 4.0);
    let mut cfg = CascadeConfig::new(gains, ts_s, T_R_S, torque_max_nm)?;
    cfg.prefilter = [butterworth_lowpass(4.0 * w_c, ts_s)?, SosCoeffs::IDENTITY];
    cfg.anti_windup = AntiWindup::ConditionalIntegration;
    // The data-sheet inertia is known: accelerate it by feedforward (4.16),
    // friction is not known yet.
    cfg.feedforward = Feedforward::linear(j, 0.0);
    Ok(cfg)
}
