//! Input shapers: trains of positive impulses whose convolution with a
//! motion command cancels the residual vibration of a lightly damped mode.
//!
//! The definitions are those Klipper publishes (`klippy/extras/shaper_defs.py`,
//! Klipper3d/klipper at 84104bb, GPLv3; written here again from its equations,
//! not copied): ZV and ZVD (Singer and Seering, "Preshaping command inputs to
//! reduce system vibration", 1990), MZV (Klipper's zero placement for `n`
//! impulses over `t` periods, default `n = 3`, `t = 0.75`), EI with a 5 %
//! vibration tolerance as Klipper's fit in the damping ratio, and the 2- and
//! 3-hump EI shapers as Klipper's cubic expansions in the damping ratio
//! (Singhose, Seering and Singer, "Residual vibration reduction using vector
//! diagrams to generate shaping inputs", 1994, closed forms at zero damping).
//! The residual vibration [`Shaper::residual_vibration`] and the smoothing
//! [`Shaper::smoothing_m`] follow Klipper's `shaper_calibrate.py`.

use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Klipper's vibration tolerance of the EI family: 1 / 20 (5 %).
pub const EI_VIBRATION_TOLERANCE: f64 = 1.0 / 20.0;

/// Klipper's default damping ratio a shaper is designed for.
pub const DEFAULT_DAMPING_RATIO: f64 = 0.1;

/// The shapers Klipper defines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShaperKind {
    /// Zero vibration: two impulses half a damped period apart.
    Zv,
    /// Modified ZV: three impulses over 0.75 damped periods.
    Mzv,
    /// ZV derivative: three impulses over one damped period.
    Zvd,
    /// Extra insensitive (5 % at the design frequency), one period.
    Ei,
    /// Two-hump extra insensitive, 1.5 periods.
    TwoHumpEi,
    /// Three-hump extra insensitive, 2 periods.
    ThreeHumpEi,
}

impl ShaperKind {
    /// Every shaper Klipper defines, in its order.
    pub const ALL: [ShaperKind; 6] = [
        ShaperKind::Zv,
        ShaperKind::Mzv,
        ShaperKind::Zvd,
        ShaperKind::Ei,
        ShaperKind::TwoHumpEi,
        ShaperKind::ThreeHumpEi,
    ];

    /// The shapers Klipper's automatic calibration tries (`AUTOTUNE_SHAPERS`),
    /// in its order.
    pub const AUTOTUNE: [ShaperKind; 5] = [
        ShaperKind::Zv,
        ShaperKind::Mzv,
        ShaperKind::Ei,
        ShaperKind::TwoHumpEi,
        ShaperKind::ThreeHumpEi,
    ];

    /// Klipper's name (`zv`, `mzv`, `zvd`, `ei`, `2hump_ei`, `3hump_ei`).
    pub fn name(self) -> &'static str {
        match self {
            ShaperKind::Zv => "zv",
            ShaperKind::Mzv => "mzv",
            ShaperKind::Zvd => "zvd",
            ShaperKind::Ei => "ei",
            ShaperKind::TwoHumpEi => "2hump_ei",
            ShaperKind::ThreeHumpEi => "3hump_ei",
        }
    }

    /// Klipper's lowest default shaper frequency (chosen there for a
    /// projected maximum acceleration of about 1.5 m/s^2), Hz.
    pub fn klipper_min_freq_hz(self) -> f64 {
        match self {
            ShaperKind::Zv => 21.0,
            ShaperKind::Mzv => 23.0,
            ShaperKind::Zvd | ShaperKind::Ei => 29.0,
            ShaperKind::TwoHumpEi => 39.0,
            ShaperKind::ThreeHumpEi => 48.0,
        }
    }

    /// Largest damping ratio Klipper accepts for the shaper.
    pub fn max_damping_ratio(self) -> f64 {
        match self {
            ShaperKind::Zv | ShaperKind::Mzv | ShaperKind::Zvd => 0.99,
            ShaperKind::Ei => 0.4,
            ShaperKind::TwoHumpEi => 0.3,
            ShaperKind::ThreeHumpEi => 0.2,
        }
    }

    /// The shaper for a mode of frequency `freq_hz` (undamped, Hz) and
    /// damping ratio `damping_ratio`.
    pub fn design(self, freq_hz: f64, damping_ratio: f64) -> Result<Shaper> {
        if !(freq_hz.is_finite() && freq_hz > 0.0) {
            return Err(Error::invalid(
                "shaper freq_hz",
                freq_hz,
                "must be finite and positive",
            ));
        }
        if !(damping_ratio.is_finite()
            && damping_ratio >= 0.0
            && damping_ratio <= self.max_damping_ratio())
        {
            return Err(Error::invalid(
                "shaper damping_ratio",
                damping_ratio,
                format!(
                    "must be in [0, {}] for the {} shaper",
                    self.max_damping_ratio(),
                    self.name()
                ),
            ));
        }
        let df = (1.0 - damping_ratio * damping_ratio).sqrt();
        // damped period, s
        let t_d = 1.0 / (freq_hz * df);
        let k = (-damping_ratio * PI / df).exp();
        let (amplitudes, times_s) = match self {
            ShaperKind::Zv => (vec![1.0, k], vec![0.0, 0.5 * t_d]),
            ShaperKind::Zvd => (vec![1.0, 2.0 * k, k * k], vec![0.0, 0.5 * t_d, t_d]),
            ShaperKind::Mzv => mzv(3, 0.75, damping_ratio, t_d)?,
            ShaperKind::Ei => ei(EI_VIBRATION_TOLERANCE, damping_ratio, t_d),
            ShaperKind::TwoHumpEi => expansion(&TWO_HUMP_T, &TWO_HUMP_A, damping_ratio, freq_hz),
            ShaperKind::ThreeHumpEi => {
                expansion(&THREE_HUMP_T, &THREE_HUMP_A, damping_ratio, freq_hz)
            }
        };
        Shaper::new(amplitudes, times_s)
    }
}

/// An input shaper: impulses of amplitude `amplitudes[i]` at `times_s[i]`
/// (the first at 0), amplitudes normalized to sum 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Shaper {
    /// Impulse amplitudes (positive, sum 1).
    pub amplitudes: Vec<f64>,
    /// Impulse times, s (ascending, the first 0).
    pub times_s: Vec<f64>,
}

impl Shaper {
    /// A shaper from impulses; the amplitudes are normalized to sum 1.
    /// Errors for an empty train, unequal lengths, a negative or non-finite
    /// amplitude, or times that are not finite, ascending and from 0.
    pub fn new(amplitudes: Vec<f64>, times_s: Vec<f64>) -> Result<Shaper> {
        if amplitudes.is_empty() || amplitudes.len() != times_s.len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "shaper with {} amplitudes and {} times (needs equal, at least one)",
                    amplitudes.len(),
                    times_s.len()
                ),
            });
        }
        for &a in &amplitudes {
            if !(a.is_finite() && a >= -1e-5) {
                return Err(Error::invalid(
                    "shaper amplitude",
                    a,
                    "must be finite and not negative",
                ));
            }
        }
        let sum: f64 = amplitudes.iter().sum();
        if sum.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::invalid(
                "shaper amplitude sum",
                sum,
                "must be positive",
            ));
        }
        if times_s[0] != 0.0 || times_s.windows(2).any(|w| w[1] < w[0] || w[1].is_nan()) {
            return Err(Error::invalid(
                "shaper times_s",
                times_s[0],
                "must be finite, ascending and start at 0",
            ));
        }
        if times_s.iter().any(|t| !t.is_finite()) {
            return Err(Error::invalid("shaper times_s", f64::NAN, "must be finite"));
        }
        Ok(Shaper {
            amplitudes: amplitudes.iter().map(|a| a.max(0.0) / sum).collect(),
            times_s,
        })
    }

    /// The identity (one impulse at 0): no shaping.
    pub fn none() -> Shaper {
        Shaper {
            amplitudes: vec![1.0],
            times_s: vec![0.0],
        }
    }

    /// Duration (time of the last impulse), s.
    pub fn duration_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }

    /// The convolution of two shapers (both modes cancelled), merged where
    /// impulses coincide within 1 ns.
    pub fn convolve(&self, other: &Shaper) -> Shaper {
        let mut pairs: Vec<(f64, f64)> = Vec::new();
        for (a, t) in self.amplitudes.iter().zip(&self.times_s) {
            for (b, u) in other.amplitudes.iter().zip(&other.times_s) {
                pairs.push((t + u, a * b));
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut times_s: Vec<f64> = Vec::new();
        let mut amplitudes: Vec<f64> = Vec::new();
        for (t, a) in pairs {
            match times_s.last() {
                Some(&last) if (t - last).abs() < 1e-9 => {
                    if let Some(x) = amplitudes.last_mut() {
                        *x += a;
                    }
                }
                _ => {
                    times_s.push(t);
                    amplitudes.push(a);
                }
            }
        }
        Shaper {
            amplitudes,
            times_s,
        }
    }

    /// Residual vibration after the shaped command, as a fraction of the
    /// unshaped command's, for a mode of (undamped) frequency `freq_hz` and
    /// damping ratio `damping_ratio` (the classic percentage vibration of
    /// Singer and Seering; Klipper's `_estimate_shaper`).
    pub fn residual_vibration(&self, freq_hz: f64, damping_ratio: f64) -> f64 {
        let omega = 2.0 * PI * freq_hz;
        let decay = damping_ratio * omega;
        let omega_d = omega * (1.0 - damping_ratio * damping_ratio).max(0.0).sqrt();
        let t_end = self.duration_s();
        let (mut s, mut c) = (0.0, 0.0);
        for (a, t) in self.amplitudes.iter().zip(&self.times_s) {
            let w = a * (-decay * (t_end - t)).exp();
            s += w * (omega_d * t).sin();
            c += w * (omega_d * t).cos();
        }
        (s * s + c * c).sqrt()
    }

    /// The largest residual vibration over the damping ratios `damping_ratios`.
    pub fn worst_residual_vibration(&self, freq_hz: f64, damping_ratios: &[f64]) -> f64 {
        damping_ratios
            .iter()
            .map(|&z| self.residual_vibration(freq_hz, z))
            .fold(0.0, f64::max)
    }

    /// Klipper's smoothing (`_get_shaper_smoothing`), m: the larger of the
    /// path offsets of a 90 and a 180 degree turn at acceleration
    /// `accel_m_s2` and square-corner velocity `scv_m_s` (Klipper's defaults
    /// 5 m/s^2 and 5 mm/s).
    pub fn smoothing_m(&self, accel_m_s2: f64, scv_m_s: f64) -> f64 {
        let half_accel = 0.5 * accel_m_s2;
        let ts: f64 = self
            .amplitudes
            .iter()
            .zip(&self.times_s)
            .map(|(a, t)| a * t)
            .sum();
        let (mut offset_90, mut offset_180) = (0.0, 0.0);
        for (a, t) in self.amplitudes.iter().zip(&self.times_s) {
            let dt = t - ts;
            if *t >= ts {
                offset_90 += a * (scv_m_s + half_accel * dt) * dt;
            }
            offset_180 += a * half_accel * dt * dt;
        }
        (offset_90 * 2f64.sqrt()).max(offset_180)
    }

    /// Klipper's suggested maximum acceleration (`find_shaper_max_accel`):
    /// the largest acceleration whose smoothing at `scv_m_s` stays within
    /// 0.12 mm, m/s^2 (bisection as Klipper's, in its mm units).
    pub fn max_accel_m_s2(&self, scv_m_s: f64) -> f64 {
        const TARGET_SMOOTHING_M: f64 = 0.12e-3;
        // Klipper bisects in mm/s^2 from 1 mm/s^2 to 1e-8 mm/s^2 resolution.
        let ok = |a_mm: f64| self.smoothing_m(a_mm * 1e-3, scv_m_s) <= TARGET_SMOOTHING_M;
        if !ok(1e-9) {
            return 0.0;
        }
        let (mut left, mut right) = (1.0_f64, 1.0_f64);
        while !ok(left) {
            right = left;
            left *= 0.5;
        }
        if right == left {
            while ok(right) && right < 1e12 {
                right *= 2.0;
            }
        }
        while right - left > 1e-8 {
            let middle = 0.5 * (left + right);
            if ok(middle) {
                left = middle;
            } else {
                right = middle;
            }
        }
        left * 1e-3
    }

    /// The band of frequencies around `design_freq_hz` over which the
    /// residual vibration, worst over `damping_ratios`, is reduced to
    /// `tolerance`, as `(low, high)` in Hz: scanning outward from the design
    /// frequency in steps of 0.01 % of it (out to a factor 3) until the
    /// vibration exceeds `tolerance` by 2 percentage points, the last
    /// frequency on each side at or below `tolerance`. The humps inside the band of the EI
    /// family (5 % at damping 0.1) reach 6-7 % when the damping ratio differs;
    /// Klipper's table of bands (docs/Resonance_Compensation.md) spans
    /// them. `None` when no frequency on a side reaches `tolerance` (ZV at 5 %).
    pub fn band_hz(
        &self,
        design_freq_hz: f64,
        damping_ratios: &[f64],
        tolerance: f64,
    ) -> Option<(f64, f64)> {
        let v = |f: f64| self.worst_residual_vibration(f, damping_ratios);
        let hump_max = tolerance + 0.02;
        let step = 1e-4 * design_freq_hz;
        let edge = |dir: f64| -> Option<f64> {
            let mut last_ok = None;
            let mut k = 0usize;
            loop {
                let f = design_freq_hz + dir * k as f64 * step;
                if f <= 0.0 || f > 3.0 * design_freq_hz {
                    break;
                }
                let x = v(f);
                if x > hump_max {
                    break;
                }
                if x <= tolerance {
                    last_ok = Some(f);
                }
                k += 1;
            }
            last_ok
        };
        Some((edge(-1.0)?, edge(1.0)?))
    }
}

/// Klipper's MZV: `n` impulses equally spaced over `t` damped periods whose
/// zeros lie at `1 + i / tau` times the design frequency (`tau` the duration
/// projected to infinitely many impulses), amplitudes from the least-squares
/// solution (pseudo-inverse) of `sum A = 1` and the zero conditions, then
/// damped by `K^i`.
fn mzv(n: usize, t: f64, damping_ratio: f64, t_d: f64) -> Result<(Vec<f64>, Vec<f64>)> {
    let nf = n as f64;
    if n < 3 || nf <= 2.0 * t + 1.0 + 1e-7 {
        return Err(Error::invalid(
            "mzv duration t",
            t,
            format!("needs n >= 3 and t < (n - 1) / 2 (n = {n})"),
        ));
    }
    let tau = t * (nf - 2.0) / (nf - 2.0 * t - 1.0);
    let times: Vec<f64> = (0..n).map(|i| i as f64 * t / (nf - 1.0)).collect();
    let rows = 1 + 2 * (n - 1);
    let mut m = nalgebra::DMatrix::<f64>::zeros(rows, n);
    let mut rhs = nalgebra::DVector::<f64>::zeros(rows);
    for j in 0..n {
        m[(0, j)] = 1.0;
    }
    rhs[0] = 1.0;
    for i in 0..n - 1 {
        for (j, tj) in times.iter().enumerate() {
            let w = 2.0 * PI * (1.0 + i as f64 / tau) * tj;
            m[(1 + 2 * i, j)] = w.cos();
            m[(2 + 2 * i, j)] = w.sin();
        }
    }
    let pinv = m
        .pseudo_inverse(1e-12)
        .map_err(|_| Error::invalid("mzv duration t", t, "ill-formed shaper"))?;
    let a = pinv * rhs;
    if a.iter().any(|&x| x < -1e-5 || !x.is_finite()) {
        return Err(Error::invalid(
            "mzv duration t",
            t,
            "gives negative impulses",
        ));
    }
    let df = (1.0 - damping_ratio * damping_ratio).sqrt();
    let k = (-2.0 * t * damping_ratio * PI / ((nf - 1.0) * df)).exp();
    let mut amplitudes = Vec::with_capacity(n);
    let mut kp = 1.0;
    for x in a.iter() {
        amplitudes.push(x * kp);
        kp *= k;
    }
    let times_s = times.iter().map(|x| x * t_d).collect();
    Ok((amplitudes, times_s))
}

/// Klipper's EI: amplitudes and the middle impulse's time as quadratic and
/// cubic fits in the damping ratio for vibration tolerance `v_tol`.
fn ei(v_tol: f64, dr: f64, t_d: f64) -> (Vec<f64>, Vec<f64>) {
    let a1 = (0.24968 + 0.24961 * v_tol)
        + ((0.80008 + 1.23328 * v_tol) + (0.49599 + 3.17316 * v_tol) * dr) * dr;
    let a3 = (0.25149 + 0.21474 * v_tol)
        + ((-0.83249 + 1.41498 * v_tol) + (0.85181 - 4.90094 * v_tol) * dr) * dr;
    let a2 = 1.0 - a1 - a3;
    let t2 = 0.4999
        + (((0.46159 + 8.57843 * v_tol) * v_tol)
            + (((4.26169 - 108.644 * v_tol) * v_tol) + ((1.75601 + 336.989 * v_tol) * v_tol) * dr)
                * dr)
            * dr;
    (vec![a1, a2, a3], vec![0.0, t2 * t_d, t_d])
}

/// Klipper's 2-hump EI expansion: impulse times (in undamped periods) and
/// amplitudes as cubics in the damping ratio, coefficients by ascending power.
const TWO_HUMP_T: [[f64; 4]; 4] = [
    [0.0, 0.0, 0.0, 0.0],
    [0.49890, 0.16270, -0.54262, 6.16180],
    [0.99748, 0.18382, -1.58270, 8.17120],
    [1.49920, -0.09297, -0.28338, 1.85710],
];
const TWO_HUMP_A: [[f64; 4]; 4] = [
    [0.16054, 0.76699, 2.26560, -1.22750],
    [0.33911, 0.45081, -2.58080, 1.73650],
    [0.34089, -0.61533, -0.68765, 0.42261],
    [0.15997, -0.60246, 1.00280, -0.93145],
];
/// Klipper's 3-hump EI expansion (as [`TWO_HUMP_T`]).
const THREE_HUMP_T: [[f64; 4]; 5] = [
    [0.0, 0.0, 0.0, 0.0],
    [0.49974, 0.23834, 0.44559, 12.4720],
    [0.99849, 0.29808, -2.36460, 23.3990],
    [1.49870, 0.10306, -2.01390, 17.0320],
    [1.99960, -0.28231, 0.61536, 5.40450],
];
const THREE_HUMP_A: [[f64; 4]; 5] = [
    [0.11275, 0.76632, 3.29160, -1.44380],
    [0.23698, 0.61164, -2.57850, 4.85220],
    [0.30008, -0.19062, -2.14560, 0.13744],
    [0.23775, -0.73297, 0.46885, -2.08650],
    [0.11244, -0.45439, 0.96382, -1.46000],
];

fn expansion<const N: usize>(
    t: &[[f64; 4]; N],
    a: &[[f64; 4]; N],
    dr: f64,
    freq_hz: f64,
) -> (Vec<f64>, Vec<f64>) {
    let poly = |c: &[f64; 4]| c[0] + dr * (c[1] + dr * (c[2] + dr * c[3]));
    let period = 1.0 / freq_hz;
    let times_s = t.iter().map(|c| poly(c) * period).collect();
    let amplitudes = a.iter().map(poly).collect();
    (amplitudes, times_s)
}
