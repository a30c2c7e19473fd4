//! Stage 4: the PRBS amplitude, increased from a small value until the motor
//! moves in most short windows (the response clears friction and encoder
//! quantization), re-centring between bursts, times a margin (Coulomb friction
//! must be small against the excitation for the small-signal FRF to show the
//! linear model), never beyond the maximum fraction of the torque limit.

use super::super::motion::move_to;
use super::super::runner::Runner;
use super::super::ExcitationConfig;
use super::Stages;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;
use beltune_rt::prbs::Prbs;
use beltune_rt::trajectory::Limits;

/// Stage 4 (or the fixed amplitude of the configuration): `A_PRBS`, N m.
#[allow(clippy::too_many_arguments)]
pub fn amplitude_stage(
    st: &mut Stages,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    torque_max: f64,
    ex: &ExcitationConfig,
) -> Result<f64> {
    st.start("excitation amplitude", 0);
    let amplitude = match ex.fixed_amplitude_nm {
        Some(a) => crate::error::require_positive("excitation amplitude [N m]", a)?.min(torque_max),
        None => find_amplitude(
            st.runner, hold, center_m, limits, holding_nm, torque_max, ex,
        )?,
    };
    let line = format!(
        "A_PRBS = {:.3} N m (+-{:.3} N m around the holding torque)",
        amplitude,
        amplitude / 2.0
    );
    st.finish("excitation", line);
    Ok(amplitude)
}

fn find_amplitude(
    runner: &mut Runner,
    hold: &CascadeConfig<f64>,
    center_m: f64,
    limits: &Limits,
    holding_nm: f64,
    torque_max: f64,
    ex: &ExcitationConfig,
) -> Result<f64> {
    let ts = runner.info().ts_s;
    let window = ex.moving_window_samples(ts);
    let burst = ex.burst_samples(ts).max(window);
    let clock = ex.clock_samples(ts);
    let mut a = ex.amplitude_start_fraction * torque_max;
    let a_max = ex.amplitude_max_fraction * torque_max;
    loop {
        let mut prbs = Prbs::new(ex.prbs_order, clock, a)?;
        move_to(runner, hold, center_m, limits, 0.05)?;
        let mut counts = Vec::with_capacity(burst);
        for _ in 0..burst {
            runner.step(holding_nm + prbs.step(), None)?;
            counts.push(runner.last().motor_counts);
        }
        let span = ((MOVING_SPAN_S / ts).round() as usize).clamp(1, window);
        let moving_windows = moving_windows(&counts, window, span);
        let windows = moving_windows.1;
        let moving = moving_windows.0;
        let fraction = moving as f64 / windows.max(1) as f64;
        if fraction >= ex.moving_fraction {
            return Ok((a * ex.amplitude_margin).min(a_max));
        }
        if a >= a_max {
            return Err(Error::NoExcitation {
                what: format!(
                    "the axis does not move freely even at A_PRBS = {a:.3} N m ({:.0} % of {:.0} ms windows moving); check brakes and friction",
                    fraction * 100.0,
                    ex.moving_window_s * 1e3
                ),
            });
        }
        a = (a * ex.amplitude_growth).min(a_max);
    }
}

/// Time over which a movement window compares the encoder counts, s: the
/// 2 ms window at 10 kHz compared its first and last sample, 19 intervals
/// apart; at 1 kHz its two samples were one interval (1 ms) apart and a
/// 1 kHz drive needed a 1.5 times larger amplitude for the same motion.
pub const MOVING_SPAN_S: f64 = 1.9e-3;

/// Windows of `window` samples in which the encoder `counts` moved over
/// `span` samples from the window's start (at most `window`: the next
/// window's start), and the windows.
pub(crate) fn moving_windows(counts: &[i64], window: usize, span: usize) -> (usize, usize) {
    let window = window.max(1);
    let span = span.clamp(1, window);
    // the windows whose span ends inside the record (at 10 kHz with
    // `span = window - 1` exactly `len / window`, as before)
    let windows = if counts.len() > span {
        (counts.len() - span - 1) / window + 1
    } else {
        0
    };
    let moving = (0..windows)
        .filter(|w| counts[w * window] != counts[w * window + span])
        .count();
    (moving, windows)
}

#[cfg(test)]
mod tests {
    use super::{moving_windows, MOVING_SPAN_S};

    /// The same motion (one count every 1.85 ms) reads the same at 10 kHz
    /// (20-sample windows over 19 intervals, as the search always counted)
    /// and 1 kHz (2-sample windows over 2 intervals, where one interval
    /// missed it): every window sees a count change.
    #[test]
    fn the_movement_test_does_not_depend_on_the_sampling_rate() {
        let counts = |ts: f64, n: usize| -> Vec<i64> {
            (0..n)
                .map(|k| (k as f64 * ts / 1.85e-3).floor() as i64)
                .collect()
        };
        let span = |ts: f64| (MOVING_SPAN_S / ts).round() as usize;
        let fast = moving_windows(&counts(1e-4, 3000), 20, span(1e-4));
        let slow = moving_windows(&counts(1e-3, 300), 2, span(1e-3));
        assert_eq!(fast.0, fast.1, "{fast:?}");
        assert_eq!(slow.0, slow.1, "{slow:?}");
        // one interval at 1 kHz (the former test) misses some of them
        let one = moving_windows(&counts(1e-3, 300), 2, 1);
        assert!(one.0 < one.1, "{one:?}");
    }
}
