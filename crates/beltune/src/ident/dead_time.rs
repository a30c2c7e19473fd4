//! Dead time of the closed current loop (3.25)-(3.30): `G_cc,cl ~ z^-n_T`
//! (3.25)-(3.26), found from the phase difference between the FRF with the
//! desired torque `tau_i` as input and the FRF with the actual torque
//! `tau_m` as input, `G_{tau_i,phi} = G_cc,cl G_{tau_m,phi}` (3.28), by
//! minimizing (3.27) over the integer `n_T` with `arg G_dt = -w n_T T_s` (3.29).

use super::etfe::Frf;
use crate::{Error, Result};
use std::f64::consts::PI;

/// The estimated dead time.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DeadTime {
    /// `n_T`, samples.
    pub samples: usize,
    /// `t_T = n_T T_s` (3.30), s.
    pub seconds: f64,
    /// RMS of the wrapped phase residual of (3.27) at the optimum, rad.
    pub rms_phase_error_rad: f64,
    /// Number of frequency lines used.
    pub n_lines: usize,
}

/// Minimize (3.27) over `n_T = 0 ..= max_samples` on the lines usable in both
/// FRFs with `0 < f <= max_freq_hz` (the thesis uses `0 <= w <= w_r`).
///
/// Errors: the FRFs are not on the same grid, or share no usable line in the band.
pub fn estimate_dead_time(
    desired: &Frf,
    actual: &Frf,
    max_freq_hz: f64,
    max_samples: usize,
) -> Result<DeadTime> {
    crate::error::require_positive("max_freq_hz", max_freq_hz)?;
    if desired.freq_hz.len() != actual.freq_hz.len()
        || (desired.ts_s - actual.ts_s).abs() > 1e-12 * desired.ts_s
    {
        return Err(Error::LengthMismatch {
            what:
                "dead time: the desired- and actual-torque FRFs are not on the same frequency grid"
                    .into(),
        });
    }
    let lines: Vec<usize> = (1..desired.freq_hz.len())
        .filter(|&i| {
            desired.is_usable(i) && actual.is_usable(i) && desired.freq_hz[i] <= max_freq_hz
        })
        .collect();
    if lines.is_empty() {
        return Err(Error::NoExcitation {
            what: format!("dead time: no line usable in both FRFs below {max_freq_hz} Hz"),
        });
    }
    let ts = desired.ts_s;
    // arg(G_i) - arg(G_m) = arg(G_i / G_m)
    let dphi: Vec<(f64, f64)> = lines
        .iter()
        .map(|&i| {
            (
                desired.omega_rad_s(i),
                (desired.response[i] / actual.response[i]).arg(),
            )
        })
        .collect();
    let cost = |n: usize| -> f64 {
        dphi.iter()
            .map(|&(w, d)| wrap(d + w * n as f64 * ts).powi(2))
            .sum()
    };
    let (samples, j) = (0..=max_samples)
        .map(|n| (n, cost(n)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("non-empty range");
    Ok(DeadTime {
        samples,
        seconds: samples as f64 * ts,
        rms_phase_error_rad: (j / lines.len() as f64).sqrt(),
        n_lines: lines.len(),
    })
}

/// Wrap an angle to `(-pi, pi]`.
fn wrap(x: f64) -> f64 {
    let y = (x + PI).rem_euclid(2.0 * PI) - PI;
    if y == -PI {
        PI
    } else {
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ident::etfe::{etfe, EtfeConfig};
    use crate::ident::testutil::{delay, prbs, simulate_two_mass};
    use crate::model::TwoMassParams;

    /// A pure delay of 10 samples between desired and actual torque (1 ms at
    /// 100 us, the thesis' (3.30)) is found exactly.
    #[test]
    fn finds_a_known_delay() {
        let p = TwoMassParams::thesis_table_a4();
        let ts = 100e-6;
        let desired = prbs(10, 4, 0.3, 4);
        let actual = delay(&desired, 10);
        let (phi, _) = simulate_two_mass(&p, &actual, ts);
        let cfg = EtfeConfig {
            ts_s: ts,
            period_samples: 1023 * 4,
            skip_periods: 1,
            ..Default::default()
        };
        let g_i = etfe(&desired, &phi, &cfg).unwrap();
        let g_m = etfe(&actual, &phi, &cfg).unwrap();
        let dt = estimate_dead_time(&g_i, &g_m, p.f_r_hz(), 40).unwrap();
        assert_eq!(dt.samples, 10);
        assert!((dt.seconds - 1e-3).abs() < 1e-12);
        assert!(dt.rms_phase_error_rad < 1e-6, "{dt:?}");
        // without delay: zero
        let dt0 = estimate_dead_time(&g_m, &g_m, p.f_r_hz(), 40).unwrap();
        assert_eq!(dt0.samples, 0);
    }

    #[test]
    fn wrap_is_in_range() {
        for k in -20..20 {
            let x = k as f64 * 0.7;
            let y = wrap(x);
            assert!(y > -PI && y <= PI);
            assert!(
                ((x - y) / (2.0 * PI)).fract().abs() < 1e-9
                    || ((x - y) / (2.0 * PI)).fract().abs() > 1.0 - 1e-9
            );
        }
    }
}
