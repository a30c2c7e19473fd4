//! Tests on the real measurement `data/twomass-bench/multisine-a.csv.gz` (see the
//! data README): 2500 Hz, 20 periods of 2500 samples, first period transient,
//! rotary two-mass bench, current units, free inertia.

use super::*;
use std::path::PathBuf;

fn data_path() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/twomass-bench/multisine-a.csv.gz");
    assert!(
        p.exists(),
        "measured data missing: {} (it ships in the repository, data/twomass-bench)",
        p.display()
    );
    p
}

fn measured_frf(input: &str, band_hz: Option<(f64, f64)>) -> Frf {
    let cols = read_csv_columns(&data_path(), &["t_s", input, "theta_motor_rad"]).unwrap();
    let s = csv_columns::check_uniform_time(&cols, "t_s", 5000, 0.01).unwrap();
    assert!((s.ts_s - 1.0 / 2500.0).abs() < 1e-9);
    let cfg = EtfeConfig {
        ts_s: s.ts_s,
        period_samples: 2500,
        skip_periods: 1,
        band_hz,
        ..Default::default()
    };
    etfe(
        cols.column(input).unwrap(),
        cols.column("theta_motor_rad").unwrap(),
        &cfg,
    )
    .unwrap()
}

fn rotary_current_fit(frf: &Frf) -> TwoMassFit {
    fit_two_mass(
        frf,
        &FitConfig {
            theta_e: None,
            free_inertia: true,
            i_t: 1.0,
            units: ModelUnits::Current,
            ..Default::default()
        },
    )
    .unwrap()
}

/// The reference input excites exactly the README's band (11-250 Hz, 1 Hz
/// lines); the FRF shows the antiresonance and resonance below 100 Hz.
#[test]
fn measured_frf_band_and_modes() {
    let frf = measured_frf("iq_ref_A", None);
    assert_eq!(frf.n_periods, 19);
    let idx = frf.usable_indices();
    assert_eq!(frf.freq_hz[idx[0]], 11.0);
    assert_eq!(frf.freq_hz[*idx.last().unwrap()], 250.0);
    assert_eq!(idx.len(), 240);
    let feat = frf_features(&frf).unwrap();
    // README: antiresonance and resonance below 100 Hz, resonance above the dip
    assert!(feat.antiresonance_hz > 20.0 && feat.antiresonance_hz < feat.resonance_hz);
    assert!(feat.resonance_hz < 100.0, "{feat:?}");
    // the peak stands well above and the dip well below the 1/w^2 line
    let backbone = 1.0 / feat.rigid_inertia;
    let w = |f: f64| 2.0 * std::f64::consts::PI * f;
    assert!(feat.resonance_magnitude * w(feat.resonance_hz).powi(2) > 10.0 * backbone);
    assert!(feat.antiresonance_magnitude * w(feat.antiresonance_hz).powi(2) < 0.3 * backbone);
}

/// Rotary, current units, free inertia: the fitted model's modes lie within
/// 3 % of the measured FRF's peak and dip, its rigid-body inertia
/// matches the low-frequency asymptote, and the two current signals agree.
#[test]
fn measured_fit_matches_peak_dip_and_asymptote() {
    /// Fitted f_r, f_z within 3 % of the measured peak and dip.
    const MODE_TOL: f64 = 0.03;
    /// The asymptote is read from lines 11-37 Hz, only 1.5-5x below the
    /// antiresonance, through an undamped shape correction: 5 %.
    const ASYMPTOTE_TOL: f64 = 0.05;
    /// A good fit of a two-mass model to a real bench: a few dB at most.
    const MAX_RMS_DB: f64 = 2.0;
    let frf = measured_frf("iq_ref_A", None);
    let fit = rotary_current_fit(&frf);
    let feat = fit.features;
    println!("{fit:#?}");
    assert!((fit.f_r_hz / feat.resonance_hz - 1.0).abs() < MODE_TOL);
    assert!((fit.f_z_hz / feat.antiresonance_hz - 1.0).abs() < MODE_TOL);
    let j = fit.params.rigid_inertia();
    assert!((j / feat.rigid_inertia - 1.0).abs() < ASYMPTOTE_TOL, "{j}");
    assert!(fit.fit_rms_db < MAX_RMS_DB, "{}", fit.fit_rms_db);
    let u = fit.uncertainty.expect("uncertainty");
    assert!(u.c > 0.0 && u.c < 0.05 * fit.params.c, "{u:?}");
    assert!(u.m_c > 0.0 && u.m_c < 0.05 * fit.params.m_c, "{u:?}");

    // the measured current, restricted to the excited band, gives the same modes
    let frf_meas = measured_frf("iq_meas_A", Some((11.0, 250.0)));
    let fit_meas = rotary_current_fit(&frf_meas);
    const INPUT_AGREEMENT: f64 = 0.01;
    assert!((fit_meas.f_r_hz / fit.f_r_hz - 1.0).abs() < INPUT_AGREEMENT);
    assert!((fit_meas.f_z_hz / fit.f_z_hz - 1.0).abs() < INPUT_AGREEMENT);
}

/// RMS of the unweighted dB residuals of `fit`'s model over `lines` of `frf`.
fn rms_db_on(frf: &Frf, fit: &TwoMassFit, lines: &[usize]) -> f64 {
    let ss: f64 = lines
        .iter()
        .map(|&i| {
            let m = fit::model_magnitude_db(&fit.params, fit.model, frf.omega_rad_s(i));
            (frf.magnitude_db(i) - m).powi(2)
        })
        .sum();
    (ss / lines.len() as f64).sqrt()
}

/// The fit reaches the best the two-mass class allows on the bench recording.
///
/// Reference (independent of beltune's code): `tools/twomass_optimum.py`, a
/// numpy/scipy script that computes the FRF from the raw columns itself
/// (Clary's method II over periods 2-20), takes the lines within 40 dB of the
/// strongest, and minimizes the unweighted squared dB residuals of (2.39)
/// (free Theta_e, i_t = 1, d = 0) by differential evolution over +-3 decades
/// of every parameter (scipy 1.17.1, seed 1; seed 7 gives the same optimum)
/// polished by trust-region least squares. Output recorded on 2026-12-03:
/// - `python3 tools/twomass_optimum.py` (the nearly log-spaced subset F_o of
///   n_o = 150 targets, Figure 3.9: 117 lines, the lines beltune fits):
///   rms 0.6757 dB, f_r 76.1899 Hz, f_z 54.0303 Hz;
/// - `python3 tools/twomass_optimum.py --all-lines` (all 240 lines 11-250 Hz):
///   rms 0.5194 dB, f_r 76.1571 Hz, f_z 54.0399 Hz.
///
/// Tolerances (issue: "within 0.05 dB rms and 0.5 % in f_r and f_z"): the
/// beltune fit weights lines by coherence (near-uniform here: every line's
/// noise is far below the model error) and runs its own FRF, so it may sit a
/// little off the unweighted optimum, by no more than these.
#[test]
fn fit_reaches_the_independent_optimum() {
    const SUBSET_RMS_DB: f64 = 0.6757;
    const SUBSET_F_R_HZ: f64 = 76.1899;
    const SUBSET_F_Z_HZ: f64 = 54.0303;
    const ALL_RMS_DB: f64 = 0.5194;
    const RMS_TOL_DB: f64 = 0.05;
    const FREQ_TOL: f64 = 0.005;
    let frf = measured_frf("iq_ref_A", None);
    let fit = rotary_current_fit(&frf);
    let subset = frf.log_spaced_subset(FitConfig::default().n_log_lines);
    assert_eq!(subset.len(), 117, "the reference's line subset");
    let rms_subset = rms_db_on(&frf, &fit, &subset);
    let rms_all = rms_db_on(&frf, &fit, &frf.usable_indices());
    println!(
        "f_r {} f_z {} rms subset {rms_subset} all {rms_all} (reported {})",
        fit.f_r_hz, fit.f_z_hz, fit.fit_rms_db
    );
    assert!((fit.fit_rms_db - rms_subset).abs() < 1e-9);
    assert!(rms_subset < SUBSET_RMS_DB + RMS_TOL_DB, "{rms_subset}");
    assert!(rms_all < ALL_RMS_DB + RMS_TOL_DB, "{rms_all}");
    assert!(
        (fit.f_r_hz / SUBSET_F_R_HZ - 1.0).abs() < FREQ_TOL,
        "{}",
        fit.f_r_hz
    );
    assert!(
        (fit.f_z_hz / SUBSET_F_Z_HZ - 1.0).abs() < FREQ_TOL,
        "{}",
        fit.f_z_hz
    );
}

/// Regression: no change may make a recording's fit worse. Every input
/// column of the bench recording, fitted as `identify` does, stays at or
/// below the rms `beltune identify` printed before the global stage and the
/// line selection landed (main 9607596: `--input iq_ref_A` 0.676 dB,
/// `--input iq_meas_A --min-freq-hz 11 --max-freq-hz 250` 0.660 dB, both
/// `--current-units --period-samples 2500`), plus 0.001 dB for the printed
/// rounding. (With them: 0.6757 and 0.6599 dB.)
#[test]
fn recorded_fits_do_not_get_worse() {
    for (input, band, max_rms_db) in [
        ("iq_ref_A", None, 0.676 + 0.001),
        ("iq_meas_A", Some((11.0, 250.0)), 0.660 + 0.001),
    ] {
        let frf = measured_frf(input, band);
        let fit = rotary_current_fit(&frf);
        println!(
            "{input}: rms {} dB, f_r {}, f_z {}",
            fit.fit_rms_db, fit.f_r_hz, fit.f_z_hz
        );
        assert!(fit.fit_rms_db <= max_rms_db, "{input}: {}", fit.fit_rms_db);
    }
}
