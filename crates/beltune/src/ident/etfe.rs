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
//!
//! Line selection by the excitation itself: only lines the input really
//! excites enter the FRF's usable set (and so the fit and the dead time):
//! - the line's input power lies within `excitation_floor_db` of the
//!   strongest line (a PRBS' spectral nulls at multiples of its clock
//!   frequency, the lines outside a chirp's sweep);
//! - and within `local_floor_db` of the strongest line within
//!   [`LOCAL_WINDOW_LINES`] lines either side: a sparse multisine (odd, or
//!   random-phase with lines left out on purpose to see nonlinear
//!   distortion) leaves lines between excited ones that carry only leakage,
//!   quantization or distortion of the input, however far above the global
//!   floor; a smooth spectrum (PRBS, chirp, full multisine) loses nothing;
//! - and, with several periods, the input at the line is periodic: its
//!   periodic part `|mean_p U_p|^2` stands well above the variance of that
//!   mean estimated from the periods' scatter ([`input_periodic_threshold`]) (a measured current carries noise at lines
//!   its reference never excited, which a foreign recording may use as input).

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
    /// Lines whose input power is more than this many dB below the strongest
    /// line within [`LOCAL_WINDOW_LINES`] either side are marked
    /// [`LineStatus::NotExcited`] (a value `< 0`; sparse multisines).
    pub local_floor_db: f64,
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
            local_floor_db: -20.0,
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
    /// The input has (almost) no power at this line, globally or against
    /// its neighbours.
    NotExcited,
    /// The input's power at this line is not periodic (noise in a measured
    /// input, not excitation).
    InputNoise,
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
            LineStatus::InputNoise => "input_noise",
            LineStatus::LowCoherence => "low_coherence",
        }
    }

    /// Why a line is left out, in words (for summaries).
    pub fn reason(self) -> &'static str {
        match self {
            LineStatus::Usable => "used",
            LineStatus::Dc => "the DC line",
            LineStatus::OutsideBand => "outside the requested band",
            LineStatus::NotExcited => "not excited by the input",
            LineStatus::InputNoise => "input not periodic there (noise)",
            LineStatus::LowCoherence => "coherence below the threshold",
        }
    }
}

/// Half-width, in lines, of the neighbourhood of the local floor.
pub const LOCAL_WINDOW_LINES: usize = 8;
/// Probability with which a line of pure input noise passes the periodicity
/// test. For `n_m` periods of Gaussian noise the ratio
/// `(n_m - 1) |sum U|^2 / n_m / sum |U_p - mean|^2` follows an F(2, 2 (n_m - 1))
/// distribution, so the threshold is `(n_m - 1) (P^(-1/(n_m - 1)) - 1)`:
/// 12 (10.8 dB) for 19 periods, 22 for 7.
pub const INPUT_NOISE_FALSE_PASS: f64 = 1e-4;
/// Cap of that threshold (30 dB; two periods would otherwise need 40 dB).
pub const MAX_INPUT_PERIODIC_SNR: f64 = 1000.0;

/// The periodicity threshold for `n_m` periods (see [`INPUT_NOISE_FALSE_PASS`]).
pub fn input_periodic_threshold(n_m: usize) -> f64 {
    let d = n_m.saturating_sub(1).max(1) as f64;
    (d * (INPUT_NOISE_FALSE_PASS.powf(-1.0 / d) - 1.0)).min(MAX_INPUT_PERIODIC_SNR)
}

/// How many lines carry each [`LineStatus`], in the order of the enum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct LineCounts {
    /// Lines used by the fit.
    pub usable: usize,
    /// The DC line (0 or 1).
    pub dc: usize,
    /// Outside the requested band.
    pub outside_band: usize,
    /// Not excited (global or local floor).
    pub not_excited: usize,
    /// Input not periodic.
    pub input_noise: usize,
    /// Coherence too low.
    pub low_coherence: usize,
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

    /// How many lines carry each status.
    pub fn line_counts(&self) -> LineCounts {
        let mut c = LineCounts::default();
        for s in &self.line_status {
            *match s {
                LineStatus::Usable => &mut c.usable,
                LineStatus::Dc => &mut c.dc,
                LineStatus::OutsideBand => &mut c.outside_band,
                LineStatus::NotExcited => &mut c.not_excited,
                LineStatus::InputNoise => &mut c.input_noise,
                LineStatus::LowCoherence => &mut c.low_coherence,
            } += 1;
        }
        c
    }

    /// One line of text: which lines are used and why the others are not.
    pub fn line_summary(&self) -> String {
        let c = self.line_counts();
        let used = self.usable_indices();
        let band = match (used.first(), used.last()) {
            (Some(&a), Some(&b)) => format!(
                " ({} to {} Hz)",
                crate::error::short_number(self.freq_hz[a]),
                crate::error::short_number(self.freq_hz[b])
            ),
            _ => String::new(),
        };
        let mut out = format!("{} of {} lines used{band}", c.usable, self.freq_hz.len());
        for (n, s) in [
            (c.not_excited, LineStatus::NotExcited),
            (c.input_noise, LineStatus::InputNoise),
            (c.low_coherence, LineStatus::LowCoherence),
            (c.outside_band, LineStatus::OutsideBand),
        ] {
            if n > 0 {
                out.push_str(&format!("; {n} {}", s.reason()));
            }
        }
        out
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
    let mut su = vec![C64::new(0.0, 0.0); n_lines];
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
            su[k] += u_spec[k];
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
    let local_ratio = 10f64.powf(cfg.local_floor_db / 10.0);
    let periodic_threshold = input_periodic_threshold(n_periods);
    let m = n_periods as f64;
    for k in 0..n_lines {
        let f = k as f64 * df;
        let w = 2.0 * PI * f;
        let lo = k.saturating_sub(LOCAL_WINDOW_LINES).max(1);
        let hi = (k + LOCAL_WINDOW_LINES + 1).min(n_lines);
        let local_max = suu[lo.min(hi)..hi].iter().cloned().fold(0.0, f64::max);
        let excited =
            suu[k] > floor && suu[k] > 0.0 && (k == 0 || suu[k] >= local_ratio * local_max);
        // periodic part |sum U|^2 / n_m against the scatter sum |U_p - mean|^2
        let periodic = su[k].norm_sqr() / m;
        let scatter = (suu[k] - periodic).max(0.0);
        let input_periodic =
            scatter <= 1e-12 * suu[k] || (m - 1.0) * periodic >= periodic_threshold * scatter;
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
        } else if !input_periodic {
            LineStatus::InputNoise
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
    if !(cfg.local_floor_db.is_finite() && cfg.local_floor_db < 0.0) {
        return Err(Error::invalid(
            "local_floor_db",
            cfg.local_floor_db,
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

    /// The PRBS' spectral nulls: with the clock period 4 every 127th line of
    /// a 508-sample period carries exactly no power (`sinc^2` of the held
    /// value, thesis 3.2); those lines, and only lines next to them, are left
    /// out on a noise-free record.
    #[test]
    fn prbs_nulls_are_not_excited() {
        let n = 127 * 4;
        let u = prbs(7, 4, 1.0, 4);
        let y = simulate_discrete(&u, 0.5, 1.0);
        let cfg = EtfeConfig {
            ts_s: 1e-3,
            period_samples: n,
            skip_periods: 1,
            integrator: false,
            ..Default::default()
        };
        let frf = etfe(&u, &y, &cfg).unwrap();
        assert_eq!(frf.line_status[127], LineStatus::NotExcited);
        assert_eq!(frf.line_status[254], LineStatus::NotExcited);
        for k in 1..=254usize {
            let d = (k % 127).min(127 - k % 127);
            if d >= 2 {
                assert_eq!(frf.line_status[k], LineStatus::Usable, "line {k}");
            }
        }
        assert!(
            frf.line_summary().contains("not excited"),
            "{}",
            frf.line_summary()
        );
    }

    /// A random-phase odd multisine with detection lines left out on purpose
    /// (every fourth odd line, seeded), played through a system with a cubic
    /// output nonlinearity and measured with noise on the input (a measured
    /// current) and the output: only the excited lines are used, although the
    /// input noise at the others stands 30 dB below the excited lines (above
    /// the global -40 dB floor) and the output carries distortion there.
    #[test]
    fn sparse_multisine_uses_only_the_excited_lines() {
        use rand::{Rng, SeedableRng};
        let n = 1024;
        let periods = 6;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(28);
        let odd: Vec<usize> = (1..200).step_by(2).collect();
        let excited: Vec<usize> = odd
            .iter()
            .copied()
            .filter(|_| rng.random::<f64>() > 0.25)
            .collect();
        let amp = 1.0;
        let phases: Vec<f64> = excited
            .iter()
            .map(|_| 2.0 * PI * rng.random::<f64>())
            .collect();
        let one: Vec<f64> = (0..n)
            .map(|t| {
                excited
                    .iter()
                    .zip(&phases)
                    .map(|(&h, &ph)| amp * (2.0 * PI * (h * t) as f64 / n as f64 + ph).cos())
                    .sum()
            })
            .collect();
        let u_ref: Vec<f64> = one.iter().cycle().take(n * periods).copied().collect();
        let lin = simulate_discrete(&u_ref, 0.9, 0.1);
        let peak = lin.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        // sigma = amp sqrt(N 1e-3) / 2: per-line input noise power 30 dB below an excited line
        let sigma_u = 0.5 * amp * (n as f64 * 1e-3).sqrt();
        let gauss = |rng: &mut rand_xoshiro::Xoshiro256PlusPlus| {
            // Box-Muller
            let (a, b): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
            (-2.0 * a.ln()).sqrt() * (2.0 * PI * b).cos()
        };
        let u_meas: Vec<f64> = u_ref
            .iter()
            .map(|&x| x + sigma_u * gauss(&mut rng))
            .collect();
        let y: Vec<f64> = lin
            .iter()
            .map(|&v| v + 0.3 * v.powi(3) / peak.powi(2) + 1e-3 * peak * gauss(&mut rng))
            .collect();
        let cfg = EtfeConfig {
            ts_s: 1e-3,
            period_samples: n,
            skip_periods: 1,
            integrator: false,
            ..Default::default()
        };
        let frf = etfe(&u_meas, &y, &cfg).unwrap();
        let used = frf.usable_indices();
        let strongest = frf.input_power[1..].iter().cloned().fold(0.0, f64::max);
        let above_global = (1..=n / 2)
            .filter(|k| !excited.contains(k) && frf.input_power[*k] > 1e-4 * strongest)
            .count();
        assert!(
            above_global > 100,
            "the test must put noise above the global floor: {above_global}"
        );
        for &k in &used {
            assert!(excited.contains(&k), "line {k} used but not excited");
        }
        for &k in &excited {
            assert_eq!(frf.line_status[k], LineStatus::Usable, "excited line {k}");
        }
        // the exactly periodic reference as input: the same selection
        let frf_ref = etfe(&u_ref, &y, &cfg).unwrap();
        assert_eq!(frf_ref.usable_indices(), excited);
    }

    /// A full multisine over lines 1..=100 and a measured input whose noise
    /// beyond the band is 30 dB below the excitation (above the global floor,
    /// far from any excited neighbour): those lines are input noise.
    #[test]
    fn input_noise_beyond_the_band_is_recognized() {
        use rand::{Rng, SeedableRng};
        let n = 1024;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(29);
        let one: Vec<f64> = (0..n)
            .map(|t| {
                (1..=100usize)
                    .map(|h| (2.0 * PI * (h * t) as f64 / n as f64 + 0.01 * (h * h) as f64).cos())
                    .sum()
            })
            .collect();
        let sigma_u = 0.5 * (n as f64 * 1e-3).sqrt();
        let u: Vec<f64> = one
            .iter()
            .cycle()
            .take(n * 8)
            .map(|&x| x + sigma_u * (rng.random::<f64>() - 0.5) * 12f64.sqrt())
            .collect();
        let y = simulate_discrete(&u, 0.9, 0.1);
        let cfg = EtfeConfig {
            ts_s: 1e-3,
            period_samples: n,
            skip_periods: 1,
            integrator: false,
            ..Default::default()
        };
        let frf = etfe(&u, &y, &cfg).unwrap();
        assert_eq!(frf.usable_indices(), (1..=100).collect::<Vec<_>>());
        let c = frf.line_counts();
        assert!(c.input_noise > 300, "{c:?}");
        assert!(frf.line_summary().contains("input not periodic"));
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
