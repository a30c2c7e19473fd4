//! The resonance range the data sheet allows, and what the stages before the
//! identification derive from it: the PRBS clock and order (thesis 3.4) for
//! the axis' sampling rate. The bootstrap controller's margin over the same
//! range is [`super::bootstrap_margin`].
//!
//! A belt axis' data sheet gives the belt's specific stiffness `c_b`, the
//! stroke and the masses; (2.26) then gives the replacement stiffness over
//! the stroke and (2.44)/(2.45) its resonance and antiresonance. The values
//! are uncertain, mostly downwards: the data-sheet stiffness ignores the
//! tooth engagement at the pulleys and the clamps, and egc70's is 28-40 %
//! above the identified one (Tables A.2, A.4/A.5,
//! [`crate::model::rigs::egc70_params`]), 13-18 % in frequency; the end
//! pulley lowers the antiresonance a few per cent more
//! ([`crate::model::equivalent`]). The range is widened by
//! [`DATA_SHEET_FREQUENCY_BELOW`] downwards and [`DATA_SHEET_FREQUENCY_ABOVE`]
//! upwards.

use super::config::{DataSheet, ExcitationConfig};

/// How far below its data-sheet value a resonance may lie, relative (twice
/// egc70's 13-18 %).
pub const DATA_SHEET_FREQUENCY_BELOW: f64 = 0.35;
/// How far above its data-sheet value a resonance may lie, relative (a
/// stiffer mounting than the data sheet's, a lighter cart).
pub const DATA_SHEET_FREQUENCY_ABOVE: f64 = 0.10;

/// Highest frequency the PRBS covers as a multiple of the highest resonance
/// the data sheet allows: the fit needs the lines above the resonance
/// (the high-frequency asymptote (2.43)).
pub const PRBS_BAND_OVER_RESONANCE: f64 = 1.5;

/// Lines of the PRBS spectrum below the lowest antiresonance: the period is
/// at least this many periods of the lowest antiresonance.
pub const PRBS_LINES_BELOW_ANTIRESONANCE: f64 = 4.0;

/// Highest PRBS order chosen from the band (a period of 32767 clocks).
pub const PRBS_ORDER_MAX: u32 = 15;

/// Longest PRBS period chosen from the band, s.
pub const PRBS_PERIOD_MAX_S: f64 = 4.0;

/// The antiresonance and resonance range of an axis, Hz.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResonanceBand {
    /// Lowest antiresonance `f_z`, Hz.
    pub f_z_min_hz: f64,
    /// Highest antiresonance, Hz.
    pub f_z_max_hz: f64,
    /// `f_r / f_z = sqrt(1 + i_t^2 m_c / Theta_e)` (2.47) of the data sheet.
    pub resonance_ratio: f64,
}

impl ResonanceBand {
    /// The band of `ds` (its antiresonance range and inertias), `None` where
    /// the data sheet gives no antiresonance range.
    pub fn of(ds: &DataSheet) -> Option<ResonanceBand> {
        let [lo, hi] = ds.antiresonance_band_hz?;
        let ratio = (1.0 + ds.i_t_m * ds.i_t_m * ds.moving_mass_kg / ds.theta_e_kg_m2).sqrt();
        (lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo && ratio.is_finite()).then_some(
            ResonanceBand {
                f_z_min_hz: lo,
                f_z_max_hz: hi,
                resonance_ratio: ratio,
            },
        )
    }

    /// Highest resonance, Hz.
    pub fn f_r_max_hz(&self) -> f64 {
        self.f_z_max_hz * self.resonance_ratio
    }
}

/// The antiresonance range `[lowest, highest]` (Hz) of `plant` over its
/// stroke from the data-sheet physics (the two-mass reduction (2.26),
/// (2.45)), widened by [`DATA_SHEET_FREQUENCY_BELOW`] and
/// [`DATA_SHEET_FREQUENCY_ABOVE`]; a linear set
/// has one antiresonance.
pub fn antiresonance_band_hz(plant: &crate::model::Plant) -> Option<[f64; 2]> {
    let ends = match plant {
        crate::model::Plant::Physical(p) => [0.0, p.stroke_m],
        crate::model::Plant::Linear(_) => [0.0, 0.0],
    };
    let f: Vec<f64> = ends
        .iter()
        .filter_map(|&x| plant.linearize(x).ok().map(|m| m.f_z_hz()))
        .collect();
    let lo = f.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = f.iter().copied().fold(0.0, f64::max);
    (f.len() == 2 && lo.is_finite() && lo > 0.0).then_some([
        lo * (1.0 - DATA_SHEET_FREQUENCY_BELOW),
        hi * (1.0 + DATA_SHEET_FREQUENCY_ABOVE),
    ])
}

impl ExcitationConfig {
    /// The excitation for an axis sampled at `ts_s` whose data sheet allows
    /// `band` (unchanged where `band` is `None` or
    /// [`ExcitationConfig::band_from_data_sheet`] is off):
    ///
    /// - the clock: at most [`Self::clock_period_s`], and short enough that
    ///   the PRBS covers [`PRBS_BAND_OVER_RESONANCE`] times the highest
    ///   resonance (its spectrum is usable up to `1 / P_PRBS`), at least one
    ///   sample;
    /// - the order: at least [`Self::prbs_order`], and a period at least as
    ///   long as the configured one (the same frequency resolution) and
    ///   [`PRBS_LINES_BELOW_ANTIRESONANCE`] periods of the lowest
    ///   antiresonance, up to [`PRBS_ORDER_MAX`] and [`PRBS_PERIOD_MAX_S`].
    pub fn for_band(&self, ts_s: f64, band: Option<&ResonanceBand>) -> ExcitationConfig {
        let Some(band) = band.filter(|_| self.band_from_data_sheet) else {
            return *self;
        };
        let configured_clock = self.clock_samples(ts_s);
        let configured_period_s =
            ((1u64 << self.prbs_order.min(30)) - 1) as f64 * f64::from(configured_clock) * ts_s;
        let wanted = 1.0 / (PRBS_BAND_OVER_RESONANCE * band.f_r_max_hz() * ts_s);
        let clock = if wanted.is_finite() && wanted >= 1.0 {
            (wanted.floor() as u32).min(configured_clock)
        } else {
            1
        };
        let clock_s = f64::from(clock) * ts_s;
        let period_s = configured_period_s
            .max(PRBS_LINES_BELOW_ANTIRESONANCE / band.f_z_min_hz)
            .min(PRBS_PERIOD_MAX_S);
        let mut order = self.prbs_order;
        while order < PRBS_ORDER_MAX && ((1u64 << order) - 1) as f64 * clock_s < period_s {
            order += 1;
        }
        ExcitationConfig {
            clock_period_s: clock_s,
            prbs_order: order,
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs;

    fn ds_with(band: [f64; 2]) -> DataSheet {
        DataSheet {
            antiresonance_band_hz: Some(band),
            stroke_variation: None,
            ..DataSheet::for_plant(&rigs::builtin("egc70", None).unwrap(), 0.05, None)
        }
    }

    /// egc70 at 10 kHz keeps the thesis' PRBS (order 9, 1.6 ms): its
    /// resonances (about 100-200 Hz) lie well inside the 625 Hz band.
    #[test]
    fn egc70_keeps_the_thesis_prbs() {
        let plant = rigs::builtin("egc70", None).unwrap();
        let ds = DataSheet::for_plant(&plant, 0.05, None);
        let band = ResonanceBand::of(&ds).unwrap();
        assert!(band.f_r_max_hz() < 400.0, "{band:?}");
        let ex = ExcitationConfig::default().for_band(1e-4, Some(&band));
        assert_eq!(ex, ExcitationConfig::default());
    }

    /// A stiff short axis whose resonance reaches 1130 Hz once failed its
    /// fit with the fixed 1.6 ms clock (band up to 625 Hz): the clock now
    /// covers 1.5 times the highest resonance and the order keeps the
    /// period (the frequency resolution).
    #[test]
    fn the_prbs_clock_covers_the_highest_resonance() {
        let mut ds = ds_with([300.0, 600.0]);
        ds.moving_mass_kg = 0.5;
        let band = ResonanceBand::of(&ds).unwrap();
        let ex = ExcitationConfig::default().for_band(1e-4, Some(&band));
        let top = 1.0 / ex.clock_period_s;
        assert!(top >= 1.5 * band.f_r_max_hz(), "{top} Hz for {band:?}");
        let period = ((1u64 << ex.prbs_order) - 1) as f64 * ex.clock_period_s;
        assert!(period >= 0.8176 - 1e-9, "{period} s");
        // an explicit clock is kept
        let fixed = ExcitationConfig {
            band_from_data_sheet: false,
            ..ExcitationConfig::default()
        };
        assert_eq!(fixed.for_band(1e-4, Some(&band)), fixed);
    }

    /// A heavy long gantry (antiresonance down to 5 Hz): the period holds
    /// four periods of the lowest antiresonance; at 1 kHz the clock is at
    /// least one sample.
    #[test]
    fn the_prbs_period_resolves_the_lowest_antiresonance() {
        let band = ResonanceBand {
            f_z_min_hz: 5.0,
            f_z_max_hz: 12.0,
            resonance_ratio: 3.0,
        };
        let ex = ExcitationConfig::default().for_band(1e-3, Some(&band));
        let period = ((1u64 << ex.prbs_order) - 1) as f64 * ex.clock_period_s;
        assert!(period >= 0.8 - 1e-9, "{period} s");
        let stiff = ResonanceBand {
            f_z_min_hz: 800.0,
            f_z_max_hz: 2000.0,
            resonance_ratio: 1.2,
        };
        let ex = ExcitationConfig::default().for_band(1e-3, Some(&stiff));
        assert!((ex.clock_period_s - 1e-3).abs() < 1e-12);
    }
}
