//! The shapers against published values: Singer and Seering's ZV, the
//! closed forms of MZV, EI, 2- and 3-hump EI at zero damping (Klipper's
//! shaper_defs.py of 2021, d5a7a7f, which wrote them out; Singhose, Seering
//! and Singer 1994), Klipper's table of durations and bands
//! (docs/Resonance_Compensation.md at 84104bb), and the residual vibration
//! against a simulated oscillator (a second method).

use super::klipper::{self, KlipperOptions, Spectrum};
use super::shaper::*;

const V: f64 = EI_VIBRATION_TOLERANCE;

fn close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b} (tol {tol})");
}

/// ZV (Singer and Seering 1990): `A = [1, K] / (1 + K)`,
/// `K = exp(-zeta pi / sqrt(1 - zeta^2))`, the second impulse half a damped
/// period later. Exact formulas: tolerance 1e-12.
#[test]
fn zv_is_singer_and_seering() {
    for zeta in [0.0_f64, 0.05, 0.1, 0.3] {
        let f = 40.0;
        let s = ShaperKind::Zv.design(f, zeta).unwrap();
        let df = (1.0 - zeta * zeta).sqrt();
        let k = (-zeta * std::f64::consts::PI / df).exp();
        close(s.amplitudes[0], 1.0 / (1.0 + k), 1e-12, "A1");
        close(s.amplitudes[1], k / (1.0 + k), 1e-12, "A2");
        close(s.times_s[1], 0.5 / (f * df), 1e-12, "T2");
        // zero vibration at the design frequency and damping
        assert!(s.residual_vibration(f, zeta) < 1e-12);
    }
}

/// ZVD and MZV: zero vibration at the design frequency and damping; MZV
/// at 3 impulses over 0.75 periods equals the closed form Klipper wrote out
/// before its general zero placement (d5a7a7f, 2021): `a1 = 1 - 1/sqrt 2`,
/// `a2 = (sqrt 2 - 1) K`, `a3 = a1 K^2`, `K = exp(-0.75 zeta pi / df)`,
/// times 0, 0.375, 0.75 damped periods. The pseudo-inverse solves an exactly
/// consistent system: tolerance 1e-9.
#[test]
fn mzv_and_zvd_match_the_closed_forms() {
    for zeta in [0.0_f64, 0.1, 0.2] {
        let f = 30.0;
        let df = (1.0 - zeta * zeta).sqrt();
        let t_d = 1.0 / (f * df);
        let k = (-0.75 * zeta * std::f64::consts::PI / df).exp();
        let a1 = 1.0 - 1.0 / 2f64.sqrt();
        let raw = [a1, (2f64.sqrt() - 1.0) * k, a1 * k * k];
        let sum: f64 = raw.iter().sum();
        let s = ShaperKind::Mzv.design(f, zeta).unwrap();
        for (a, r) in s.amplitudes.iter().zip(raw) {
            close(*a, r / sum, 1e-9, "MZV amplitude");
        }
        close(s.times_s[1], 0.375 * t_d, 1e-12, "MZV T2");
        close(s.times_s[2], 0.75 * t_d, 1e-12, "MZV T3");
        assert!(s.residual_vibration(f, zeta) < 1e-9);
        let zvd = ShaperKind::Zvd.design(f, zeta).unwrap();
        assert!(zvd.residual_vibration(f, zeta) < 1e-12);
        close(zvd.duration_s(), t_d, 1e-12, "ZVD duration");
    }
}

/// EI, 2-hump and 3-hump EI at zero damping against their closed forms
/// (Singhose, Seering and Singer 1994, as Klipper wrote them in 2021):
/// EI `[(1+V)/4, (1-V)/2, (1+V)/4]` at 0, T/2, T; 2-hump
/// `a1 = (3X^2 + 2X + 3V^2) / (16X)`, `X = (V^2 (sqrt(1-V^2) + 1))^(1/3)`,
/// `a2 = 1/2 - a1`, symmetric, at 0, T/2, T, 3T/2; 3-hump
/// `a1 = (1 + 3V + 2 sqrt(2V(V+1))) / 16`, `a2 = (1-V)/4`, `a3 = 1 - 2(a1+a2)`,
/// symmetric, at 0 .. 2T. Klipper's current shapers are fits in the damping
/// ratio whose constant terms differ from these by up to 1.1e-3 in amplitude
/// (0.33911 vs 0.34020) and 2.5e-3 periods in time (0.99748 vs 1):
/// tolerance 1.5e-3 in amplitude and 3e-3 periods.
#[test]
fn the_ei_family_matches_the_closed_forms_at_zero_damping() {
    let f = 50.0;
    let period = 1.0 / f;
    let check = |kind: ShaperKind, a: &[f64], t: &[f64]| {
        let s = kind.design(f, 0.0).unwrap();
        assert_eq!(s.amplitudes.len(), a.len(), "{}", kind.name());
        for i in 0..a.len() {
            close(s.amplitudes[i], a[i], 1.5e-3, kind.name());
            close(s.times_s[i] / period, t[i], 3e-3, kind.name());
        }
    };
    check(
        ShaperKind::Ei,
        &[(1.0 + V) / 4.0, (1.0 - V) / 2.0, (1.0 + V) / 4.0],
        &[0.0, 0.5, 1.0],
    );
    let v2 = V * V;
    let x = (v2 * ((1.0 - v2).sqrt() + 1.0)).cbrt();
    let a1 = (3.0 * x * x + 2.0 * x + 3.0 * v2) / (16.0 * x);
    check(
        ShaperKind::TwoHumpEi,
        &[a1, 0.5 - a1, 0.5 - a1, a1],
        &[0.0, 0.5, 1.0, 1.5],
    );
    let a1 = (1.0 + 3.0 * V + 2.0 * (2.0 * V * (V + 1.0)).sqrt()) / 16.0;
    let a2 = (1.0 - V) / 4.0;
    check(
        ShaperKind::ThreeHumpEi,
        &[a1, a2, 1.0 - 2.0 * (a1 + a2), a2, a1],
        &[0.0, 0.5, 1.0, 1.5, 2.0],
    );
    // EI's defining property: the vibration at the design frequency is the
    // tolerance V (5 %); Klipper's fit gives 5.06 % at damping 0.1:
    // tolerance 0.2 percentage points.
    for zeta in [0.0, 0.1] {
        let s = ShaperKind::Ei.design(f, zeta).unwrap();
        close(
            s.residual_vibration(f, zeta),
            V,
            2e-3,
            "EI at the design frequency",
        );
    }
}

/// Klipper's table (docs/Resonance_Compensation.md): durations 0.5, 0.75,
/// 1, 1, 1.5, 2 periods, and the bands reduced to 5 % and 10 % over damping
/// ratios 0.075-0.15 for a shaper designed at 0.1: ZV N/A and +-5 %, MZV +-4 %
/// and -10..+15 %, ZVD +-15 % and +-22 %, EI +-20 % and +-25 %, 2-hump EI
/// -40..+45 % and -45..+50 %, 3-hump EI -50..+60 % and -55..+65 %. The table
/// calls its values approximate, rounds the wide ones to 5 points (2.5) and
/// takes the damping range as "approx. from 0.075 to 0.15": tolerance 3
/// percentage points on each edge (the largest difference found: EI's upper
/// 5 % edge, +22.8 %). The 10 % column is checked for ZV, MZV and ZVD; for the
/// EI family, which is "tuned to reduce vibrations to 5 %", Klipper gives it
/// "only for the reference" (EI's upper edge is +28.8 % here); durations at zero damping
/// to 2e-3 periods (the fits' constant terms).
#[test]
fn durations_and_bands_match_klippers_table() {
    let f = 50.0;
    let drs = [0.075, 0.1, 0.15];
    #[allow(clippy::type_complexity)]
    let table: [(ShaperKind, f64, Option<(f64, f64)>, (f64, f64)); 6] = [
        (ShaperKind::Zv, 0.5, None, (-5.0, 5.0)),
        (ShaperKind::Mzv, 0.75, Some((-4.0, 4.0)), (-10.0, 15.0)),
        (ShaperKind::Zvd, 1.0, Some((-15.0, 15.0)), (-22.0, 22.0)),
        (ShaperKind::Ei, 1.0, Some((-20.0, 20.0)), (-25.0, 25.0)),
        (
            ShaperKind::TwoHumpEi,
            1.5,
            Some((-40.0, 45.0)),
            (-45.0, 50.0),
        ),
        (
            ShaperKind::ThreeHumpEi,
            2.0,
            Some((-50.0, 60.0)),
            (-55.0, 65.0),
        ),
    ];
    for (kind, periods, band5, band10) in table {
        let s0 = kind.design(f, 0.0).unwrap();
        close(s0.duration_s() * f, periods, 2e-3, kind.name());
        let s = kind.design(f, DEFAULT_DAMPING_RATIO).unwrap();
        let pct =
            |b: Option<(f64, f64)>| b.map(|(l, h)| (100.0 * (l / f - 1.0), 100.0 * (h / f - 1.0)));
        let got5 = pct(s.band_hz(f, &drs, 0.05));
        match (band5, got5) {
            (None, None) => {}
            (Some(w), Some(g)) => {
                close(g.0, w.0, 3.0, &format!("{} 5 % low", kind.name()));
                close(g.1, w.1, 3.0, &format!("{} 5 % high", kind.name()));
            }
            (w, g) => panic!("{}: 5 % band {w:?} vs {g:?}", kind.name()),
        }
        if matches!(
            kind,
            ShaperKind::Ei | ShaperKind::TwoHumpEi | ShaperKind::ThreeHumpEi
        ) {
            continue;
        }
        let g = pct(s.band_hz(f, &drs, 0.10)).unwrap();
        close(g.0, band10.0, 3.0, &format!("{} 10 % low", kind.name()));
        close(g.1, band10.1, 3.0, &format!("{} 10 % high", kind.name()));
    }
    // The table's note on smoothing: ZV < MZV < ZVD ~ EI < 2-hump < 3-hump.
    let sm = |k: ShaperKind| k.design(f, 0.1).unwrap().smoothing_m(5.0, 5e-3);
    assert!(sm(ShaperKind::Zv) < sm(ShaperKind::Mzv));
    assert!(sm(ShaperKind::Mzv) < sm(ShaperKind::Zvd));
    assert!((sm(ShaperKind::Zvd) / sm(ShaperKind::Ei) - 1.0).abs() < 0.1);
    assert!(sm(ShaperKind::Ei) < sm(ShaperKind::TwoHumpEi));
    assert!(sm(ShaperKind::TwoHumpEi) < sm(ShaperKind::ThreeHumpEi));
}

/// Response of `y'' + 2 zeta w y' + w^2 y = w^2 u` to the command `u` (a
/// unit step shaped by `s`), integrated with RK4 at `h`; the peak-to-peak of
/// `y - 1` over two periods after the last impulse.
fn simulated_residual_pp(s: &Shaper, f: f64, zeta: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f;
    let h = 1e-3 / f;
    let u = |t: f64| -> f64 {
        s.amplitudes
            .iter()
            .zip(&s.times_s)
            .filter(|(_, ti)| t >= **ti - 1e-15)
            .map(|(a, _)| a)
            .sum()
    };
    let (mut y, mut v) = (0.0_f64, 0.0_f64);
    let acc = |y: f64, v: f64, u: f64| w * w * (u - y) - 2.0 * zeta * w * v;
    let t_end = s.duration_s();
    let mut t = 0.0;
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    while t < t_end + 2.0 / f {
        // the command is constant within a step (impulse times are
        // multiples of h to within rounding at this step)
        let uk = u(t + 0.5 * h);
        let (k1y, k1v) = (v, acc(y, v, uk));
        let (k2y, k2v) = (
            v + 0.5 * h * k1v,
            acc(y + 0.5 * h * k1y, v + 0.5 * h * k1v, uk),
        );
        let (k3y, k3v) = (
            v + 0.5 * h * k2v,
            acc(y + 0.5 * h * k2y, v + 0.5 * h * k2v, uk),
        );
        let (k4y, k4v) = (v + h * k3v, acc(y + h * k3y, v + h * k3v, uk));
        y += h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t += h;
        if t >= t_end {
            lo = lo.min(y - 1.0);
            hi = hi.max(y - 1.0);
        }
    }
    hi - lo
}

/// The residual vibration formula against a second method: an oscillator
/// integrated in time, the shaped step over two periods after its last
/// impulse against the unshaped step over two periods after its one
/// impulse (the formula's normalization: the vibration a single impulse
/// leaves where it is given). Impulses fall between integration steps by up
/// to h = 1e-3 periods, and peak-to-peak over two damped periods measures a
/// decaying sinusoid's amplitude to a few per cent: tolerance 3 % of the
/// unshaped vibration plus 5 % relative.
#[test]
fn residual_vibration_matches_a_simulated_oscillator() {
    let unshaped = Shaper::none();
    for (kind, design_f, f, zeta) in [
        (ShaperKind::Zv, 20.0, 23.0, 0.05),
        (ShaperKind::Mzv, 20.0, 18.0, 0.1),
        (ShaperKind::Ei, 20.0, 25.0, 0.02),
        (ShaperKind::TwoHumpEi, 20.0, 14.0, 0.1),
        (ShaperKind::ThreeHumpEi, 20.0, 30.0, 0.15),
    ] {
        let s = kind.design(design_f, 0.1).unwrap();
        // the unshaped step over the same window [t_end, t_end + 2/f]
        let base = simulated_residual_pp(&unshaped, f, zeta);
        let shaped = simulated_residual_pp(&s, f, zeta);
        let expected = s.residual_vibration(f, zeta);
        let got = shaped / base;
        assert!(
            (got - expected).abs() <= 0.03 + 0.05 * expected,
            "{} at {f} Hz, zeta {zeta}: simulated {got}, formula {expected}",
            kind.name()
        );
    }
}

/// Bad input gives a typed error, not NaN.
#[test]
fn bad_shaper_input_is_an_error() {
    assert!(ShaperKind::Zv.design(0.0, 0.1).is_err());
    assert!(ShaperKind::Ei.design(f64::NAN, 0.1).is_err());
    assert!(ShaperKind::ThreeHumpEi.design(30.0, 0.25).is_err());
    assert!(Shaper::new(vec![1.0, -0.5], vec![0.0, 0.01]).is_err());
    assert!(Shaper::new(vec![1.0], vec![0.1]).is_err());
    let empty = Spectrum {
        freq_hz: vec![1.0, 2.0],
        psd: vec![0.0, 0.0],
    };
    assert!(klipper::find_best_shaper(&[empty], &KlipperOptions::default()).is_err());
}

/// A spectrum of one lightly damped resonance at `f0` (|H|^2 of a
/// second-order mode of damping `zeta`) on Klipper's bins.
fn resonance(f0: f64, zeta: f64) -> Spectrum {
    let freq_hz: Vec<f64> = (0..=400).map(|i| i as f64 * 0.5).collect();
    let psd = freq_hz
        .iter()
        .map(|&f| {
            let r = f / f0;
            1.0 / ((1.0 - r * r).powi(2) + (2.0 * zeta * r).powi(2))
        })
        .collect();
    Spectrum { freq_hz, psd }
}

/// Klipper's rules on one resonance: no shaping leaves all the vibration
/// (the definition: 1); the chosen shaper's vibration is its remaining
/// vibration recomputed, worst over the test damping ratios; the chosen
/// shaper reduces a clean 60 Hz resonance below 5 % (Klipper's goal,
/// SHAPER_VIBRATION_REDUCTION); and it is not worse than 1.1 x the least
/// vibration its kind reached (+0.05 points).
#[test]
fn klipper_choice_on_one_resonance() {
    let spec = resonance(60.0, 0.1);
    let none = klipper::remaining_vibration(&Shaper::none(), 0.1, &spec, 200.0);
    close(none, 1.0, 1e-12, "no shaping");
    let opts = KlipperOptions::default();
    let (best, all) = klipper::find_best_shaper(std::slice::from_ref(&spec), &opts).unwrap();
    assert_eq!(all.len(), 5);
    let recomputed = klipper::TEST_DAMPING_RATIOS
        .iter()
        .map(|&z| klipper::remaining_vibration(&best.shaper, z, &spec, 200.0))
        .fold(0.0, f64::max);
    close(best.vibration, recomputed, 1e-12, "remaining vibration");
    assert!(best.vibration < 0.05, "{best:?}");
    let (_, points) = klipper::fit_shaper(best.kind, std::slice::from_ref(&spec), &opts).unwrap();
    let least = points.iter().map(|p| p.vibration).fold(f64::MAX, f64::min);
    assert!(best.vibration <= least * 1.1 + 0.0005 + 1e-12);
    // two resonances far apart (35 and 60 Hz, the docs' example): the
    // choice still reduces both below 5 %
    let two = Spectrum {
        freq_hz: spec.freq_hz.clone(),
        psd: resonance(35.0, 0.1)
            .psd
            .iter()
            .zip(&spec.psd)
            .map(|(a, b)| a + b)
            .collect(),
    };
    let (best2, _) = klipper::find_best_shaper(&[two], &opts).unwrap();
    assert!(
        best2.vibration < 0.05,
        "{:?} at {} Hz, v {}",
        best2.kind,
        best2.freq_hz,
        best2.vibration
    );
}

/// Residual of the oscillator `y'' = w^2 (x_d - y) - 2 zeta w y'` driven by
/// the desired position `x_d` of `path` (RK4 at 10 us, the path sampled at
/// each stage): the largest `|y - target|` over two periods after the path
/// ends.
fn oscillator_residual_m(
    path: &super::shaping::ShapedTrajectory,
    mode: &super::shaping::Mode,
) -> f64 {
    let w = 2.0 * std::f64::consts::PI * mode.freq_hz;
    let z = mode.damping_ratio;
    let h = 1e-5;
    let start = path.sample(0.0).position;
    let target = path.sample(path.duration_s() + 10.0).position;
    let (mut y, mut v) = (start, 0.0_f64);
    let acc = |t: f64, y: f64, v: f64| w * w * (path.sample(t).position - y) - 2.0 * z * w * v;
    let t_end = path.duration_s();
    let mut t = 0.0;
    let mut worst: f64 = 0.0;
    while t < t_end + 2.0 / mode.freq_hz {
        let (k1y, k1v) = (v, acc(t, y, v));
        let (k2y, k2v) = (
            v + 0.5 * h * k1v,
            acc(t + 0.5 * h, y + 0.5 * h * k1y, v + 0.5 * h * k1v),
        );
        let (k3y, k3v) = (
            v + 0.5 * h * k2v,
            acc(t + 0.5 * h, y + 0.5 * h * k2y, v + 0.5 * h * k2v),
        );
        let (k4y, k4v) = (v + h * k3v, acc(t + h, y + h * k3y, v + h * k3v));
        y += h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t += h;
        if t >= t_end {
            worst = worst.max((y - target).abs());
        }
    }
    worst
}

/// Model-based shaping (issue 32 item 3): the shaped move takes exactly the
/// duration asked, stays within the velocity, acceleration and jerk limits
/// (sampled every 0.1 ms), and on a second method, an oscillator integrated
/// in time, leaves at most its prediction (the predicted worst over the
/// band, +10 % and 0.1 um for the integration) at the band's ends and
/// middle and at most a fifth of the unshaped move of the same duration
/// (90 ms of shaping over a 1:1.33 band: a ZVD, whose 5 % band is +-15 %).
#[test]
fn model_based_shaping_within_limits_and_against_an_oscillator() {
    use super::shaping::{choose_shaper, scaled_trajectory, Mode, ShapedTrajectory};
    use beltune_rt::trajectory::Limits;
    let limits = Limits {
        v_max: 1.0,
        v_min: -1.0,
        a_max: 20.0,
        a_min: -20.0,
        j_max: 2000.0,
        j_min: -2000.0,
        position_min: -0.01,
        position_max: 0.11,
    };
    let (start, target) = (0.0, 0.1);
    let modes = [
        Mode {
            freq_hz: 18.0,
            damping_ratio: 0.03,
        },
        Mode {
            freq_hz: 24.0,
            damping_ratio: 0.03,
        },
    ];
    let fastest = scaled_trajectory(start, target, &limits, 0.0).err();
    assert!(fastest.is_some(), "a zero duration is refused");
    let d_min = beltune_rt::trajectory::Trajectory::plan(
        &beltune_rt::trajectory::State::at_rest(start),
        &beltune_rt::trajectory::State::at_rest(target),
        &limits,
    )
    .unwrap()
    .duration_s();
    let duration = d_min + 0.09;
    let choice = choose_shaper(start, target, &limits, duration, &modes, 0.0).unwrap();
    let shaped = ShapedTrajectory {
        base: scaled_trajectory(
            start,
            target,
            &limits,
            duration - choice.shaper.duration_s(),
        )
        .unwrap(),
        shaper: choice.shaper.clone(),
    };
    let plain = ShapedTrajectory {
        base: scaled_trajectory(start, target, &limits, duration).unwrap(),
        shaper: Shaper::none(),
    };
    close(shaped.duration_s(), duration, 1e-9, "shaped duration");
    close(plain.duration_s(), duration, 1e-9, "plain duration");
    let mut t = 0.0;
    while t <= duration + 0.01 {
        let s = shaped.sample(t);
        assert!(s.velocity.abs() <= limits.v_max * (1.0 + 1e-9), "v {t}");
        assert!(s.acceleration.abs() <= limits.a_max * (1.0 + 1e-9), "a {t}");
        assert!(s.jerk.abs() <= limits.j_max * (1.0 + 1e-9), "j {t}");
        t += 1e-4;
    }
    close(
        shaped.sample(duration).position,
        target,
        1e-12,
        "shaped end",
    );
    for f in [18.0, 21.0, 24.0] {
        let m = Mode {
            freq_hz: f,
            damping_ratio: 0.03,
        };
        let s = oscillator_residual_m(&shaped, &m);
        let p = oscillator_residual_m(&plain, &m);
        assert!(
            s <= choice.predicted_residual_m * 1.1 + 1e-7,
            "{f} Hz: simulated {s}, predicted {}",
            choice.predicted_residual_m
        );
        assert!(
            s <= 0.2 * p,
            "{f} Hz: shaped {s} vs plain {p} ({:?} at {})",
            choice.kind,
            choice.freq_hz
        );
    }
}
