//! Each measured quantity against its baseline, with the uncertainty of
//! both, and the verdict per quantity:
//!
//! - the change is `value / baseline - 1` (a relative limit) or `value -
//!   baseline` (an absolute one), its one-sigma uncertainty the two
//!   uncertainties combined as independent errors;
//! - a change counts where it exceeds `significance_sigmas` times that
//!   uncertainty (an unknown uncertainty counts every change);
//! - a counting change beyond its limit is [`Status::Act`], beyond
//!   `watch_fraction` of it [`Status::Watch`], else [`Status::Ok`];
//! - each change that is not `ok` gets a recommendation in words.

use super::baseline::{resonances, Baseline};
use super::config::{HealthLimits, Limit, Quantity};
use super::experiment::{Measured, PositionFit};
use super::Estimate;
use serde::{Deserialize, Serialize};

/// The verdict on one quantity, or on a whole check (the worst of its quantities).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Within its limits, or no change beyond the uncertainty.
    #[default]
    Ok,
    /// A real change beyond part of its limit: look again at the next check.
    Watch,
    /// Beyond its limit: act on the recommendation.
    Act,
}

impl Status {
    /// The word of the report.
    pub fn word(self) -> &'static str {
        match self {
            Status::Ok => "OK",
            Status::Watch => "WATCH",
            Status::Act => "ACT",
        }
    }
}

/// One quantity against its baseline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Which quantity.
    pub quantity: Quantity,
    /// Where it was measured (cart position, m), if it depends on it.
    pub position_m: Option<f64>,
    /// The baseline's value and uncertainty (the quantity's unit).
    pub baseline: Estimate,
    /// The health check's value and uncertainty.
    pub measured: Estimate,
    /// The change: relative (a fraction) or absolute (the quantity's unit), as the limit.
    #[serde(with = "super::nan_as_null")]
    pub change: f64,
    /// Its one-sigma uncertainty (NaN: unknown).
    #[serde(with = "super::nan_as_null")]
    pub change_sigma: f64,
    /// The limit it was judged against.
    pub limit: Limit,
    /// The verdict.
    pub status: Status,
    /// What to do, where the status is not `ok`.
    pub recommendation: Option<String>,
}

impl Comparison {
    /// The change as text: `-18 % +- 2 %` (relative) or `+0.080 +- 0.010 N m`.
    pub fn change_text(&self) -> String {
        if self.limit.relative || self.quantity == Quantity::AmplitudeDependence {
            format!(
                "{:+.1} % +- {:.1} %",
                100.0 * self.change,
                100.0 * self.change_sigma
            )
        } else {
            format!(
                "{:+.4} +- {:.4} {}",
                self.change,
                self.change_sigma,
                self.quantity.unit()
            )
        }
    }
}

/// The change of `measured` from `baseline` and its uncertainty.
fn change(measured: Estimate, baseline: Estimate, relative: bool) -> (f64, f64) {
    let known = |x: f64| if x.is_finite() { Some(x) } else { None };
    if relative {
        let ratio = measured.value / baseline.value;
        let (a, b) = (
            known(measured.sigma / measured.value),
            known(baseline.sigma / baseline.value),
        );
        let rel = match (a, b) {
            (None, None) => f64::NAN,
            (a, b) => ratio.abs() * (a.unwrap_or(0.0).powi(2) + b.unwrap_or(0.0).powi(2)).sqrt(),
        };
        (ratio - 1.0, rel)
    } else {
        let s = match (known(measured.sigma), known(baseline.sigma)) {
            (None, None) => f64::NAN,
            (a, b) => (a.unwrap_or(0.0).powi(2) + b.unwrap_or(0.0).powi(2)).sqrt(),
        };
        (measured.value - baseline.value, s)
    }
}

/// The verdict on a change (module docs).
pub fn judge(change: f64, sigma: f64, limit: &Limit, limits: &HealthLimits) -> Status {
    if !change.is_finite() {
        return Status::Ok;
    }
    let counts = !sigma.is_finite() || change.abs() > limits.significance_sigmas * sigma;
    let beyond = |fraction: f64| {
        limit.lower.is_some_and(|l| change < fraction * l)
            || limit.upper.is_some_and(|u| change > fraction * u)
    };
    if !counts {
        Status::Ok
    } else if beyond(1.0) {
        Status::Act
    } else if beyond(limits.watch_fraction) {
        Status::Watch
    } else {
        Status::Ok
    }
}

/// What to do about a change of `q` in the direction of `change`.
fn advice(q: Quantity, change: f64) -> &'static str {
    use Quantity::*;
    let up = change > 0.0;
    match q {
        StiffnessFar | StiffnessNear if up => {
            "the belt is stiffer than commissioned (re-tensioned or replaced?): re-commission"
        }
        StiffnessFar | StiffnessNear => {
            "re-tension the belt to its data-sheet value, then re-commission"
        }
        ResonanceFar | AntiresonanceFar | ResonanceNear | AntiresonanceNear => {
            "the resonance the controller's filter is tuned to has moved: re-commission (and see the belt stiffness)"
        }
        ResonanceDamping if up => {
            "the belt mode is damped more: look for rubbing (guide, cover strip, a foreign body)"
        }
        ResonanceDamping => {
            "the belt mode is damped less: check the belt for wear and glazing, then re-commission"
        }
        MovingMass => {
            "the moving mass is not the commissioned one (payload changed?): re-commission for the new load"
        }
        CoulombFriction if up => {
            "clean and lubricate the guide, check the bearings, the cover strip and the guide for wear"
        }
        CoulombFriction => "the friction dropped: check the guide's preload and the seals",
        ViscousFriction if up => {
            "the lubricant is ageing or contaminated: re-lubricate the guide and the bearings"
        }
        ViscousFriction => "the viscous friction dropped: check the lubrication and the seals",
        HoldingTorque => {
            "the load the axis holds changed (payload, counterweight, a dragging brake): check it, then re-commission"
        }
        AmplitudeDependence if up => {
            "the belt is softer at small amplitudes (backlash): check the belt clamps on the cart, the pulley fit and the coupling"
        }
        AmplitudeDependence => {
            "the belt is softer under load (a span goes slack): re-tension the belt to its data-sheet value, then re-commission"
        }
    }
}

/// Compare the measurements `m` with `base` under `limits`, quantity by
/// quantity (those `m` has).
pub fn compare(base: &Baseline, m: &Measured, limits: &HealthLimits) -> Vec<Comparison> {
    let mut out = Vec::new();
    let mut push = |q: Quantity, position_m: Option<f64>, b: Estimate, v: Estimate| {
        let limit = limits.of(q);
        let (c, s) = change(v, b, limit.relative);
        let status = judge(c, s, &limit, limits);
        let mut cmp = Comparison {
            quantity: q,
            position_m,
            baseline: b,
            measured: v,
            change: c,
            change_sigma: s,
            limit,
            status,
            recommendation: None,
        };
        if status != Status::Ok {
            cmp.recommendation = Some(format!(
                "{} {}: {}",
                q.description(),
                cmp.change_text(),
                advice(q, c)
            ));
        }
        out.push(cmp);
    };
    let at = |fit: &PositionFit| {
        if fit.position_m.is_finite() {
            fit.position_m
        } else {
            base.model.position_m
        }
    };
    let fit_estimates = |fit: &PositionFit| {
        let (c_rel, m_rel) = fit.sigma.map_or((f64::NAN, f64::NAN), |u| {
            (u.c / fit.params.c, u.m_c / fit.params.m_c)
        });
        let m_rel = if fit.mass_held { 0.0 } else { m_rel };
        let (fr, fz) = resonances(&fit.params, c_rel, m_rel);
        (
            Estimate::new(fit.params.c, fit.params.c * c_rel),
            fr,
            fz,
            Estimate::new(fit.params.m_c, fit.params.m_c * m_rel),
        )
    };
    let positions: [(Option<&PositionFit>, [Quantity; 3]); 2] = [
        (
            m.far.as_ref(),
            [
                Quantity::StiffnessFar,
                Quantity::ResonanceFar,
                Quantity::AntiresonanceFar,
            ],
        ),
        (
            m.near.as_ref(),
            [
                Quantity::StiffnessNear,
                Quantity::ResonanceNear,
                Quantity::AntiresonanceNear,
            ],
        ),
    ];
    for (fit, [qc, qr, qz]) in positions {
        let Some(fit) = fit else { continue };
        let x = at(fit);
        let (c, fr, fz, _) = fit_estimates(fit);
        let (bfr, bfz) = base.resonances_at(x);
        push(qc, Some(x), base.stiffness_at(x), c);
        push(qr, Some(x), bfr, fr);
        push(qz, Some(x), bfz, fz);
    }
    if let Some(far) = &m.far {
        let (_, _, _, mass) = fit_estimates(far);
        push(
            Quantity::MovingMass,
            None,
            Estimate::new(base.model.m_c, base.model.m_c_sigma),
            mass,
        );
        push(
            Quantity::ResonanceDamping,
            Some(at(far)),
            Estimate::new(base.frf_fit.resonance_damping_ratio(), f64::NAN),
            damping_ratio(far),
        );
    }
    if let Some(f) = &m.friction {
        let bf = base.friction_fit;
        let sigma =
            |get: fn(&super::friction::FrictionEstimate) -> f64| bf.map_or(f64::NAN, |b| get(&b));
        push(
            Quantity::CoulombFriction,
            None,
            Estimate::new(base.friction.coulomb_nm, sigma(|b| b.coulomb_sigma_nm)),
            Estimate::new(f.coulomb_nm, f.coulomb_sigma_nm),
        );
        push(
            Quantity::ViscousFriction,
            None,
            Estimate::new(
                base.friction.viscous_nm_s_per_rad,
                sigma(|b| b.viscous_sigma_nm_s_per_rad),
            ),
            Estimate::new(f.viscous_nm_s_per_rad, f.viscous_sigma_nm_s_per_rad),
        );
        push(
            Quantity::HoldingTorque,
            None,
            Estimate::new(
                base.friction.holding_torque_nm,
                sigma(|b| b.holding_sigma_nm),
            ),
            Estimate::new(f.holding_nm, f.holding_sigma_nm),
        );
    }
    if let (Some(far), Some(half)) = (&m.far, &m.far_half) {
        let (_, fr_full, _, _) = fit_estimates(far);
        let (_, fr_half, _, _) = fit_estimates(half);
        let ratio = fr_full.value / fr_half.value;
        let rel = (fr_full.sigma / fr_full.value).hypot(fr_half.sigma / fr_half.value);
        push(
            Quantity::AmplitudeDependence,
            Some(at(far)),
            Estimate::new(0.0, 0.0),
            Estimate::new(ratio - 1.0, ratio * rel),
        );
    }
    out
}

/// The damping ratio of the resonance of the FRF fit of `fit`, with the
/// uncertainty of its `d_m` and `d_c` propagated by finite differences.
fn damping_ratio(fit: &PositionFit) -> Estimate {
    let p = fit.frf_fit;
    let z = p.resonance_damping_ratio();
    let sigma = fit.frf_sigma.map_or(f64::NAN, |u| {
        let dm = crate::model::TwoMassParams {
            d_m: p.d_m + u.d_m,
            ..p
        }
        .resonance_damping_ratio()
            - z;
        let dc = crate::model::TwoMassParams {
            d_c: p.d_c + u.d_c,
            ..p
        }
        .resonance_damping_ratio()
            - z;
        dm.hypot(dc)
    });
    Estimate::new(z, sigma)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule of the module docs on a stiffness-like limit (-10 %, +25 %,
    /// watch at half, two sigma).
    #[test]
    fn a_change_counts_beyond_its_uncertainty_and_is_judged_by_its_limit() {
        let limits = HealthLimits::default();
        let l = Limit::relative(Some(-0.10), Some(0.25));
        assert_eq!(judge(-0.18, 0.02, &l, &limits), Status::Act);
        assert_eq!(judge(-0.07, 0.01, &l, &limits), Status::Watch);
        assert_eq!(judge(-0.03, 0.01, &l, &limits), Status::Ok);
        // beyond the limit but within two sigma: not a change
        assert_eq!(judge(-0.12, 0.07, &l, &limits), Status::Ok);
        // an unknown uncertainty counts every change
        assert_eq!(judge(-0.12, f64::NAN, &l, &limits), Status::Act);
        assert_eq!(judge(0.30, 0.01, &l, &limits), Status::Act);
        assert_eq!(judge(f64::NAN, 0.01, &l, &limits), Status::Ok);
        // relative change of two estimates: (0.8 +- 1 %) / (1 +- 1 %)
        let (c, s) = change(Estimate::new(0.8, 0.008), Estimate::new(1.0, 0.01), true);
        assert!((c + 0.2).abs() < 1e-12 && (s - 0.8 * 2f64.sqrt() * 0.01).abs() < 1e-12);
        let (c, s) = change(Estimate::new(0.3, 0.03), Estimate::new(0.1, 0.04), false);
        assert!((c - 0.2).abs() < 1e-12 && (s - 0.05).abs() < 1e-12);
    }
}
