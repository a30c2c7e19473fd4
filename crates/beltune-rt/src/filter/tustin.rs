//! Tustin (bilinear) transform with frequency pre-warping, and the thesis'
//! continuous filter designs turned into discrete sections.
//!
//! With `s = K (1 - z^-1) / (1 + z^-1)`, `K = 2/T_s` (plain Tustin) or
//! `K = w_p / tan(w_p T_s / 2)` (pre-warped at `w_p`), the discrete response
//! equals the continuous one exactly at `w_p`.

use super::{FirstOrderCoeffs, SosCoeffs};
use crate::error::{positive, Error};

/// Where the Tustin transform is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Prewarp {
    /// Plain Tustin, `K = 2 / T_s` (exact at 0 only).
    None,
    /// Pre-warped at this angular frequency in rad/s (must lie below Nyquist).
    At(f64),
}

fn tustin_gain(ts_s: f64, prewarp: Prewarp) -> Result<f64, Error> {
    let ts = positive("ts_s", ts_s)?;
    match prewarp {
        Prewarp::None => Ok(2.0 / ts),
        Prewarp::At(w) => {
            let w = positive("prewarp_rad_s", w)?;
            if w * ts >= core::f64::consts::PI {
                return Err(Error::InvalidParameter {
                    name: "prewarp_rad_s",
                    reason: "must lie below the Nyquist frequency pi/T_s",
                });
            }
            Ok(w / libm::tan(0.5 * w * ts))
        }
    }
}

/// Discretize `(n2 s^2 + n1 s + n0) / (d2 s^2 + d1 s + d0)` by Tustin.
/// `num = [n2, n1, n0]`, `den = [d2, d1, d0]` (highest power first).
pub fn sos_from_continuous(
    num: [f64; 3],
    den: [f64; 3],
    ts_s: f64,
    prewarp: Prewarp,
) -> Result<SosCoeffs<f64>, Error> {
    let k = tustin_gain(ts_s, prewarp)?;
    let k2 = k * k;
    let map = |p: [f64; 3]| {
        [
            p[0] * k2 + p[1] * k + p[2],
            2.0 * (p[2] - p[0] * k2),
            p[0] * k2 - p[1] * k + p[2],
        ]
    };
    let b = map(num);
    let a = map(den);
    if !(a[0].is_finite() && a[0] != 0.0 && b.iter().chain(a.iter()).all(|x| x.is_finite())) {
        return Err(Error::InvalidParameter {
            name: "den",
            reason: "continuous denominator degenerates under the Tustin transform",
        });
    }
    Ok(SosCoeffs {
        b0: b[0] / a[0],
        b1: b[1] / a[0],
        b2: b[2] / a[0],
        a1: a[1] / a[0],
        a2: a[2] / a[0],
    })
}

/// Discretize `(n1 s + n0) / (d1 s + d0)` by Tustin. Arrays highest power first.
pub fn first_order_from_continuous(
    num: [f64; 2],
    den: [f64; 2],
    ts_s: f64,
    prewarp: Prewarp,
) -> Result<FirstOrderCoeffs<f64>, Error> {
    let k = tustin_gain(ts_s, prewarp)?;
    let b = [num[0] * k + num[1], num[1] - num[0] * k];
    let a = [den[0] * k + den[1], den[1] - den[0] * k];
    if !(a[0].is_finite() && a[0] != 0.0 && b.iter().chain(a.iter()).all(|x| x.is_finite())) {
        return Err(Error::InvalidParameter {
            name: "den",
            reason: "continuous denominator degenerates under the Tustin transform",
        });
    }
    Ok(FirstOrderCoeffs {
        b0: b[0] / a[0],
        b1: b[1] / a[0],
        a1: a[1] / a[0],
    })
}

/// The notch (4.1) centred at `w_r_rad_s` with width parameter `d_n > 0`,
/// pre-warped at its centre so the notch lands exactly on `w_r`.
pub fn notch(w_r_rad_s: f64, d_n: f64, ts_s: f64) -> Result<SosCoeffs<f64>, Error> {
    let w = positive("w_r_rad_s", w_r_rad_s)?;
    let d = positive("d_n", d_n)?;
    sos_from_continuous(
        [1.0, 2.0 * w / d, w * w],
        [1.0, 2.0 * d * w, w * w],
        ts_s,
        Prewarp::At(w),
    )
}

/// The 2nd-order Butterworth low-pass (4.3) with cut-off `w_bw_rad_s`,
/// pre-warped at the cut-off.
pub fn butterworth_lowpass(w_bw_rad_s: f64, ts_s: f64) -> Result<SosCoeffs<f64>, Error> {
    let w = positive("w_bw_rad_s", w_bw_rad_s)?;
    sos_from_continuous(
        [0.0, 0.0, 1.0],
        [1.0 / (w * w), core::f64::consts::SQRT_2 / w, 1.0],
        ts_s,
        Prewarp::At(w),
    )
}

/// The velocity filter (6.1) `G_R(s) = s / (T_R s + 1)` (a differentiator
/// with a first-order low-pass), pre-warped at its corner `1/T_R`.
pub fn velocity_filter(t_r_s: f64, ts_s: f64) -> Result<FirstOrderCoeffs<f64>, Error> {
    let t = positive("t_r_s", t_r_s)?;
    let ts = positive("ts_s", ts_s)?;
    // Plain Tustin: pre-warping would scale the low-frequency gain by
    // K T_s / 2 != 1, and a velocity estimate must be exact for a ramp.
    first_order_from_continuous([1.0, 0.0], [t, 1.0], ts, Prewarp::None)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::filter::{FreqPoint, Sos};

    const TS: f64 = 1e-4;

    /// Continuous `(n2 s^2 + n1 s + n0)/(d2 s^2 + d1 s + d0)` at `s = j w`.
    fn cont2(num: [f64; 3], den: [f64; 3], w: f64) -> FreqPoint {
        let (nr, ni) = (num[2] - num[0] * w * w, num[1] * w);
        let (dr, di) = (den[2] - den[0] * w * w, den[1] * w);
        let d = dr * dr + di * di;
        FreqPoint {
            re: (nr * dr + ni * di) / d,
            im: (ni * dr - nr * di) / d,
        }
    }

    fn db(x: f64) -> f64 {
        20.0 * libm::log10(x)
    }

    /// Tustin's frequency warping limits the dB agreement on a roll-off: the
    /// discrete response at `w` is the continuous one at `K tan(w T_s/2)`, which
    /// for a 40 dB/decade slope is 0.1 dB off at fs/24 and 0.58 dB off at fs/10.
    /// We therefore check (a) the exact warping relation up to 0.9 Nyquist and
    /// (b) 0.1 dB agreement up to `F_MAX_01DB`.
    const F_MAX_01DB: f64 = 400.0;

    /// Largest dB deviation of the discrete section from the continuous design
    /// on a log grid from 1 Hz to `F_MAX_01DB`.
    fn max_db_error(c: &SosCoeffs<f64>, num: [f64; 3], den: [f64; 3]) -> f64 {
        let mut worst: f64 = 0.0;
        let n = 400;
        for i in 0..=n {
            let f = libm::pow(10.0, (i as f64 / n as f64) * libm::log10(F_MAX_01DB));
            let w = 2.0 * core::f64::consts::PI * f;
            let e = db(c.freq_response(w, TS).magnitude()) - db(cont2(num, den, w).magnitude());
            worst = worst.max(e.abs());
        }
        worst
    }

    /// Largest relative deviation between the discrete response at `w` and the
    /// continuous response at the warped frequency `K tan(w T_s / 2)`.
    fn max_warp_error(c: &SosCoeffs<f64>, num: [f64; 3], den: [f64; 3], w_p: f64) -> f64 {
        let k = w_p / libm::tan(0.5 * w_p * TS);
        let mut worst: f64 = 0.0;
        for i in 1..1000 {
            let w = 0.9 * core::f64::consts::PI / TS * i as f64 / 1000.0;
            let hd = c.freq_response(w, TS);
            let hc = cont2(num, den, k * libm::tan(0.5 * w * TS));
            let e = libm::hypot(hd.re - hc.re, hd.im - hc.im) / hc.magnitude().max(1e-12);
            worst = worst.max(e);
        }
        worst
    }

    /// Thesis-sized notch: resonance of Table A.4 (107.1 Hz), d_n = 4.60 (Table A.6).
    #[test]
    fn notch_matches_continuous_below_tenth_of_fs_and_exactly_at_centre() {
        let w = 2.0 * core::f64::consts::PI * 107.1;
        let d = 4.60;
        let c = notch(w, d, TS).unwrap();
        let num = [1.0, 2.0 * w / d, w * w];
        let den = [1.0, 2.0 * d * w, w * w];
        assert!(max_db_error(&c, num, den) < 0.1);
        assert!(max_warp_error(&c, num, den, w) < 1e-8);
        // exact at the pre-warped frequency: notch depth 1/d_n^2
        let at = c.freq_response(w, TS).magnitude();
        assert!((at - 1.0 / (d * d)).abs() < 1e-9, "{at}");
        assert!(c.is_stable());
    }

    #[test]
    fn butterworth_is_minus_3db_at_cutoff_and_matches_continuous() {
        let w = 123.24;
        let c = butterworth_lowpass(w, TS).unwrap();
        let num = [0.0, 0.0, 1.0];
        let den = [1.0 / (w * w), core::f64::consts::SQRT_2 / w, 1.0];
        assert!(max_db_error(&c, num, den) < 0.1);
        assert!(max_warp_error(&c, num, den, w) < 1e-8);
        let at = c.freq_response(w, TS).magnitude();
        assert!((at - core::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
        assert!((c.dc_gain() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn velocity_filter_differentiates_a_ramp() {
        // T_R = 2 ms (Table A.4). A ramp of slope 3 rad/s must give 3 rad/s after the transient.
        let c = velocity_filter(2e-3, TS).unwrap();
        let mut f = crate::filter::FirstOrder::new(c);
        let mut y = 0.0;
        for k in 0..2000 {
            y = f.step(3.0 * k as f64 * TS);
        }
        assert!((y - 3.0).abs() < 1e-9, "{y}");
        // continuous response s/(T_R s + 1) at the corner: |.| = (1/T_R)/sqrt(2);
        // plain Tustin warps the corner by (w T_s)^2/12 = 2e-4 relative.
        let w = 1.0 / 2e-3;
        let m = c.freq_response(w, TS).magnitude();
        assert!((m - w / core::f64::consts::SQRT_2).abs() / m < 1e-3);
    }

    #[test]
    fn step_response_settles_to_dc_gain_and_reset_to_has_no_transient() {
        let c = butterworth_lowpass(500.0, TS).unwrap();
        let mut s = Sos::new(c);
        let mut y = 0.0;
        for _ in 0..20000 {
            y = s.step(2.5);
        }
        assert!((y - 2.5).abs() < 1e-9);
        let mut s2 = Sos::new(c);
        s2.reset_to(1.5);
        for _ in 0..10 {
            assert!((s2.step(1.5) - 1.5).abs() < 1e-12);
        }
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(notch(-1.0, 1.0, TS).is_err());
        assert!(notch(100.0, f64::NAN, TS).is_err());
        assert!(butterworth_lowpass(1e6, TS).is_err()); // above Nyquist
        assert!(velocity_filter(0.0, TS).is_err());
        assert!(sos_from_continuous([1.0, 0.0, 0.0], [0.0, 0.0, 0.0], TS, Prewarp::None).is_err());
    }

    #[test]
    fn f32_section_tracks_f64() {
        let c = notch(673.0, 4.6, TS).unwrap();
        let mut a = Sos::<f64>::new(c);
        let mut b = Sos::<f32>::new(c.cast());
        for k in 0..5000 {
            let x = libm::sin(k as f64 * 0.07);
            let ya = a.step(x);
            let yb = b.step(x as f32);
            assert!((ya - yb as f64).abs() < 1e-4);
        }
    }
}
