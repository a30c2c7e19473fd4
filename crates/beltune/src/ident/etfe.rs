//! Empirical transfer function estimate (ETFE) (3.7) with Clary's method II
//! (3.8)-(3.15), averaged over the periods of a periodic excitation
//! (Figure 3.7), with the magnitude-squared coherence per frequency line.
//!
//! Clary's method II: the plant `G_{u,y}(z) = z/(z-1) G_i(z)` (3.8), (3.11)
//! contains a known integrator. The output is prefiltered with
//! `V_2(z) = (z-1)/z` (3.14), i.e. the per-sample increment
//! `y_k - y_{k-1}`, which is periodic in the steady state even when the angle
//! drifts; the unknown part `G_i` is estimated from input and increment and
//! the integrator `z/(z-1)` is put back afterwards (3.15).
//!
//! Averaging: with `n_m` periods `U_p`, `V_p` (p = 1..n_m) the estimate is
//! `G_i = sum_p V_p conj(U_p) / sum_p |U_p|^2` (for an identical input in
//! every period this is the mean of the per-period ETFEs), and the coherence
//! is `gamma^2 = |sum V conj U|^2 / (sum |U|^2 sum |V|^2)`: 1 for a noise-free
//! linear response, lower where noise or nonlinearity dominates.

use crate::error::require_all_finite;
use crate::lti::C64;
use crate::{Error, Result};
use realfft::RealFftPlanner;
use std::f64::consts::PI;

/// Settings of the ETFE.
#[derive(Clone, Debug, PartialEq)]
pub struct EtfeConfig {
    /// Sampling time `T_s`, s.
    pub ts_s: f64,
    /// Samples per period of the excitation (the FFT length).
    pub period_samples: usize,
    /// Leading periods discarded as transient.
    pub skip_periods: usize,
    /// Apply Clary's method II with the known integrator `z/(z-1)` (3.11)
    /// (torque -> angle). `false`: plain ETFE (3.7) of input -> output.
    pub integrator: bool,
    /// Lines whose averaged input power is more than this many dB below the
    /// strongest line are marked [`LineStatus::NotExcited`] (a value `< 0`).
    pub excitation_floor_db: f64,
    /// Lines with a coherence below this are marked [`LineStatus::LowCoherence`].
    pub min_coherence: f64,
    /// Optional band `(low, high)` in Hz; lines outside are marked
    /// [`LineStatus::OutsideBand`].
    pub band_hz: Option<(f64, f64)>,
}

impl Default for EtfeConfig {
    fn default() -> Self {
        EtfeConfig {
            ts_s: 100e-6,
            period_samples: 1270,
            skip_periods: 1,
            integrator: true,
            excitation_floor_db: -40.0,
            min_coherence: 0.5,
            band_hz: None,
        }
    }
}

/// Why a frequency line is or is not used by the parametric fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum LineStatus {
    /// Excited, coherent, inside the band: used.
    Usable,
    /// The DC line (the integrator is infinite there).
    Dc,
    /// Outside the requested band.
    OutsideBand,
    /// The input has (almost) no power at this line.
    NotExcited,
    /// The coherence is below the threshold.
    LowCoherence,
}

impl LineStatus {
    /// Short lower-case label for files.
    pub fn label(self) -> &'static str {
        match self {
            LineStatus::Usable => "usable",
            LineStatus::Dc => "dc",
            LineStatus::OutsideBand => "outside_band",
            LineStatus::NotExcited => "not_excited",
            LineStatus::LowCoherence => "low_coherence",
        }
    }
}

/// A measured frequency response function on the FFT grid `k / (N T_s)`,
/// `k = 0 ..= N/2` (up to the Nyquist frequency).
#[derive(Clone, Debug, PartialEq)]
pub struct Frf {
    /// Line frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Complex response at each line (output unit per input unit; 0 at the DC
    /// line when the integrator is applied, see `line_status`).
    pub response: Vec<C64>,
    /// Magnitude-squared coherence per line, in `[0, 1]`.
    pub coherence: Vec<f64>,
    /// Per-line flag with the reason a line is excluded.
    pub line_status: Vec<LineStatus>,
    /// Averaged input power per line (|U|^2 / N^2), input unit squared.
    pub input_power: Vec<f64>,
    /// Sampling time, s.
    pub ts_s: f64,
    /// Number of averaged periods `n_m`.
    pub n_periods: usize,
}

impl Frf {
    /// Whether line `i` is used by the fit.
    pub fn is_usable(&self, i: usize) -> bool {
        self.line_status[i] == LineStatus::Usable
    }

    /// Indices of all usable lines, ascending.
    pub fn usable_indices(&self) -> Vec<usize> {
        (0..self.freq_hz.len())
            .filter(|&i| self.is_usable(i))
            .collect()
    }

    /// `20 log10 |G|` at line `i`, dB.
    pub fn magnitude_db(&self, i: usize) -> f64 {
        20.0 * self.response[i].norm().log10()
    }

    /// Line angular frequency `2 pi f`, rad/s.
    pub fn omega_rad_s(&self, i: usize) -> f64 {
        2.0 * PI * self.freq_hz[i]
    }

    /// The "nearly log-spaced" subset `F_o` of the usable lines (Figure 3.9):
    /// for `n_o` logarithmically spaced target frequencies between the lowest
    /// and highest usable line, the nearest usable line; duplicates removed,
    /// so the result may hold fewer than `n_o` lines.
    pub fn log_spaced_subset(&self, n_o: usize) -> Vec<usize> {
        let usable = self.usable_indices();
        log_spaced_subset(&self.freq_hz, &usable, n_o)
    }
}

/// Nearly log-spaced subset (Figure 3.9) of the lines `candidates` (indices
/// into `freq_hz`, ascending, all with `freq_hz > 0`).
pub fn log_spaced_subset(freq_hz: &[f64], candidates: &[usize], n_o: usize) -> Vec<usize> {
    if candidates.is_empty() || n_o == 0 {
        return Vec::new();
    }
    if n_o >= candidates.len() {
        return candidates.to_vec();
    }
    let lo = freq_hz[candidates[0]].ln();
    let hi = freq_hz[*candidates.last().expect("non-empty")].ln();
    let mut out: Vec<usize> = Vec::with_capacity(n_o);
    let mut j = 0; // candidates are ascending, so is the target
    for m in 0..n_o {
        let target = if n_o == 1 {
            lo
        } else {
            lo + (hi - lo) * m as f64 / (n_o - 1) as f64
        };
        while j + 1 < candidates.len()
            && (freq_hz[candidates[j + 1]].ln() - target).abs()
                <= (freq_hz[candidates[j]].ln() - target).abs()
        {
            j += 1;
        }
        if out.last() != Some(&candidates[j]) {
            out.push(candidates[j]);
        }
    }
    out
}

/// The ETFE of `input -> output` (both sampled at `cfg.ts_s`, same
/// length), with Clary's method II when `cfg.integrator`, averaged over all
/// complete periods after the `skip_periods` transient ones.
///
/// Errors: non-finite samples, length mismatch, fewer than two complete
/// periods after the skipped ones (the coherence needs two), a constant
/// input ([`Error::NoExcitation`]), invalid settings.
pub fn etfe(input: &[f64], output: &[f64], cfg: &EtfeConfig) -> Result<Frf> {
    validate_config(cfg)?;
    if input.len() != output.len() {
        return Err(Error::LengthMismatch {
            what: format!(
                "input has {} samples, output has {}",
                input.len(),
                output.len()
            ),
        });
    }
    require_all_finite("input", input)?;
    require_all_finite("output", output)?;
    let n = cfg.period_samples;
    // Checked: a huge period or skip count must be "too short", not an overflow.
    let needed = cfg
        .skip_periods
        .checked_add(2)
        .and_then(|p| p.checked_mul(n))
        .unwrap_or(usize::MAX);
    if input.len() < needed {
        return Err(Error::TooShort {
            what: format!(
                "{} skipped + 2 averaged periods of {} samples",
                cfg.skip_periods, n
            ),
            needed,
            got: input.len(),
        });
    }
    let n_periods = input.len() / n - cfg.skip_periods;

    // Clary's V_2 = (z-1)/z on the output: per-sample increments (3.14).
    let out_seq: Vec<f64> = if cfg.integrator {
        let mut v: Vec<f64> = output.windows(2).map(|w| w[1] - w[0]).collect();
        // The first sample has no predecessor: in the periodic steady state
        // its increment equals the one a period later.
        let first = v.get(n - 1).copied().unwrap_or(0.0);
        v.insert(0, first);
        v
    } else {
        output.to_vec()
    };

    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let n_lines = n / 2 + 1;
    let mut suu = vec![0.0; n_lines];
    let mut svv = vec![0.0; n_lines];
    let mut svu = vec![C64::new(0.0, 0.0); n_lines];
    let mut buf = fft.make_input_vec();
    let mut u_spec = fft.make_output_vec();
    let mut v_spec = fft.make_output_vec();
    for p in 0..n_periods {
        let start = (cfg.skip_periods + p) * n;
        buf.copy_from_slice(&input[start..start + n]);
        fft.process(&mut buf, &mut u_spec)
            .map_err(|e| Error::FitFailed {
                reason: format!("FFT: {e}"),
            })?;
        buf.copy_from_slice(&out_seq[start..start + n]);
        fft.process(&mut buf, &mut v_spec)
            .map_err(|e| Error::FitFailed {
                reason: format!("FFT: {e}"),
            })?;
        for k in 0..n_lines {
            suu[k] += u_spec[k].norm_sqr();
            svv[k] += v_spec[k].norm_sqr();
            svu[k] += v_spec[k] * u_spec[k].conj();
        }
    }

    let max_power = suu.iter().skip(1).cloned().fold(0.0, f64::max);
    let analysed = &input[cfg.skip_periods * n..(cfg.skip_periods + n_periods) * n];
    let constant = analysed.iter().all(|&x| x == analysed[0]);
    if constant || max_power <= 1e-24 * suu[0] {
        return Err(Error::NoExcitation {
            what:
                "the input is constant over the analysed periods (no power at any frequency line)"
                    .into(),
        });
    }
    let floor = max_power * 10f64.powf(cfg.excitation_floor_db / 10.0);
    let ts = cfg.ts_s;
    let df = 1.0 / (n as f64 * ts);
    let norm = (n_periods as f64) * (n as f64) * (n as f64);

    let mut frf = Frf {
        freq_hz: Vec::with_capacity(n_lines),
        response: Vec::with_capacity(n_lines),
        coherence: Vec::with_capacity(n_lines),
        line_status: Vec::with_capacity(n_lines),
        input_power: Vec::with_capacity(n_lines),
        ts_s: ts,
        n_periods,
    };
    for k in 0..n_lines {
        let f = k as f64 * df;
        let w = 2.0 * PI * f;
        let excited = suu[k] > floor && suu[k] > 0.0;
        let coh = if excited && svv[k] > 0.0 {
            (svu[k].norm_sqr() / (suu[k] * svv[k])).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut g = if excited {
            svu[k] / suu[k]
        } else {
            C64::new(0.0, 0.0)
        };
        let status = if k == 0 && cfg.integrator {
            g = C64::new(0.0, 0.0);
            LineStatus::Dc
        } else if k == 0 && !excited {
            LineStatus::Dc
        } else if cfg.band_hz.is_some_and(|(lo, hi)| f < lo || f > hi) {
            LineStatus::OutsideBand
        } else if !excited {
            LineStatus::NotExcited
        } else if coh < cfg.min_coherence {
            LineStatus::LowCoherence
        } else {
            LineStatus::Usable
        };
        if cfg.integrator && k > 0 {
            // put the known integrator z/(z-1) back (3.15)
            let z = C64::from_polar(1.0, w * ts);
            g *= z / (z - 1.0);
        }
        frf.freq_hz.push(f);
        frf.response.push(g);
        frf.coherence.push(coh);
        frf.line_status.push(status);
        frf.input_power.push(suu[k] / norm);
    }
    Ok(frf)
}

/// Fewest samples a period of the excitation may have (fewer hold no line
/// between the mean and the Nyquist frequency worth estimating).
pub const MIN_PERIOD_SAMPLES: usize = 4;

fn validate_config(cfg: &EtfeConfig) -> Result<()> {
    crate::error::require_positive("ts_s", cfg.ts_s)?;
    if cfg.period_samples < MIN_PERIOD_SAMPLES {
        return Err(Error::invalid(
            "period_samples",
            cfg.period_samples as f64,
            "a period needs at least 4 samples",
        ));
    }
    if cfg.period_samples > crate::ident::csv_columns::MAX_CSV_ROWS {
        return Err(Error::invalid(
            "period_samples",
            cfg.period_samples as f64,
            format!(
                "a period of more than {} samples is beyond the longest record",
                crate::ident::csv_columns::MAX_CSV_ROWS
            ),
        ));
    }
    if !(cfg.excitation_floor_db.is_finite() && cfg.excitation_floor_db < 0.0) {
        return Err(Error::invalid(
            "excitation_floor_db",
            cfg.excitation_floor_db,
            "must be finite and < 0 dB",
        ));
    }
    if !(0.0..=1.0).contains(&cfg.min_coherence) {
        return Err(Error::invalid(
            "min_coherence",
            cfg.min_coherence,
            "must lie in [0, 1]",
        ));
    }
    if let Some((lo, hi)) = cfg.band_hz {
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
            return Err(Error::invalid(
                "band_hz",
                lo,
                format!("band ({lo}, {hi}) Hz must satisfy 0 <= low < high"),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ident::testutil::{prbs, simulate_discrete};

    /// A known discrete system y_k = a y_{k-1} + b u_{k-1} (+ integrator):
    /// the ETFE on a periodic excitation equals the exact discrete response.
    #[test]
    fn exact_for_a_known_discrete_system() {
        let n = 127 * 4;
        let u = prbs(7, 4, 1.0, 6);
        let (a, b) = (0.9, 0.05);
        let vel = simulate_discrete(&u, a, b);
        // angle = running sum of velocity, so the increment is vel
        let mut phi = Vec::with_capacity(vel.len());
        let mut acc = 0.0;
        for v in &vel {
            acc += v;
            phi.push(acc);
        }
        let ts = 1e-3;
        let cfg = EtfeConfig {
            ts_s: ts,
            period_samples: n,
            skip_periods: 2,
            ..Default::default()
        };
        let frf = etfe(&u, &phi, &cfg).unwrap();
        assert_eq!(frf.n_periods, 4);
        // reference: z/(z-1) * b z^-1 / (1 - a z^-1)
        const TOL_REL: f64 = 1e-6; // transient decays as 0.9^(2 n) ~ 1e-46
        let mut checked = 0;
        for i in frf.usable_indices() {
            let z = C64::from_polar(1.0, frf.omega_rad_s(i) * ts);
            let exact = z / (z - 1.0) * b / z / (1.0 - a / z);
            assert!(
                (frf.response[i] - exact).norm() / exact.norm() < TOL_REL,
                "line {i}"
            );
            assert!(frf.coherence[i] > 1.0 - 1e-9);
            checked += 1;
        }
        assert!(checked > 100, "only {checked} usable lines");
        assert_eq!(frf.line_status[0], LineStatus::Dc);
    }

    #[test]
    fn noise_lowers_the_coherence_and_flags_lines() {
        use rand::{Rng, SeedableRng};
        let n = 127 * 4;
        let u = prbs(7, 4, 1.0, 6);
        let y = simulate_discrete(&u, 0.5, 1.0);
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let noisy: Vec<f64> = y
            .iter()
            .map(|v| v + 3.0 * (rng.random::<f64>() - 0.5))
            .collect();
        let cfg = EtfeConfig {
            ts_s: 1e-3,
            period_samples: n,
            skip_periods: 1,
            integrator: false,
            min_coherence: 0.9,
            ..Default::default()
        };
        let clean = etfe(&u, &y, &cfg).unwrap();
        let dirty = etfe(&u, &noisy, &cfg).unwrap();
        // mean over the excited lines (the clock period 4 leaves lines k N/4 unexcited)
        let mean = |f: &Frf| {
            let idx: Vec<usize> = (1..f.freq_hz.len())
                .filter(|&i| f.line_status[i] != LineStatus::NotExcited)
                .collect();
            idx.iter().map(|&i| f.coherence[i]).sum::<f64>() / idx.len() as f64
        };
        assert!(mean(&clean) > 0.999);
        assert!(mean(&dirty) < 0.9, "{}", mean(&dirty));
        assert!(dirty.line_status.contains(&LineStatus::LowCoherence));
    }

    #[test]
    fn bad_input_gives_typed_errors() {
        let cfg = EtfeConfig {
            period_samples: 100,
            skip_periods: 1,
            ..Default::default()
        };
        let u = vec![1.0; 300];
        let y = vec![0.0; 300];
        assert!(matches!(
            etfe(&u, &y, &cfg),
            Err(Error::NoExcitation { .. })
        ));
        assert!(matches!(
            etfe(&u[..250], &y[..250], &cfg),
            Err(Error::TooShort { .. })
        ));
        assert!(matches!(
            etfe(&u, &y[..299], &cfg),
            Err(Error::LengthMismatch { .. })
        ));
        let mut bad = u.clone();
        bad[17] = f64::NAN;
        assert!(matches!(
            etfe(&bad, &y, &cfg),
            Err(Error::NonFinite { index: 17, .. })
        ));
    }

    #[test]
    fn log_spaced_subset_is_nearly_logarithmic() {
        // Figure 3.9: n_f = 100 lines 5..500 Hz, n_o = 30
        let freq: Vec<f64> = (0..100).map(|k| 5.0 + 5.0 * k as f64).collect();
        let cand: Vec<usize> = (0..100).collect();
        let sub = log_spaced_subset(&freq, &cand, 30);
        assert!(sub.len() < 30 && sub.len() > 15, "{}", sub.len());
        assert_eq!(sub[0], 0);
        assert_eq!(*sub.last().unwrap(), 99);
        assert!(sub.windows(2).all(|w| w[0] < w[1]));
        // the low decade holds more points than a linear spacing would give
        let low = sub.iter().filter(|&&i| freq[i] < 50.0).count();
        assert!(low >= 8, "{low}");
    }
}
