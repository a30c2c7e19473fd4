//! The shaper Klipper would choose from a measured vibration spectrum: the
//! rules of Klipper's `klippy/extras/shaper_calibrate.py` (`fit_shaper`,
//! `find_best_shaper`; Klipper3d/klipper at 84104bb, GPLv3), written again in
//! Rust from their description, not copied:
//!
//! - the remaining vibration of a shaper is the share of the spectrum above a
//!   twentieth of its peak that the shaper lets through, the largest over
//!   the test damping ratios 0.075, 0.1 and 0.15 and over the data sets
//!   (positions) recorded;
//! - each shaper is fitted over a grid of frequencies (from the highest
//!   down): the one with the least remaining vibration, then, among those
//!   within 10 % (+0.05 percentage points) of it, the lowest score
//!   `smoothing (v^1.5 + 0.2 v + 0.01)`;
//! - across shapers a later one replaces the best when its score is 20 %
//!   lower, or 5 % lower with 10 % less smoothing; a fitted point with both
//!   less vibration and less smoothing than the best replaces it; a ZV choice
//!   yields to the first other shaper with 10 % less vibration.
//!
//! Klipper's spectrum is an accelerometer's power spectral density on the
//! toolhead; beltune hands it the same quantity of its model, the cart's
//! acceleration per motor acceleration squared (see `super::bench`).

use super::shaper::{Shaper, ShaperKind, DEFAULT_DAMPING_RATIO};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Klipper's test damping ratios (`TEST_DAMPING_RATIOS`).
pub const TEST_DAMPING_RATIOS: [f64; 3] = [0.075, 0.1, 0.15];
/// Klipper's highest spectrum frequency considered (`MAX_FREQ`), Hz.
pub const MAX_FREQ_HZ: f64 = 200.0;
/// Klipper's highest shaper frequency (`MAX_SHAPER_FREQ`), Hz.
pub const MAX_SHAPER_FREQ_HZ: f64 = 150.0;
/// Klipper's shaper-frequency step, Hz.
pub const SHAPER_FREQ_STEP_HZ: f64 = 0.2;
/// Klipper's default square-corner velocity (5 mm/s), m/s.
pub const DEFAULT_SCV_M_S: f64 = 5e-3;
/// Klipper's vibration reduction threshold: spectrum below peak / 20 is ignored.
pub const SHAPER_VIBRATION_REDUCTION: f64 = 20.0;

/// A vibration spectrum recorded at one place: power per frequency bin.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spectrum {
    /// Bin frequencies, Hz (ascending).
    pub freq_hz: Vec<f64>,
    /// Power spectral density per bin (any consistent unit; only ratios count).
    pub psd: Vec<f64>,
}

impl Spectrum {
    /// Checks: equal lengths, at least two bins, finite non-negative values,
    /// some power.
    pub fn validate(&self) -> Result<()> {
        if self.freq_hz.len() != self.psd.len() || self.freq_hz.len() < 2 {
            return Err(Error::LengthMismatch {
                what: format!(
                    "spectrum with {} frequencies and {} values (needs equal, at least 2)",
                    self.freq_hz.len(),
                    self.psd.len()
                ),
            });
        }
        for (i, (&f, &p)) in self.freq_hz.iter().zip(&self.psd).enumerate() {
            if !f.is_finite() || !p.is_finite() {
                return Err(Error::NonFinite {
                    what: "spectrum".into(),
                    index: i,
                });
            }
            if p < 0.0 {
                return Err(Error::invalid("spectrum psd", p, "must not be negative"));
            }
        }
        if !self.psd.iter().any(|&p| p > 0.0) {
            return Err(Error::NoExcitation {
                what: "the spectrum has no power".into(),
            });
        }
        Ok(())
    }
}

/// How Klipper's calibration is run.
#[derive(Clone, Debug, PartialEq)]
pub struct KlipperOptions {
    /// Shapers tried, in order.
    pub shapers: Vec<ShaperKind>,
    /// Damping ratio the shapers are designed for.
    pub damping_ratio: f64,
    /// Test damping ratios the remaining vibration is pessimized over.
    pub test_damping_ratios: Vec<f64>,
    /// Square-corner velocity of the smoothing, m/s.
    pub scv_m_s: f64,
    /// Shaper frequency range `(start, end)`, Hz (`None` start: each
    /// shaper's own lowest default; `--shaper_freq` in Klipper's script).
    pub shaper_freq_start_hz: Option<f64>,
    /// Highest shaper frequency, Hz.
    pub shaper_freq_end_hz: f64,
    /// Largest smoothing accepted, m (`None`: any).
    pub max_smoothing_m: Option<f64>,
}

impl Default for KlipperOptions {
    fn default() -> Self {
        KlipperOptions {
            shapers: ShaperKind::AUTOTUNE.to_vec(),
            damping_ratio: DEFAULT_DAMPING_RATIO,
            test_damping_ratios: TEST_DAMPING_RATIOS.to_vec(),
            scv_m_s: DEFAULT_SCV_M_S,
            shaper_freq_start_hz: None,
            shaper_freq_end_hz: MAX_SHAPER_FREQ_HZ,
            max_smoothing_m: None,
        }
    }
}

/// One fitted shaper.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FittedShaper {
    /// Which shaper.
    pub kind: ShaperKind,
    /// Its frequency, Hz.
    pub freq_hz: f64,
    /// The impulses.
    pub shaper: Shaper,
    /// Remaining vibration (fraction, worst over damping ratios and data sets).
    pub vibration: f64,
    /// Smoothing at 5 m/s^2, m.
    pub smoothing_m: f64,
    /// Klipper's score `smoothing (v^1.5 + 0.2 v + 0.01)`, m.
    pub score: f64,
    /// Suggested maximum acceleration, m/s^2.
    pub max_accel_m_s2: f64,
}

/// Klipper's remaining vibration of `shaper` at damping ratio `damping_ratio`
/// on `spectrum` (bins at or below `max_freq_hz`).
pub fn remaining_vibration(
    shaper: &Shaper,
    damping_ratio: f64,
    spectrum: &Spectrum,
    max_freq_hz: f64,
) -> f64 {
    let bins = || {
        spectrum
            .freq_hz
            .iter()
            .zip(&spectrum.psd)
            .filter(move |(f, _)| **f <= max_freq_hz)
    };
    let peak = bins().map(|(_, p)| *p).fold(0.0, f64::max);
    let threshold = peak / SHAPER_VIBRATION_REDUCTION;
    let (mut remaining, mut all) = (0.0, 0.0);
    for (&f, &p) in bins() {
        let v = shaper.residual_vibration(f, damping_ratio);
        remaining += (v * p - threshold).max(0.0);
        all += (p - threshold).max(0.0);
    }
    if all > 0.0 {
        remaining / all
    } else {
        0.0
    }
}

fn fit_point(
    kind: ShaperKind,
    freq_hz: f64,
    data: &[Spectrum],
    opts: &KlipperOptions,
    max_freq_hz: f64,
) -> Result<FittedShaper> {
    let shaper = kind.design(freq_hz, opts.damping_ratio)?;
    let smoothing_m = shaper.smoothing_m(5.0, opts.scv_m_s);
    let mut vibration: f64 = 0.0;
    for s in data {
        for &dr in &opts.test_damping_ratios {
            vibration = vibration.max(remaining_vibration(&shaper, dr, s, max_freq_hz));
        }
    }
    let score = smoothing_m * (vibration.powf(1.5) + 0.2 * vibration + 0.01);
    let max_accel_m_s2 = shaper.max_accel_m_s2(opts.scv_m_s);
    Ok(FittedShaper {
        kind,
        freq_hz,
        shaper,
        vibration,
        smoothing_m,
        score,
        max_accel_m_s2,
    })
}

/// Klipper's `fit_shaper`: the selected point first, then every point fitted
/// (from the highest frequency down).
pub fn fit_shaper(
    kind: ShaperKind,
    data: &[Spectrum],
    opts: &KlipperOptions,
) -> Result<(FittedShaper, Vec<FittedShaper>)> {
    if data.is_empty() {
        return Err(Error::NoExcitation {
            what: "no spectrum to fit a shaper to".into(),
        });
    }
    for s in data {
        s.validate()?;
    }
    let end = opts.shaper_freq_end_hz;
    let start = opts
        .shaper_freq_start_hz
        .unwrap_or(kind.klipper_min_freq_hz())
        .min(end - 1e-7);
    if !(start.is_finite() && end.is_finite() && start > 0.0) {
        return Err(Error::invalid(
            "shaper_freq_start_hz",
            start,
            "must be finite, positive and below the end",
        ));
    }
    // numpy.arange(start, end, 0.2), walked from the top.
    let n = ((end - start) / SHAPER_FREQ_STEP_HZ).ceil().max(1.0) as usize;
    let mut freqs: Vec<f64> = (0..n)
        .map(|i| start + i as f64 * SHAPER_FREQ_STEP_HZ)
        .collect();
    freqs.reverse();
    let max_freq_hz = MAX_FREQ_HZ.max(freqs.first().copied().unwrap_or(start));
    let mut results: Vec<FittedShaper> = Vec::with_capacity(n);
    let mut best: Option<usize> = None;
    for f in freqs {
        let point = fit_point(kind, f, data, opts, max_freq_hz)?;
        if let (Some(max_s), Some(b)) = (opts.max_smoothing_m, best) {
            if point.smoothing_m > max_s {
                // Klipper returns its least-vibration point as it is here.
                return Ok((results[b].clone(), results));
            }
        }
        results.push(point);
        let last = results.len() - 1;
        match best {
            Some(b) if results[b].vibration <= results[last].vibration => {}
            _ => best = Some(last),
        }
    }
    let best = best.ok_or(Error::NoExcitation {
        what: "no shaper frequency to try".into(),
    })?;
    let best_v = results[best].vibration;
    let mut selected = best;
    for (i, r) in results.iter().enumerate().rev() {
        if r.vibration < best_v * 1.1 + 0.0005 && r.score < results[selected].score {
            selected = i;
        }
    }
    Ok((results[selected].clone(), results))
}

/// Klipper's `find_best_shaper`: the chosen shaper and the one fitted for
/// each kind tried.
pub fn find_best_shaper(
    data: &[Spectrum],
    opts: &KlipperOptions,
) -> Result<(FittedShaper, Vec<FittedShaper>)> {
    let mut best: Option<FittedShaper> = None;
    let mut all = Vec::new();
    for &kind in &opts.shapers {
        let (mut shaper, results) = fit_shaper(kind, data, opts)?;
        let replace = match &best {
            None => true,
            Some(b) => {
                shaper.score * 1.2 < b.score
                    || (shaper.score * 1.05 < b.score && shaper.smoothing_m * 1.1 < b.smoothing_m)
            }
        };
        if replace {
            best = Some(shaper.clone());
        }
        for s in results.iter().rev() {
            if let Some(b) = &best {
                if s.vibration < b.vibration && s.smoothing_m < b.smoothing_m {
                    best = Some(s.clone());
                    shaper = s.clone();
                }
            }
        }
        all.push(shaper);
    }
    let mut best = best.ok_or(Error::NoExcitation {
        what: "no shaper kinds to try".into(),
    })?;
    if best.kind == ShaperKind::Zv {
        if let Some(t) = all
            .iter()
            .find(|t| t.kind != ShaperKind::Zv && t.vibration * 1.1 < best.vibration)
        {
            best = t.clone();
        }
    }
    Ok((best, all))
}
