//! Commissioning from data recorded on a real drive instead of a plant: the
//! identification comes from a logged periodic excitation (CSV, see
//! [`crate::ident::recorded`]), friction optionally from a logged motion, then
//! the design. The stages that need the axis (positioning, holding torque,
//! amplitude search, friction runs, validation moves) are skipped and say so.

use super::CommissioningConfig;
use crate::design::robust::{design_identified, GuaranteedMargins};
use crate::design::{ControllerDesign, DesignInput};
use crate::ident::{MotionFriction, RecordedIdentification};
use crate::record::model::{FrictionResult, IdentifiedModel, DEFAULT_DEAD_TIME_S};
use crate::verdict::Verdict;
use crate::{Error, Result};
use std::time::Instant;

/// What a recorded commissioning produced.
#[derive(Clone, Debug)]
pub struct RecordedCommissioning {
    /// The identification from the record.
    pub identification: RecordedIdentification,
    /// The model summary.
    pub identified: IdentifiedModel,
    /// Friction from the motion record (motor angle in rad, torque in N m), if given.
    pub friction: Option<FrictionResult>,
    /// The design.
    pub design: ControllerDesign,
    /// Its margins over the identification's uncertainty.
    pub guaranteed: GuaranteedMargins,
    /// The verdict: not validated (no move), its design checks.
    pub verdict: Verdict,
    /// Duration of the excitation record, s.
    pub record_time_s: f64,
    /// Computation time, s.
    pub computation_time_s: f64,
    /// One line per stage, including the skipped ones.
    pub log: Vec<String>,
}

/// Design from a recorded identification and, optionally, a friction
/// regression on a recorded motion of the motor angle (rad) under a torque
/// (N m), for a drive with the torque limit `torque_max_nm` (in the record's
/// units), with the knobs, design rule, `T_R` and limits of `cfg`.
pub fn commission_recorded(
    identification: RecordedIdentification,
    motion_friction: Option<MotionFriction>,
    torque_max_nm: f64,
    cfg: &CommissioningConfig,
) -> Result<RecordedCommissioning> {
    crate::error::require_positive("torque limit", torque_max_nm)?;
    let t0 = Instant::now();
    let fit = &identification.fit;
    let p = fit.params;
    let (dead_time_s, dead_line) = match identification.dead_time {
        Some(d) => (
            d.seconds,
            format!("{:.2} ms from the actual torque", d.seconds * 1e3),
        ),
        None => (
            DEFAULT_DEAD_TIME_S,
            format!(
                "no actual-torque column: {:.1} ms assumed (thesis 3.30)",
                DEFAULT_DEAD_TIME_S * 1e3
            ),
        ),
    };
    let t_r_s = cfg.t_r_s;
    let friction = motion_friction.map(|m| FrictionResult {
        viscous_nm_s_per_rad: m.viscous.max(0.0),
        coulomb_nm: m.coulomb.max(0.0),
        linear_viscous_nm_s_per_rad: m.viscous.max(0.0),
        relative_residual: m.relative_residual,
        holding_torque_nm: m.offset,
        cart_coulomb_n: 0.0,
        cart_viscous_n_s_per_m: 0.0,
    });
    let input = DesignInput {
        model: p,
        dead_time_s,
        t_r_s,
        ts_s: identification.ts_s,
        friction: friction.as_ref().map(FrictionResult::params),
    };
    if let Some(f) = &friction {
        for (name, v) in [
            ("Coulomb friction", f.coulomb_nm),
            ("holding torque", f.holding_torque_nm),
        ] {
            if !(v.is_finite() && v.abs() <= torque_max_nm) {
                return Err(Error::invalid(
                    name,
                    v,
                    format!(
                        "the friction record's fitted {name} exceeds the torque limit \
                         {torque_max_nm}; check the friction record's units"
                    ),
                ));
            }
        }
    }
    let robust = design_identified(
        &input,
        friction.as_ref().map(|f| f.viscous_nm_s_per_rad),
        fit.m_c_sigma(),
        fit.c_sigma(),
        None,
        &cfg.knobs,
        cfg.design_rule,
    )?;
    let des = robust.design;
    let mut identified = IdentifiedModel::from_fit(fit, &identification.frf, dead_time_s, f64::NAN);
    identified.dead_time_measured = identification.dead_time.is_some();
    identified.ts_s = Some(identification.ts_s);
    identified.t_r_s = t_r_s;
    identified.torque_max_nm = Some(torque_max_nm);
    let mean_coherence = identified.mean_coherence;
    let skipped = "skipped (recorded data, no axis)";
    let mut log = vec![
        format!("plausibility, positioning, holding torque, excitation amplitude: {skipped}"),
        format!("identification strategy: {}", identification.method.words()),
        format!(
            "identification: f_r {:.2} Hz, f_z {:.2} Hz, m_c {:.4e}, c {:.4e}, fit {:.2} dB rms over {} lines, coherence {:.3}; dead time {dead_line}",
            fit.f_r_hz, fit.f_z_hz, p.m_c, p.c, fit.fit_rms_db, fit.n_lines, mean_coherence
        ),
        format!(
            "design: K_P {:.4e}, K_I {:.4e}, K_PP {:.3}; phase margins {:.1} / {:.1} deg",
            des.k_p,
            des.k_i,
            des.k_pp,
            des.velocity_margins.phase_margin_deg,
            des.position_margins.phase_margin_deg
        ),
    ];
    log.push(match &friction {
        Some(f) => format!(
            "friction (from the motion record): d_v {:.4e}, tau_c {:.4e}, offset {:.4e}, relative residual {:.3}",
            f.viscous_nm_s_per_rad, f.coulomb_nm, f.holding_torque_nm, f.relative_residual
        ),
        None => format!("friction: {skipped}: no motion record given"),
    });
    log.push(format!("validation moves: {skipped}"));
    let verdict = crate::verdict::judge(&crate::verdict::VerdictInput {
        limits: &cfg.limits,
        validation: None,
        guaranteed: Some(&robust.guaranteed),
        design: &des,
        identified: Some(&identified),
        controller_file: crate::record::CONTROLLER_FILE,
    });
    log.push(format!("verdict: {}", verdict.text()));
    let record_time_s = identification.rows as f64 * identification.ts_s;
    Ok(RecordedCommissioning {
        identification,
        identified,
        friction,
        design: des,
        guaranteed: robust.guaranteed,
        verdict,
        record_time_s,
        computation_time_s: t0.elapsed().as_secs_f64(),
        log,
    })
}
