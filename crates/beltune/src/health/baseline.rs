//! The baseline a health check compares with: a commissioning's result
//! folder, read by the one folder reader
//! ([`crate::report::folder::ResultFolder::read`]), with the uncertainty of
//! each quantity:
//!
//! - `c` and `m_c`: the identification's one-sigma values (`c_sigma`,
//!   `m_c_sigma` of the model record); along the stroke the stiffness of
//!   the commissioning's profile ([`TargetStiffness`]) with the same
//!   relative uncertainty as where it was identified;
//! - `f_r`, `f_z`: from `c` and `m_c` by (2.44), (2.45), their uncertainties
//!   propagated to first order (independent errors: the larger of the
//!   possible spreads);
//! - friction and holding torque: (3.36) with an offset refitted to the
//!   friction runs of the folder's `friction.csv`, its covariance from the
//!   residual ([`super::friction::fit_friction`]);
//! - the resonance damping: the thesis' FRF fit of the record, without an
//!   uncertainty (the record keeps none).

use super::friction::{fit_friction, FrictionEstimate};
use super::Estimate;
use crate::commission::stiffness::TargetStiffness;
use crate::ident::friction::ConstantVelocityRun;
use crate::model::TwoMassParams;
use crate::record::model::{FrictionResult, IdentifiedModel};
use crate::report::folder::ResultFolder;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// What a health check compares with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// The folder it was read from.
    pub folder: String,
    /// The axis' name in the record.
    pub plant: String,
    /// When the commissioning ran (UTC, RFC 3339), if recorded.
    pub created_utc: Option<String>,
    /// The identified model.
    pub model: IdentifiedModel,
    /// The thesis' FRF fit, if recorded (else the model).
    pub frf_fit: TwoMassParams,
    /// The belt stiffness along the stroke.
    pub profile: TargetStiffness,
    /// Friction and holding torque as commissioned.
    pub friction: FrictionResult,
    /// Their uncertainties from the folder's friction runs (NaN: unknown).
    pub friction_fit: Option<FrictionEstimate>,
    /// The PRBS amplitude of the commissioning, N m.
    pub excitation_amplitude_nm: Option<f64>,
}

impl Baseline {
    /// The baseline of a commissioning folder. Errors name the folder: a
    /// result without friction or without a measured stiffness (a
    /// commissioning from a recording) cannot be a baseline of the axis.
    pub fn read(dir: &std::path::Path) -> Result<Baseline> {
        let folder = ResultFolder::read(dir)?;
        Baseline::of(&folder)
    }

    /// The baseline of a folder as read.
    pub fn of(folder: &ResultFolder) -> Result<Baseline> {
        let r = &folder.record;
        let bad = |what: &str| {
            Error::Parse {
            path: folder.dir.display().to_string(),
            message: format!(
                "{what}: not a commissioning on an axis (run `beltune commission` on the axis for a baseline)"
            ),
        }
        };
        let friction = r.friction.clone().ok_or_else(|| bad("no friction"))?;
        let profile = r
            .target_stiffness
            .ok_or_else(|| bad("no belt stiffness along the stroke"))?;
        let friction_fit = folder.data.friction.as_ref().and_then(|f| {
            let runs: Vec<ConstantVelocityRun> = f
                .velocity_rad_s
                .iter()
                .zip(&f.torque_nm)
                .map(|(&w, &t)| ConstantVelocityRun {
                    velocity_rad_s: w,
                    mean_torque_nm: t,
                })
                .collect();
            fit_friction(&runs, None).ok().map(|e| FrictionEstimate {
                // the record's values; the runs give their uncertainty (the
                // points carry the friction alone: the offset is the
                // uncertainty of the holding torque the commissioning refined)
                coulomb_nm: friction.coulomb_nm,
                viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
                holding_nm: friction.holding_torque_nm,
                ..e
            })
        });
        Ok(Baseline {
            folder: folder.dir.display().to_string(),
            plant: r.plant.clone(),
            created_utc: r.provenance.as_ref().map(|p| p.created_utc.clone()),
            model: r.identified.clone(),
            frf_fit: r.frf_fit.unwrap_or_else(|| r.identified.params()),
            profile,
            friction,
            friction_fit,
            excitation_amplitude_nm: r.excitation_amplitude_nm,
        })
    }

    /// Relative one-sigma uncertainty of the identified `c` (NaN: unknown).
    fn c_rel_sigma(&self) -> f64 {
        self.model.c_sigma / self.model.c
    }

    /// The belt stiffness at cart position `x_m`, N/m.
    pub fn stiffness_at(&self, x_m: f64) -> Estimate {
        let c = self.profile.stiffness_at(x_m);
        Estimate::new(c, c * self.c_rel_sigma())
    }

    /// The model at `x_m`: the identified one with the profile's stiffness.
    pub fn params_at(&self, x_m: f64) -> TwoMassParams {
        TwoMassParams {
            c: self.profile.stiffness_at(x_m),
            ..self.model.params()
        }
    }

    /// `f_r` and `f_z` at `x_m`, Hz, with their uncertainties
    /// ([`resonances`]).
    pub fn resonances_at(&self, x_m: f64) -> (Estimate, Estimate) {
        let m = &self.model;
        resonances(
            &self.params_at(x_m),
            self.c_rel_sigma(),
            m.m_c_sigma / m.m_c,
        )
    }
}

/// `f_r` (2.44) and `f_z` (2.45) of `p` with the relative one-sigma
/// uncertainties of `c` and `m_c` propagated to first order as independent
/// errors: `d ln f_z = (d ln c - d ln m_c) / 2`, `d ln f_r = (d ln c - k d ln
/// m_c) / 2` with `k = Theta_e / (Theta_e + i_t^2 m_c)`. Unknown
/// uncertainties (NaN) count as zero where the other is known.
pub fn resonances(p: &TwoMassParams, c_rel: f64, m_rel: f64) -> (Estimate, Estimate) {
    let known = |x: f64| if x.is_finite() { x } else { 0.0 };
    let (c_rel, m_rel) = if c_rel.is_finite() || m_rel.is_finite() {
        (known(c_rel), known(m_rel))
    } else {
        (f64::NAN, f64::NAN)
    };
    let k = p.theta_e / p.rigid_inertia();
    let fz_rel = 0.5 * (c_rel.powi(2) + m_rel.powi(2)).sqrt();
    let fr_rel = 0.5 * (c_rel.powi(2) + (k * m_rel).powi(2)).sqrt();
    (
        Estimate::new(p.f_r_hz(), p.f_r_hz() * fr_rel),
        Estimate::new(p.f_z_hz(), p.f_z_hz() * fz_rel),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first-order propagation against finite differences of (2.44)
    /// and (2.45) on Table A.4 (a 1 % change of `c`, then of `m_c`).
    #[test]
    fn resonance_uncertainty_follows_2_44_and_2_45() {
        let p = TwoMassParams::thesis_table_a4();
        let step = 0.01;
        let with = |c: f64, m: f64| TwoMassParams {
            c: p.c * c,
            m_c: p.m_c * m,
            ..p
        };
        let (fr_c, fz_c) = resonances(&p, step, 0.0);
        let (fr_m, fz_m) = resonances(&p, 0.0, step);
        let d = |a: f64, b: f64| (a / b - 1.0).abs();
        let q = with(1.0 + step, 1.0);
        let r = with(1.0, 1.0 + step);
        // first order: within 1 % of the finite difference
        assert!((fr_c.sigma / fr_c.value / d(q.f_r_hz(), p.f_r_hz()) - 1.0).abs() < 0.01);
        assert!((fz_c.sigma / fz_c.value / d(q.f_z_hz(), p.f_z_hz()) - 1.0).abs() < 0.01);
        assert!((fr_m.sigma / fr_m.value / d(r.f_r_hz(), p.f_r_hz()) - 1.0).abs() < 0.01);
        assert!((fz_m.sigma / fz_m.value / d(r.f_z_hz(), p.f_z_hz()) - 1.0).abs() < 0.01);
        let (fr, _) = resonances(&p, f64::NAN, f64::NAN);
        assert!(fr.sigma.is_nan());
    }
}
