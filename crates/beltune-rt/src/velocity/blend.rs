//! Blend of gate measurement and event counter (6.19)-(6.21).

use super::{EncoderResolution, EventCounter, GateMeasurement};
use crate::encoder::EdgeWindow;
use crate::error::positive;
use crate::filter::{first_order_from_continuous, FirstOrder, Prewarp};
use crate::{Error, Real};

/// The switching function (6.20), evaluated at `|v_l|`:
/// 0 for `|v_l| <= v_sw/2`, `(1 - sin(pi |v_l| / v_sw)) / 2` between, 1 for
/// `|v_l| >= 3 v_sw/2`. Continuous, monotone, `1/2` at `v_sw`.
/// Returns 0 for a non-finite or non-positive `v_sw`.
#[inline]
pub fn switching_weight<T: Real>(gate_speed: T, switching_speed: T) -> T {
    let v = gate_speed.abs();
    let half = T::from_f64(0.5);
    if !(switching_speed > T::ZERO && switching_speed.is_finite() && v.is_finite()) {
        return T::ZERO;
    }
    if v <= half * switching_speed {
        T::ZERO
    } else if v >= T::from_f64(1.5) * switching_speed {
        T::ONE
    } else {
        half * (T::ONE - (T::PI * v / switching_speed).sin())
    }
}

/// The combined estimate (6.21) `v_m = (1 - delta_sw) v_l + delta_sw v_h`.
///
/// Both branches, the gate measurement `v_l` ([`GateMeasurement`]) and the
/// event counter `v_h` ([`EventCounter`]), are first filtered by the same
/// first-order low-pass `1/(T_f s + 1)` (Tustin, unit DC gain), then blended
/// with the weight (6.20) evaluated at the *filtered* gate speed and the
/// switching speed (6.19) `v_sw = 2 Delta xi_min / (T_s - Delta t_min)`.
///
/// Cost per sample: a [`GateMeasurement`] and an [`EventCounter`] update, two
/// first-order sections (6 multiplications), the weight (1 division, and 1 sine
/// inside the transition band `v_sw/2 < |v_l| < 3 v_sw/2`), 2 multiplications.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blended<T = f64> {
    gate: GateMeasurement<T>,
    event: EventCounter<T>,
    lp_gate: FirstOrder<T>,
    lp_event: FirstOrder<T>,
    switching_speed: T,
    gate_filtered: T,
    event_filtered: T,
    weight: T,
    velocity: T,
}

impl<T: Real> Blended<T> {
    /// Blend for the encoder `resolution`, gate timeout `t_out_s` (`> T_s`, s)
    /// and low-pass time constant `t_f_s` (`> 0`, s; e.g. `T_R`).
    pub fn new(resolution: &EncoderResolution, t_out_s: f64, t_f_s: f64) -> Result<Self, Error> {
        let gate = GateMeasurement::new(resolution, t_out_s)?;
        let event = EventCounter::new(resolution)?;
        let t_f = positive("t_f_s", t_f_s)?;
        let lp =
            first_order_from_continuous([0.0, 1.0], [t_f, 1.0], resolution.ts_s, Prewarp::None)?
                .cast::<T>();
        Ok(Blended {
            gate,
            event,
            lp_gate: FirstOrder::new(lp),
            lp_event: FirstOrder::new(lp),
            switching_speed: T::from_f64(resolution.switching_speed()),
            gate_filtered: T::ZERO,
            event_filtered: T::ZERO,
            weight: T::ZERO,
            velocity: T::ZERO,
        })
    }

    /// One sample ending at `now_ticks`; returns the blended velocity in u/s.
    #[inline]
    pub fn update(&mut self, window: &EdgeWindow, now_ticks: u64) -> T {
        let v_l = self.gate.update(window, now_ticks);
        let v_h = self.event.update(window);
        self.gate_filtered = self.lp_gate.step(v_l);
        self.event_filtered = self.lp_event.step(v_h);
        self.weight = switching_weight(self.gate_filtered, self.switching_speed);
        self.velocity =
            (T::ONE - self.weight) * self.gate_filtered + self.weight * self.event_filtered;
        self.velocity
    }

    /// The most recent blended estimate, u/s.
    pub fn velocity(&self) -> T {
        self.velocity
    }

    /// The most recent filtered gate estimate `v_l`, u/s.
    pub fn gate_filtered(&self) -> T {
        self.gate_filtered
    }

    /// The most recent filtered event-counter estimate `v_h`, u/s.
    pub fn event_filtered(&self) -> T {
        self.event_filtered
    }

    /// The most recent weight `delta_sw` of (6.20).
    pub fn weight(&self) -> T {
        self.weight
    }

    /// The switching speed (6.19), u/s.
    pub fn switching_speed(&self) -> T {
        self.switching_speed
    }

    /// Restart at zero velocity.
    pub fn reset(&mut self) {
        self.gate.reset();
        self.event.reset();
        self.lp_gate.reset();
        self.lp_event.reset();
        self.gate_filtered = T::ZERO;
        self.event_filtered = T::ZERO;
        self.weight = T::ZERO;
        self.velocity = T::ZERO;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::velocity::stream::ConstantSpeedStream;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    const T_OUT: f64 = 20e-3;
    const T_F: f64 = 2e-3; // T_R of Table A.4
    /// Residual of the filters' start transient after the settling samples
    /// (`e^{-700/20}` ~ 6e-16) plus rounding: relative, in percent.
    const SETTLE_SLACK: f64 = 1e-8;

    #[test]
    fn switching_weight_is_continuous_monotone_and_hits_the_knots() {
        let v_sw = EncoderResolution::thesis().switching_speed();
        assert_eq!(switching_weight(0.5 * v_sw, v_sw), 0.0);
        assert_eq!(switching_weight(1.5 * v_sw, v_sw), 1.0);
        assert!((switching_weight(v_sw, v_sw) - 0.5).abs() < 1e-15);
        assert_eq!(switching_weight(-v_sw, v_sw), switching_weight(v_sw, v_sw));
        // Lipschitz constant of (6.20) is pi / (2 v_sw): no jump anywhere,
        // including across the knots v_sw/2 and 3 v_sw/2.
        let lip = core::f64::consts::PI / (2.0 * v_sw);
        let n = 20_000;
        let h = 2.0 * v_sw / n as f64;
        let mut prev = switching_weight(0.0, v_sw);
        for i in 1..=n {
            let w = switching_weight(i as f64 * h, v_sw);
            assert!(w >= prev, "monotone");
            assert!(
                w - prev <= lip * h * (1.0 + 1e-9),
                "jump at {}",
                i as f64 * h
            );
            prev = w;
        }
        assert_eq!(switching_weight(1.0, f64::NAN), 0.0);
        assert_eq!(switching_weight(f64::NAN, 1.0), 0.0);
    }

    /// At constant speeds across both ranges and the switching band, the
    /// settled blend stays within the worse of the two branches' bounds
    /// ((6.16) and (C.5) with the fewest increments a sample can hold), since
    /// both branches are filtered by a low-pass with non-negative impulse
    /// response of unit sum (a convex combination of in-bound estimates).
    #[test]
    fn settled_blend_is_within_the_branch_bounds() {
        let r = EncoderResolution::thesis();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(621);
        let v_sw = r.switching_speed();
        let mut weights_seen = [false; 3];
        for i in 0..60 {
            let mag = 0.002 * libm::pow(5.0 / 0.002, i as f64 / 59.0);
            for sign in [1.0, -1.0] {
                let v = sign * mag;
                let mut s =
                    ConstantSpeedStream::new(&r, v, rng.random_range(0.0..10_000.0), f64::INFINITY);
                let mut b = Blended::<f64>::new(&r, T_OUT, T_F).unwrap();
                let x = mag * r.ts_s / r.increment;
                let n_min = (libm::floor(x) as u32).max(2);
                let bound_h = r.event_counter_error_exact_percent(v, n_min);
                let bound = r.gate_error_percent(v).max(bound_h);
                for k in 0..1500 {
                    let (w, now) = s.next_sample();
                    let est = b.update(&w, now);
                    if k >= 800 {
                        let err = 100.0 * (est - v).abs() / mag;
                        assert!(err <= bound + SETTLE_SLACK, "v {v}: {err} > {bound}");
                        let wt = b.weight();
                        weights_seen[if wt == 0.0 {
                            0
                        } else if wt == 1.0 {
                            2
                        } else {
                            1
                        }] = true;
                    }
                }
                if mag < 0.45 * v_sw {
                    assert_eq!(b.weight(), 0.0);
                }
                if mag > 1.55 * v_sw {
                    assert_eq!(b.weight(), 1.0);
                }
            }
        }
        assert_eq!(
            weights_seen, [true; 3],
            "sweep covers gate, band and counter"
        );
    }

    #[test]
    fn f32_blend_tracks_f64() {
        let r = EncoderResolution::thesis();
        for v in [0.003, 0.05, 0.8] {
            let mut s = ConstantSpeedStream::new(&r, v, 777.0, f64::INFINITY);
            let mut b64 = Blended::<f64>::new(&r, T_OUT, T_F).unwrap();
            let mut b32 = Blended::<f32>::new(&r, T_OUT, T_F).unwrap();
            for _ in 0..1000 {
                let (w, now) = s.next_sample();
                let a = b64.update(&w, now);
                let c = b32.update(&w, now);
                assert!((a - f64::from(c)).abs() <= 1e-5 * v, "{a} {c}");
            }
        }
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let r = EncoderResolution::thesis();
        assert!(Blended::<f64>::new(&r, T_OUT, 0.0).is_err());
        assert!(Blended::<f64>::new(&r, 0.5 * r.ts_s, T_F).is_err());
        let bad = EncoderResolution {
            increment: -1.0,
            ..r
        };
        assert!(Blended::<f64>::new(&bad, T_OUT, T_F).is_err());
    }
}
