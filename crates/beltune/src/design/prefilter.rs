//! Prefilter design (thesis 4.2.1): the notch (4.1) centred on the resonance
//! `w_r` with `d_n` solved explicitly from (4.2), and the 2nd-order Butterworth
//! low-pass (4.3) with `w_bw` from (4.4). Both conditions fix the filter's gain
//! at the antiresonance `w_z`, which ties the filter to the resonance ratio.

use crate::error::require_finite;
use crate::lti::{from_db, Tf};
use crate::model::TwoMassParams;
use crate::{Error, Result};
use beltune_rt::filter::SosCoeffs;
use std::f64::consts::SQRT_2;

/// Which prefilter `G_pre` sits in the velocity loop.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PrefilterKind {
    /// 2nd-order Butterworth low-pass (4.3), default attenuation -3 dB at `w_z`.
    #[default]
    Butterworth,
    /// Notch (4.1) at `w_r`, default attenuation -6 dB at `w_z`.
    Notch,
    /// No prefilter (`G_pre = 1`), as in the thesis' comparison of Section 5.1.
    None,
}

impl PrefilterKind {
    /// Default attenuation at the antiresonance: `A_bw = -3 dB`, `A_Notch = -6 dB`
    /// (thesis 4.2.1, Tables A.6/A.7); 0 dB for no filter.
    pub fn default_attenuation_db(self) -> f64 {
        match self {
            PrefilterKind::Butterworth => -3.0,
            PrefilterKind::Notch => -6.0,
            PrefilterKind::None => 0.0,
        }
    }
}

impl std::str::FromStr for PrefilterKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "butterworth" | "bw" => Ok(PrefilterKind::Butterworth),
            "notch" => Ok(PrefilterKind::Notch),
            "none" => Ok(PrefilterKind::None),
            _ => Err(Error::Parse {
                path: "prefilter".into(),
                message: format!("unknown prefilter `{s}` (expected butterworth, notch or none)"),
            }),
        }
    }
}

/// A designed prefilter with its continuous parameters.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Prefilter {
    /// Butterworth (4.3) with cut-off `omega_bw_rad_s`.
    Butterworth {
        /// Cut-off `w_bw` in rad/s.
        omega_bw_rad_s: f64,
    },
    /// Notch (4.1) centred on `omega_r_rad_s` with width parameter `d_n > 1`.
    Notch {
        /// Centre `w_r,N = w_r` in rad/s.
        omega_r_rad_s: f64,
        /// Width parameter `d_n` (dimensionless); depth at the centre `1 / d_n^2`.
        d_n: f64,
    },
    /// `G_pre = 1`.
    None,
}

/// `d_n` of the notch (4.1) from (4.2), solved explicitly: with
/// `a = w_r^2 - w_z^2`, `b = w_r w_z`, `|G_N(j w_z)|^2 = A^2` becomes the quadratic
/// `4 A^2 b^2 q^2 - (1 - A^2) a^2 q - 4 b^2 = 0` in `q = d_n^2`, whose positive root is taken.
pub fn notch_d_n(omega_r_rad_s: f64, omega_z_rad_s: f64, attenuation_db: f64) -> Result<f64> {
    let a_lin = attenuation_gain(attenuation_db)?;
    if !(omega_z_rad_s > 0.0 && omega_r_rad_s > omega_z_rad_s && omega_r_rad_s.is_finite()) {
        return Err(Error::invalid(
            "omega_r_rad_s",
            omega_r_rad_s,
            format!("the notch needs 0 < w_z ({omega_z_rad_s}) < w_r"),
        ));
    }
    let a = omega_r_rad_s.powi(2) - omega_z_rad_s.powi(2);
    let b = omega_r_rad_s * omega_z_rad_s;
    let a2 = a_lin * a_lin;
    let p = (1.0 - a2) * a * a;
    let q = (p + (p * p + 64.0 * a2 * b.powi(4)).sqrt()) / (8.0 * a2 * b * b);
    Ok(q.sqrt())
}

/// `w_bw` of the Butterworth (4.3) from (4.4): `1 / (1 + (w_z/w_bw)^4) = A^2`,
/// i.e. `w_bw = w_z / (1/A^2 - 1)^(1/4)`.
pub fn butterworth_omega_bw(omega_z_rad_s: f64, attenuation_db: f64) -> Result<f64> {
    let a_lin = attenuation_gain(attenuation_db)?;
    crate::error::require_positive("omega_z_rad_s", omega_z_rad_s)?;
    Ok(omega_z_rad_s / (1.0 / (a_lin * a_lin) - 1.0).powf(0.25))
}

/// `A < 1` as a linear gain from a negative dB value.
fn attenuation_gain(attenuation_db: f64) -> Result<f64> {
    require_finite("filter_attenuation_db", attenuation_db)?;
    if !(-60.0..0.0).contains(&attenuation_db) {
        return Err(Error::invalid(
            "filter_attenuation_db",
            attenuation_db,
            "the attenuation at the antiresonance must lie in [-60, 0) dB",
        ));
    }
    Ok(from_db(attenuation_db))
}

impl Prefilter {
    /// Design `kind` for `model` with the attenuation `attenuation_db` at `w_z`
    /// ((4.2) or (4.4)); ignored for [`PrefilterKind::None`].
    pub fn design(kind: PrefilterKind, model: &TwoMassParams, attenuation_db: f64) -> Result<Self> {
        model.validate()?;
        let (w_r, w_z) = (model.resonance_rad_s(), model.antiresonance_rad_s());
        Ok(match kind {
            PrefilterKind::Butterworth => Prefilter::Butterworth {
                omega_bw_rad_s: butterworth_omega_bw(w_z, attenuation_db)?,
            },
            PrefilterKind::Notch => Prefilter::Notch {
                omega_r_rad_s: w_r,
                d_n: notch_d_n(w_r, w_z, attenuation_db)?,
            },
            PrefilterKind::None => Prefilter::None,
        })
    }

    /// Which kind this is.
    pub fn kind(&self) -> PrefilterKind {
        match self {
            Prefilter::Butterworth { .. } => PrefilterKind::Butterworth,
            Prefilter::Notch { .. } => PrefilterKind::Notch,
            Prefilter::None => PrefilterKind::None,
        }
    }

    /// Continuous transfer function `G_pre(s)`: (4.3), (4.1) or 1.
    pub fn tf(&self) -> Tf {
        match *self {
            Prefilter::Butterworth { omega_bw_rad_s: w } => {
                Tf::from_descending(&[1.0], &[1.0 / (w * w), SQRT_2 / w, 1.0])
            }
            Prefilter::Notch {
                omega_r_rad_s: w,
                d_n: d,
            } => Tf::from_descending(&[1.0, 2.0 * w / d, w * w], &[1.0, 2.0 * d * w, w * w]),
            Prefilter::None => Tf::gain(1.0),
        }
    }

    /// Tustin section at `ts_s`, pre-warped at the filter's characteristic
    /// frequency (the rt crate's `butterworth_lowpass` / `notch`).
    pub fn discretize(&self, ts_s: f64) -> Result<SosCoeffs<f64>> {
        Ok(match *self {
            Prefilter::Butterworth { omega_bw_rad_s } => {
                beltune_rt::filter::butterworth_lowpass(omega_bw_rad_s, ts_s)?
            }
            Prefilter::Notch { omega_r_rad_s, d_n } => {
                beltune_rt::filter::notch(omega_r_rad_s, d_n, ts_s)?
            }
            Prefilter::None => SosCoeffs::IDENTITY,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Table A.7: `w_bw = 123.24 rad/s` for `A_bw = -3 dB`; 0.1 % as the issue asks
    /// (the table's w_z is rounded, docs/thesis-map.md computes 123.25).
    const W_BW_REL_TOL: f64 = 1e-3;
    /// Table A.6: `d_n = 4.60` for `A_Notch = -6 dB`; 0.5 % (two printed digits).
    const D_N_REL_TOL: f64 = 5e-3;

    #[test]
    fn table_a7_butterworth_cutoff() {
        let p = Prefilter::design(
            PrefilterKind::Butterworth,
            &TwoMassParams::thesis_table_a4(),
            -3.0,
        )
        .unwrap();
        let Prefilter::Butterworth { omega_bw_rad_s } = p else {
            panic!("{p:?}")
        };
        assert!(
            (omega_bw_rad_s / 123.24 - 1.0).abs() < W_BW_REL_TOL,
            "{omega_bw_rad_s}"
        );
    }

    #[test]
    fn table_a6_notch_width() {
        let m = TwoMassParams::thesis_table_a4();
        let p = Prefilter::design(PrefilterKind::Notch, &m, -6.0).unwrap();
        let Prefilter::Notch { omega_r_rad_s, d_n } = p else {
            panic!("{p:?}")
        };
        assert!((d_n / 4.60 - 1.0).abs() < D_N_REL_TOL, "{d_n}");
        assert!((omega_r_rad_s - m.resonance_rad_s()).abs() < 1e-9);
    }

    /// Independent check of (4.2)/(4.4): evaluate the designed filters at `w_z`
    /// on random plants; the gain equals the requested attenuation.
    #[test]
    fn conditions_hold_on_random_plants() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        for _ in 0..200 {
            let m = TwoMassParams {
                m_c: rng.random_range(0.3..30.0),
                c: rng.random_range(2e4..3e6),
                ..TwoMassParams::thesis_table_a4()
            };
            let att = rng.random_range(-20.0..-0.5);
            for kind in [PrefilterKind::Butterworth, PrefilterKind::Notch] {
                let p = Prefilter::design(kind, &m, att).unwrap();
                let g = p.tf().freq_response(m.antiresonance_rad_s()).norm();
                assert!((crate::lti::db(g) - att).abs() < 1e-9, "{kind:?} {att} {g}");
                assert!(p.discretize(1e-4).unwrap().is_stable());
            }
        }
    }

    #[test]
    fn bad_attenuation_is_an_error() {
        let m = TwoMassParams::thesis_table_a4();
        for att in [0.0, 3.0, f64::NAN, -100.0] {
            assert!(Prefilter::design(PrefilterKind::Notch, &m, att).is_err());
            assert!(Prefilter::design(PrefilterKind::Butterworth, &m, att).is_err());
        }
        assert!(Prefilter::design(PrefilterKind::None, &m, 0.0).is_ok());
        assert!("bogus".parse::<PrefilterKind>().is_err());
        assert_eq!(
            "Notch".parse::<PrefilterKind>().unwrap(),
            PrefilterKind::Notch
        );
    }
}
