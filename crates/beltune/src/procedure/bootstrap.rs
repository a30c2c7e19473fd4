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
//! 0 dB: with `w_c = 2 pi 4 Hz` it attenuates 100 Hz by 44 dB.

use crate::error::require_positive;
use crate::Result;
use beltune_rt::control::{AntiWindup, CascadeConfig, CascadeGains};
use beltune_rt::filter::{butterworth_lowpass, SosCoeffs};

/// Crossover of the bootstrap velocity loop, Hz.
pub const BOOTSTRAP_CROSSOVER_HZ: f64 = 4.0;
/// Velocity-filter time constant `T_R`, s (Table A.4).
pub const T_R_S: f64 = 2e-3;

/// The bootstrap cascade for a rigid-body inertia `j_kg_m2` (data sheet:
/// `Theta_e + i_t^2 m_c`).
pub fn bootstrap_controller(
    j_kg_m2: f64,
    ts_s: f64,
    torque_max_nm: f64,
) -> Result<CascadeConfig<f64>> {
    let j = require_positive("rigid inertia [kg m^2]", j_kg_m2)?;
    let w_c = 2.0 * std::f64::consts::PI * BOOTSTRAP_CROSSOVER_HZ;
    let k_p = j * w_c;
    let gains = CascadeGains::new(w_c / 5.0, k_p, k_p * w_c / 4.0);
    let mut cfg = CascadeConfig::new(gains, ts_s, T_R_S, torque_max_nm)?;
    cfg.prefilter = [butterworth_lowpass(4.0 * w_c, ts_s)?, SosCoeffs::IDENTITY];
    cfg.anti_windup = AntiWindup::ConditionalIntegration;
    Ok(cfg)
}
