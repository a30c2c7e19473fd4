//! The drift of an open-loop excitation (stage 5): where an attempt that
//! ended at the edge guard ([`super::identification::EXCITATION_GUARD_M`])
//! starts again, and the words that say why, which stay meaningful when an
//! attempt ended before its drift could be measured.
//!
//! An attempt that ran a fraction `done / n` of its samples and moved the
//! axis by `moved` extrapolates (linear in time) to a drift of
//! `moved n / done` over the whole excitation. An attempt that ended within
//! [`DRIFT_MEASURED_FRACTION`] of the record having moved less than the
//! guard says nothing about the drift (1.1 mm in the first sample once read
//! "extrapolated to 3495 mm"): it ended because it started too close to the
//! edge, and the drift measured by an earlier attempt, if any, stays the
//! estimate.

/// Shortest fraction of an excitation whose drift is extrapolated to the
/// whole record.
pub const DRIFT_MEASURED_FRACTION: f64 = 0.05;

/// An open-loop attempt that ended early at the edge guard.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndedAttempt {
    /// Attempt number, from 1.
    pub attempt: usize,
    /// Where the attempt started, m.
    pub center_m: f64,
    /// Where it ended, m.
    pub ended_m: f64,
    /// Samples it ran.
    pub done: usize,
    /// Samples of the whole excitation.
    pub n: usize,
    /// Sampling time, s.
    pub ts_s: f64,
}

/// The drift an attempt measured, or why it measured none.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftReading {
    /// The drift over the whole excitation, m (signed), where measured.
    pub drift_m: Option<f64>,
    /// What happened, in words (mm and s).
    pub why: String,
}

impl EndedAttempt {
    /// What this attempt says about the drift (module docs).
    pub fn reading(&self, guard_m: f64) -> DriftReading {
        let moved = self.ended_m - self.center_m;
        let ran_s = self.done as f64 * self.ts_s;
        let total_s = self.n as f64 * self.ts_s;
        if (self.done as f64) < DRIFT_MEASURED_FRACTION * self.n as f64 && moved.abs() < guard_m {
            return DriftReading {
                drift_m: None,
                why: format!(
                    "attempt {} from {:.1} mm ended after {:.3} of {:.2} s at {:.1} mm, within {:.0} mm of the travel window's edge, before its drift could be measured",
                    self.attempt,
                    self.center_m * 1e3,
                    ran_s,
                    total_s,
                    self.ended_m * 1e3,
                    guard_m * 1e3
                ),
            };
        }
        DriftReading {
            drift_m: Some(moved * self.n as f64 / self.done as f64),
            why: format!(
                "the open-loop excitation drifted {:.1} mm in {:.2} of {:.2} s (attempt {} from {:.1} mm)",
                moved * 1e3,
                ran_s,
                total_s,
                self.attempt,
                self.center_m * 1e3
            ),
        }
    }
}

/// Where the next attempt starts inside the travel window
/// `window_min_m ..= window_max_m` for an expected drift `drift_m` (m,
/// signed; 0 where none was measured): at `preferred_m` (as far against the
/// drift as it extrapolates to, or where the attempt began where it measured
/// none), kept two guards from either edge (one for the guard, one for the
/// positioning move's error and ringing: a start exactly at the guard
/// ended in its first sample) and the drift's length from the edge it runs
/// towards. `None` where the window cannot hold the drift.
pub fn restart_center_m(
    preferred_m: f64,
    drift_m: f64,
    window_min_m: f64,
    window_max_m: f64,
    guard_m: f64,
) -> Option<f64> {
    let lo = window_min_m + 2.0 * guard_m - drift_m.min(0.0);
    let hi = window_max_m - 2.0 * guard_m - drift_m.max(0.0);
    (lo <= hi).then(|| preferred_m.clamp(lo, hi))
}

/// The one-line reason an excitation is given up after `reading`, with the
/// drift `drift_m` measured by an earlier attempt where this one measured
/// none, and where the axis was stopped (`rest_m`).
pub fn give_up_reason(
    stage: &str,
    reading: &DriftReading,
    earlier_drift_m: Option<f64>,
    rest_m: f64,
) -> String {
    let what = match (reading.drift_m, earlier_drift_m) {
        (Some(d), _) => format!(
            "the travel window does not fit its drift, extrapolated to {:.0} mm over the whole excitation (check the holding torque, or lower the PRBS amplitude)",
            d.abs() * 1e3
        ),
        (None, Some(d)) => format!(
            "the travel window does not fit the drift of {:.0} mm an earlier attempt measured (check the holding torque, or lower the PRBS amplitude)",
            d.abs() * 1e3
        ),
        (None, None) => {
            "the excitation cannot start clear of the travel window's edges (widen the window)"
                .to_string()
        }
    };
    format!(
        "{stage}: {}; {what}; axis stopped at {:.1} mm",
        reading.why,
        rest_m * 1e3
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A restart that ended in its first sample once said "drifted 1.1 mm
    /// in 0.00 of 3.07 s ... extrapolated to 3495 mm". Such an attempt
    /// extrapolates nothing, says where it ended and why, and the reason
    /// given up names the drift an earlier attempt measured.
    #[test]
    fn an_attempt_that_ended_at_once_extrapolates_no_drift() {
        let a = EndedAttempt {
            attempt: 2,
            center_m: 0.5512,
            ended_m: 0.5523,
            done: 1,
            n: 30_700,
            ts_s: 1e-4,
        };
        let r = a.reading(0.01);
        assert_eq!(r.drift_m, None);
        assert!(
            r.why.contains("ended after 0.000 of 3.07 s at 552.3 mm"),
            "{}",
            r.why
        );
        assert!(!r.why.contains("drifted"));
        let reason = give_up_reason("identification", &r, Some(-0.062), 0.553);
        assert!(
            reason.contains("drift of 62 mm an earlier attempt measured"),
            "{reason}"
        );
        assert!(!reason.contains("3495"));
        let none = give_up_reason("identification", &r, None, 0.553);
        assert!(none.contains("cannot start clear"), "{none}");
    }

    /// A measured attempt extrapolates linearly: 10 mm in a quarter of the
    /// record is 40 mm over the whole of it; a short attempt that moved
    /// more than the guard measured its drift too.
    #[test]
    fn a_measured_attempt_extrapolates_linearly() {
        let a = EndedAttempt {
            attempt: 1,
            center_m: 0.3,
            ended_m: 0.29,
            done: 2500,
            n: 10_000,
            ts_s: 1e-4,
        };
        let r = a.reading(0.01);
        assert!((r.drift_m.unwrap() + 0.04).abs() < 1e-12);
        assert!(
            r.why.contains("drifted -10.0 mm in 0.25 of 1.00 s"),
            "{}",
            r.why
        );
    }

    /// The restart keeps two guards from either edge: the attempt it
    /// starts is clear of the guard at its first sample.
    #[test]
    fn the_restart_keeps_clear_of_the_guard() {
        // drift +40 mm from 0.05 m in [0, 0.3]: start at 0.02 m (two guards)
        let c = restart_center_m(0.05 - 0.04, 0.04, 0.0, 0.3, 0.01).unwrap();
        assert!((c - 0.02).abs() < 1e-12, "{c}");
        // drift -40 mm from 0.25 m: 0.29 m is within two guards of the edge
        let c = restart_center_m(0.25 + 0.04, -0.04, 0.0, 0.3, 0.01).unwrap();
        assert!((c - 0.28).abs() < 1e-12, "{c}");
        // a window shorter than the drift and the guards
        assert_eq!(restart_center_m(0.05, 0.1, 0.0, 0.12, 0.01), None);
    }
}
