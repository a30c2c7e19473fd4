//! The cascaded P-PI controller of Figure 4.1 / Figure 6.9, one [`CascadeController::step`]
//! per sample, in motor coordinates (angle rad, velocity rad/s, torque N m).
//!
//! Per sample `k`:
//!
//! ```text
//! omega_hat = G_R(phi_m)                          velocity filter (6.1) (or caller-supplied)
//! omega_d'  = L_R(omega_d)   or omega_d           refinement (a): same lag as G_R
//! omega_ref = K_PP (phi_d - phi_m) + K_v omega_d' P position controller, K_v = 1 (4.17)
//! e         = omega_ref - omega_hat               velocity error
//! e_f       = G_pre(e)                            prefilter (notch / Butterworth), Figure 6.9
//! tau_FF    = m_e alpha_d + d_v omega_d + tau_c sign(omega_d)    (4.16), refinement (b): sample n_T ahead
//!             + tau_c h   while omega_d = 0                          refinement (c): Coulomb hold
//! tau_d     = K_P e_f + K_I x_I[k] + tau_FF + tau_offset
//! tau       = clamp(tau_d, -tau_max, tau_max)
//! x_I[k+1]  = (6.25), or the conditional integration (6.26)
//! ```
//!
//! `L_R` is the unity-gain low-pass part of the velocity filter: for the Tustin
//! velocity filter `G_R(z) = L_R(z) D(z)` with the Tustin differentiator `D`, so
//! `L_R(omega_d)` is what `G_R` makes of the desired angle, without depending on the
//! absolute angle (better conditioned in `f32`) and without a start transient.
//!
//! The integrator state `x_I` is the integral of the filtered velocity error, in rad;
//! `K_I x_I` is a torque. The error `e_omega` of (6.25)/(6.26) is the PI input of
//! Figure 6.9, i.e. the prefiltered error `e_f`. The output uses `x_I[k]` (forward
//! Euler, as (6.25)); the condition of (6.26) is evaluated on the tentative next
//! torque `K_P e_f[k] + K_I (x_I[k] + T_s e_f[k]) + tau_FF[k]`, and the reset makes
//! `K_P e_f[k] + K_I x_I[k+1] + tau_FF[k]` equal the limit exactly. The torque
//! offset (holding torque, e.g. on a tilted axis) is treated like the feedforward
//! in (6.26). With `K_I = 0` there is no integral action and (6.26) is skipped.
//!
//! Refinement (c), the Coulomb hold: `sign(omega_d)` drops to 0 when
//! the trajectory ends, while the axis, a few hundred um short of its target,
//! sticks; the integrator alone then needs seconds to build the Coulomb torque
//! from the small standing error (`K_I K_PP e` per second). The hold `h` keeps
//! the direction of the last motion (`+1`/`-1`) at standstill of the
//! trajectory as long as the position error `phi_d - phi_m` points that way,
//! and releases it (`h = 0`) when the error reaches zero or changes sign. With
//! an accurate `tau_c` the axis finishes its move as if frictionless under the
//! cascade's feedback, and stops at the target where the hold lets go. It acts
//! only with the Coulomb term switched on.
//!
//! The breakaway (`FeedforwardParams::coulomb_breakaway_rad > 0`)
//! engages the hold again, toward the target, when the axis rests with an
//! error beyond the threshold: after an overshoot, or when it stuck before
//! the target. Without it the integrator alone must build the breakaway
//! torque `2 tau_c` from the standing error, which took seconds on slow loops
//! (the cart then rested 100-450 um from its target at the end of the
//! validation record). The threshold is a dead zone: inside it the
//! integrator finishes the positioning without the Coulomb push, so the hold
//! cannot chatter about the target. A push against the previous one (the
//! axis overshot its target) doubles the threshold, back to the configured
//! one when the trajectory moves again: a light cart with high friction,
//! pushed with the whole `tau_c`, can overshoot beyond the threshold in the
//! other direction, and a constant threshold let it hunt between the two for
//! seconds (1.2 kg, 0.23 N m, +-600 um at the motor); a growing
//! one ends any such cycle after a few pushes and leaves the rest to the
//! integrator. Pushes the same way (a heavy load on a slope creeping back)
//! keep the threshold.
//!
//! [`CascadeController::reset_to`] assumes the axis at rest (`omega_d = 0`); the
//! desired-velocity low-pass starts from zero.
//!
//! Cost per sample: the velocity filter (2 multiplications), the desired-velocity
//! low-pass (3), two second-order sections (5 each), feedforward (2), Coulomb
//! hold and breakaway (1 multiplication, 7 comparisons), position loop, PI and anti-windup
//! (about 8): about 26 multiplications, no division, no allocation, no panic. Measured (crate README): 140 instructions, about 80 ns
//! per step in f64 on the development machine (137 instructions in f32).

use super::feedforward::{Feedforward, FeedforwardParams};
use super::setpoint::Setpoint;
use crate::error::{finite, positive, Error};
use crate::filter::{velocity_filter, Cascade, FirstOrder, FirstOrderCoeffs, SosCoeffs};
use crate::Real;

/// Gains of the cascaded P-PI controller (Figure 4.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeGains<T = f64> {
    /// Position gain `K_PP` in 1/s (rad/s of velocity reference per rad of error).
    pub k_pp_per_s: T,
    /// Proportional velocity gain `K_P` in N m s/rad.
    pub k_p_nm_s_per_rad: T,
    /// Integral velocity gain `K_I` in N m/rad (torque per rad of integrated velocity error).
    pub k_i_nm_per_rad: T,
    /// Velocity feedforward gain `K_v` (dimensionless), 1 by (4.17).
    pub k_v: T,
}

impl<T: Real> CascadeGains<T> {
    /// Gains with `K_v = 1` (4.17).
    pub fn new(k_pp_per_s: T, k_p_nm_s_per_rad: T, k_i_nm_per_rad: T) -> Self {
        CascadeGains {
            k_pp_per_s,
            k_p_nm_s_per_rad,
            k_i_nm_per_rad,
            k_v: T::ONE,
        }
    }

    /// Check: `K_PP, K_P, K_I` finite and `>= 0`, `K_v` finite.
    pub fn validate(&self) -> Result<(), Error> {
        for (name, v) in [
            ("k_pp_per_s", self.k_pp_per_s),
            ("k_p_nm_s_per_rad", self.k_p_nm_s_per_rad),
            ("k_i_nm_per_rad", self.k_i_nm_per_rad),
        ] {
            if !(v.is_finite() && v >= T::ZERO) {
                return Err(Error::InvalidParameter {
                    name,
                    reason: "must be finite and >= 0",
                });
            }
        }
        if !self.k_v.is_finite() {
            return Err(Error::InvalidParameter {
                name: "k_v",
                reason: "must be finite",
            });
        }
        Ok(())
    }

    /// The same gains in another scalar type.
    pub fn cast<U: Real>(&self) -> CascadeGains<U> {
        CascadeGains {
            k_pp_per_s: U::from_f64(self.k_pp_per_s.to_f64()),
            k_p_nm_s_per_rad: U::from_f64(self.k_p_nm_s_per_rad.to_f64()),
            k_i_nm_per_rad: U::from_f64(self.k_i_nm_per_rad.to_f64()),
            k_v: U::from_f64(self.k_v.to_f64()),
        }
    }
}

/// How the velocity integrator handles torque saturation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AntiWindup {
    /// Conditional integration (6.26): when the torque would exceed a limit in
    /// the direction of the error, the integrator is set so that the torque meets
    /// the limit exactly.
    #[default]
    ConditionalIntegration,
    /// Plain integration (6.25), for comparison (Figure 6.10).
    Off,
}

/// Configuration of [`CascadeController`]. Public fields; checked by
/// [`CascadeController::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeConfig<T = f64> {
    /// Sampling time `T_s` in s (100 us in the thesis).
    pub ts_s: T,
    /// Controller gains.
    pub gains: CascadeGains<T>,
    /// Velocity filter `G_R` (6.1) from the measured angle (rad) to the velocity
    /// estimate (rad/s); must have a zero at `z = 1` (`b0 + b1 = 0`) and `|a1| < 1`.
    /// Not used by [`CascadeController::step_with_velocity`] except for its pole,
    /// see [`CascadeConfig::filter_desired_velocity`].
    pub velocity_filter: FirstOrderCoeffs<T>,
    /// Prefilter `G_pre` on the velocity error (notch (4.1) and/or Butterworth
    /// (4.3)); unused sections are [`SosCoeffs::IDENTITY`]. Must be stable.
    pub prefilter: [SosCoeffs<T>; 2],
    /// Torque limit `tau_m,max` in N m (> 0).
    pub torque_max_nm: T,
    /// Anti-windup method.
    pub anti_windup: AntiWindup,
    /// Torque feedforward (4.16).
    pub feedforward: Feedforward<T>,
    /// Constant torque offset in N m added to the command (holding torque).
    pub torque_offset_nm: T,
    /// Refinement (a): pass the desired velocity through the low-pass part of
    /// `G_R` before it enters the velocity loop, so that reference and
    /// measurement see the same lag.
    pub filter_desired_velocity: bool,
    /// Refinement (b): take the feedforward torque from [`Setpoint::ahead`]
    /// (the trajectory `n_T` samples ahead, dead-time preview) instead of
    /// [`Setpoint::now`].
    pub feedforward_preview: bool,
}

impl<T: Real> CascadeConfig<T> {
    /// The thesis structure as drawn in Figure 4.1: velocity filter
    /// `G_R = s/(T_R s + 1)` (Tustin), no prefilter, conditional-integration
    /// anti-windup, no feedforward, no offset, refinements off.
    pub fn new(
        gains: CascadeGains<T>,
        ts_s: f64,
        t_r_s: f64,
        torque_max_nm: T,
    ) -> Result<Self, Error> {
        let vf = velocity_filter(t_r_s, ts_s)?;
        Ok(CascadeConfig {
            ts_s: T::from_f64(ts_s),
            gains,
            velocity_filter: vf.cast(),
            prefilter: [SosCoeffs::IDENTITY; 2],
            torque_max_nm,
            anti_windup: AntiWindup::ConditionalIntegration,
            feedforward: Feedforward::none(),
            torque_offset_nm: T::ZERO,
            filter_desired_velocity: false,
            feedforward_preview: false,
        })
    }

    /// The same configuration in another scalar type (e.g. designed in `f64`,
    /// run in `f32`).
    pub fn cast<U: Real>(&self) -> CascadeConfig<U> {
        CascadeConfig {
            ts_s: U::from_f64(self.ts_s.to_f64()),
            gains: self.gains.cast(),
            velocity_filter: self.velocity_filter.cast(),
            prefilter: [self.prefilter[0].cast(), self.prefilter[1].cast()],
            torque_max_nm: U::from_f64(self.torque_max_nm.to_f64()),
            anti_windup: self.anti_windup,
            feedforward: self.feedforward.cast(),
            torque_offset_nm: U::from_f64(self.torque_offset_nm.to_f64()),
            filter_desired_velocity: self.filter_desired_velocity,
            feedforward_preview: self.feedforward_preview,
        }
    }

    /// Check every parameter (see the field docs).
    pub fn validate(&self) -> Result<(), Error> {
        positive("ts_s", self.ts_s.to_f64())?;
        positive("torque_max_nm", self.torque_max_nm.to_f64())?;
        self.gains.validate()?;
        self.feedforward.validate()?;
        finite("torque_offset_nm", self.torque_offset_nm.to_f64())?;
        let v = &self.velocity_filter;
        let (b0, b1, a1) = (v.b0.to_f64(), v.b1.to_f64(), v.a1.to_f64());
        if !(b0.is_finite() && b1.is_finite() && a1.is_finite() && a1.abs() < 1.0) {
            return Err(Error::InvalidParameter {
                name: "velocity_filter",
                reason: "coefficients must be finite with |a1| < 1",
            });
        }
        if (b0 + b1).abs() > 1e-6 * b0.abs().max(1.0) {
            return Err(Error::InvalidParameter {
                name: "velocity_filter",
                reason: "must differentiate: zero at z = 1 (b0 + b1 = 0)",
            });
        }
        for c in self.prefilter.iter() {
            let fin = [c.b0, c.b1, c.b2, c.a1, c.a2].iter().all(|x| x.is_finite());
            if !(fin && c.is_stable()) {
                return Err(Error::InvalidParameter {
                    name: "prefilter",
                    reason: "sections must be finite and stable",
                });
            }
        }
        Ok(())
    }
}

/// Everything one controller sample computed (for the command and for logging).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ControlOutput<T = f64> {
    /// Torque command `tau` in N m, within `[-tau_max, tau_max]`.
    pub torque_nm: T,
    /// Torque before saturation `tau_d` in N m.
    pub torque_unsaturated_nm: T,
    /// `true` if `tau_d` was outside the limits (or not finite).
    pub saturated: bool,
    /// Position error `phi_d - phi_m` in rad.
    pub position_error_rad: T,
    /// Velocity reference `omega_ref` of the velocity loop in rad/s.
    pub velocity_reference_rad_s: T,
    /// Velocity estimate `omega_hat` in rad/s.
    pub velocity_estimate_rad_s: T,
    /// Velocity error `e = omega_ref - omega_hat` in rad/s.
    pub velocity_error_rad_s: T,
    /// Prefiltered velocity error `e_f` in rad/s.
    pub velocity_error_filtered_rad_s: T,
    /// Integrator state `x_I[k+1]` after this sample, in rad.
    pub integrator_rad: T,
    /// Feedforward torque `tau_FF` in N m (without the offset).
    pub feedforward_nm: T,
    /// `false` if an input or an intermediate value was not finite (or
    /// overflowed); the torque is then 0, the integrator is kept (zeroed if it
    /// overflowed) and the filter states are reset (velocity filter: at rest at
    /// the measured angle).
    pub finite: bool,
}

/// The velocity filter `G_R(z) = b0 (1 - z^-1) / (1 + a1 z^-1)` evaluated on the
/// angle increment, `y[k] = b0 (x[k] - x[k-1]) - a1 y[k-1]`: the same transfer
/// function as a [`FirstOrder`] section with `b1 = -b0`, but without the
/// cancellation of two terms of the size `b0 x` (about 5000 rad/s at 10 rad
/// for `T_R = 2 ms`), which in `f32` would add 5e-4 rad/s of rounding noise per
/// sample. Cost: 2 multiplications, 2 additions.
#[derive(Clone, Copy, Debug)]
struct VelocityFilterState<T> {
    b0: T,
    a1: T,
    last_angle_rad: T,
    last_velocity_rad_s: T,
}

impl<T: Real> VelocityFilterState<T> {
    #[inline]
    fn step(&mut self, angle_rad: T) -> T {
        let y = self.b0 * (angle_rad - self.last_angle_rad) - self.a1 * self.last_velocity_rad_s;
        self.last_angle_rad = angle_rad;
        self.last_velocity_rad_s = y;
        y
    }

    fn reset_to(&mut self, angle_rad: T) {
        self.last_angle_rad = angle_rad;
        self.last_velocity_rad_s = T::ZERO;
    }
}

/// The cascaded P-PI controller with prefilter, anti-windup and feedforward.
#[derive(Clone, Copy, Debug)]
pub struct CascadeController<T = f64> {
    config: CascadeConfig<T>,
    ff: FeedforwardParams<T>,
    vel_filter: VelocityFilterState<T>,
    desired_lp: FirstOrder<T>,
    prefilter: Cascade<T, 2>,
    integrator_rad: T,
    inv_k_i: T,
    /// Direction of the Coulomb hold `h` of refinement (c): +1, -1 or 0.
    coulomb_hold: T,
    /// Breakaway threshold for the next engagement at rest, rad: the
    /// configured one, doubled by each push against the previous one until
    /// the trajectory moves.
    breakaway_rad: T,
    /// Direction of the last breakaway push at rest (0: none since the
    /// trajectory moved).
    last_push: T,
}

impl<T: Real> CascadeController<T> {
    /// A controller at rest at angle 0. Errors if the configuration is invalid.
    pub fn new(config: CascadeConfig<T>) -> Result<Self, Error> {
        config.validate()?;
        let vf = config.velocity_filter;
        let half = T::from_f64(0.5) * (T::ONE + vf.a1);
        let lp = FirstOrderCoeffs {
            b0: half,
            b1: half,
            a1: vf.a1,
        };
        let k_i = config.gains.k_i_nm_per_rad;
        let mut c = CascadeController {
            config,
            ff: config.feedforward.effective(),
            vel_filter: VelocityFilterState {
                b0: vf.b0,
                a1: vf.a1,
                last_angle_rad: T::ZERO,
                last_velocity_rad_s: T::ZERO,
            },
            desired_lp: FirstOrder::new(lp),
            prefilter: Cascade::new(config.prefilter),
            integrator_rad: T::ZERO,
            inv_k_i: if k_i > T::ZERO { T::ONE / k_i } else { T::ZERO },
            coulomb_hold: T::ZERO,
            breakaway_rad: T::ZERO,
            last_push: T::ZERO,
        };
        c.reset_to(T::ZERO);
        Ok(c)
    }

    /// The configuration in use.
    pub fn config(&self) -> &CascadeConfig<T> {
        &self.config
    }

    /// Replace the configuration at run time (e.g. gains from a tuning slider).
    /// Filter states are kept (coefficients replaced), and the integrator is
    /// rescaled so that the integral torque `K_I x_I` is continuous: a gain change
    /// at zero error causes no torque step. An invalid configuration is rejected
    /// and the controller is left unchanged.
    pub fn set_config(&mut self, config: CascadeConfig<T>) -> Result<(), Error> {
        let mut next = Self::new(config)?;
        next.vel_filter.last_angle_rad = self.vel_filter.last_angle_rad;
        next.vel_filter.last_velocity_rad_s = self.vel_filter.last_velocity_rad_s;
        let mut lp = self.desired_lp;
        lp.coeffs = next.desired_lp.coeffs;
        next.desired_lp = lp;
        let mut pre = self.prefilter;
        for (n, o) in next.prefilter.sections.iter().zip(pre.sections.iter_mut()) {
            o.coeffs = n.coeffs;
        }
        next.prefilter = pre;
        let integral_torque = self.config.gains.k_i_nm_per_rad * self.integrator_rad;
        next.integrator_rad = integral_torque * next.inv_k_i;
        *self = next;
        Ok(())
    }

    /// Bumpless start at the current position: the velocity filter sees a
    /// motor at rest at `angle_rad`, all filter states and the integrator are zero.
    pub fn reset_to(&mut self, angle_rad: T) {
        self.vel_filter.reset_to(angle_rad);
        self.desired_lp.reset();
        self.prefilter.reset();
        self.integrator_rad = T::ZERO;
        self.coulomb_hold = T::ZERO;
        self.breakaway_rad = self.ff.coulomb_breakaway_rad;
        self.last_push = T::ZERO;
    }

    /// As [`Self::reset_to`], with the integrator preloaded so that at zero
    /// error and zero feedforward the command is `torque_nm` (e.g. the torque
    /// that was holding the axis before the controller took over).
    /// Without integral action (`K_I = 0`) the integrator stays 0.
    pub fn reset_to_holding(&mut self, angle_rad: T, torque_nm: T) {
        self.reset_to(angle_rad);
        let x = (torque_nm - self.config.torque_offset_nm) * self.inv_k_i;
        if x.is_finite() {
            self.integrator_rad = x;
        }
    }

    /// Change the constant torque offset (N m) at run time; ignored if not finite.
    pub fn set_torque_offset(&mut self, torque_offset_nm: T) {
        if torque_offset_nm.is_finite() {
            self.config.torque_offset_nm = torque_offset_nm;
        }
    }

    /// Integrator state `x_I` in rad.
    pub fn integrator_rad(&self) -> T {
        self.integrator_rad
    }

    /// Direction of the Coulomb hold of refinement (c): `+1`, `-1`, or `0`
    /// when released.
    pub fn coulomb_hold(&self) -> T {
        self.coulomb_hold
    }

    /// One sample with the velocity from the velocity filter `G_R` (6.1) of the
    /// measured motor angle (rad).
    #[inline]
    pub fn step(&mut self, setpoint: &Setpoint<T>, measured_angle_rad: T) -> ControlOutput<T> {
        if !measured_angle_rad.is_finite() {
            return self.fault();
        }
        let omega_hat = self.vel_filter.step(measured_angle_rad);
        let out = self.step_with_velocity(setpoint, measured_angle_rad, omega_hat);
        if !out.finite {
            self.vel_filter.reset_to(measured_angle_rad);
        }
        out
    }

    /// One sample with a velocity estimate (rad/s) supplied by the caller (e.g.
    /// the blended encoder estimator of Section 6.1); `G_R` is not run.
    #[inline]
    pub fn step_with_velocity(
        &mut self,
        setpoint: &Setpoint<T>,
        measured_angle_rad: T,
        velocity_estimate_rad_s: T,
    ) -> ControlOutput<T> {
        let cfg = &self.config;
        let g = &cfg.gains;
        let now = &setpoint.now;
        let ff_sample = if cfg.feedforward_preview {
            &setpoint.ahead
        } else {
            now
        };
        let omega_d = if cfg.filter_desired_velocity {
            self.desired_lp.step(now.velocity_rad_s)
        } else {
            now.velocity_rad_s
        };
        let e_phi = now.angle_rad - measured_angle_rad;
        let omega_ref = g.k_pp_per_s * e_phi + g.k_v * omega_d;
        let e = omega_ref - velocity_estimate_rad_s;
        let e_f = self.prefilter.step(e);
        let mut tau_ff = self
            .ff
            .torque_nm(ff_sample.velocity_rad_s, ff_sample.acceleration_rad_s2);
        // Refinement (c), the Coulomb hold (module docs).
        let v_ff = ff_sample.velocity_rad_s;
        let band = self.ff.coulomb_deadband_rad_s;
        if v_ff > band || v_ff < -band {
            self.coulomb_hold = if v_ff > band { T::ONE } else { -T::ONE };
            self.breakaway_rad = self.ff.coulomb_breakaway_rad;
            self.last_push = T::ZERO;
        } else {
            // Breakaway: at rest, an error beyond the threshold engages the
            // hold toward the target (only with the Coulomb term on); a push
            // against the previous one doubles the threshold (module docs).
            let th = self.breakaway_rad;
            if self.coulomb_hold == T::ZERO && th > T::ZERO && self.ff.coulomb_nm > T::ZERO {
                // against the last push the threshold is doubled
                let against = e_phi * self.last_push < T::ZERO;
                let need = if against { th + th } else { th };
                if e_phi > need || e_phi < -need {
                    self.breakaway_rad = need;
                    self.coulomb_hold = if e_phi > T::ZERO { T::ONE } else { -T::ONE };
                    self.last_push = self.coulomb_hold;
                }
            }
            if e_phi * self.coulomb_hold > T::ZERO {
                tau_ff += self.coulomb_hold * self.ff.coulomb_nm;
            } else {
                self.coulomb_hold = T::ZERO;
            }
        }
        let bias = tau_ff + cfg.torque_offset_nm;
        let p_part = g.k_p_nm_s_per_rad * e_f;
        let tau_d = p_part + g.k_i_nm_per_rad * self.integrator_rad + bias;
        if !(tau_d.is_finite() && e_f.is_finite()) {
            self.desired_lp.reset();
            self.prefilter.reset();
            if !self.integrator_rad.is_finite() {
                self.integrator_rad = T::ZERO;
            }
            return self.fault();
        }
        let max = cfg.torque_max_nm;
        let tau = tau_d.clamp_to(-max, max);
        let saturated = tau_d > max || tau_d < -max;

        // Integrator update: (6.25), or (6.26) when the tentative next torque
        // K_P e_f[k] + K_I (x_I[k] + T_s e_f[k]) + tau_FF[k] violates a limit
        // in the direction of the error.
        let x_next = self.integrator_rad + cfg.ts_s * e_f;
        self.integrator_rad = match cfg.anti_windup {
            AntiWindup::Off => x_next,
            AntiWindup::ConditionalIntegration => {
                if self.inv_k_i > T::ZERO {
                    let tau_next = p_part + g.k_i_nm_per_rad * x_next + bias;
                    if tau_next >= max && e_f > T::ZERO {
                        (max - p_part - bias) * self.inv_k_i
                    } else if tau_next <= -max && e_f < T::ZERO {
                        (-max - p_part - bias) * self.inv_k_i
                    } else {
                        x_next
                    }
                } else {
                    x_next
                }
            }
        };

        ControlOutput {
            torque_nm: tau,
            torque_unsaturated_nm: tau_d,
            saturated,
            position_error_rad: e_phi,
            velocity_reference_rad_s: omega_ref,
            velocity_estimate_rad_s,
            velocity_error_rad_s: e,
            velocity_error_filtered_rad_s: e_f,
            integrator_rad: self.integrator_rad,
            feedforward_nm: tau_ff,
            finite: true,
        }
    }

    fn fault(&self) -> ControlOutput<T> {
        ControlOutput {
            saturated: true,
            integrator_rad: self.integrator_rad,
            finite: false,
            ..ControlOutput::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::setpoint::MotionSample;
    use crate::filter::butterworth_lowpass;

    const TS: f64 = 1e-4;
    const T_R: f64 = 2e-3;

    fn config() -> CascadeConfig<f64> {
        let mut c = CascadeConfig::new(CascadeGains::new(6.29, 0.12, 1.39), TS, T_R, 2.0).unwrap();
        c.prefilter[0] = butterworth_lowpass(123.24, TS).unwrap();
        c
    }

    #[test]
    fn reset_to_gives_a_bumpless_start_at_any_position() {
        let mut c = CascadeController::new(config()).unwrap();
        c.reset_to(37.5);
        for _ in 0..100 {
            let out = c.step(&Setpoint::hold(37.5), 37.5);
            assert_eq!(out.torque_nm, 0.0);
            assert_eq!(out.velocity_estimate_rad_s, 0.0);
        }
        c.reset_to_holding(-3.0, 0.4);
        let out = c.step(&Setpoint::hold(-3.0), -3.0);
        assert!((out.torque_nm - 0.4).abs() < 1e-12);
    }

    #[test]
    fn torque_offset_and_feedforward_add_to_the_command() {
        let mut cfg = config();
        cfg.torque_offset_nm = 0.3;
        cfg.feedforward = Feedforward::nonlinear(2e-3, 1e-3, 0.1);
        let mut c = CascadeController::new(cfg).unwrap();
        let sp = Setpoint::at(MotionSample {
            angle_rad: 0.0,
            velocity_rad_s: 0.0,
            acceleration_rad_s2: 100.0,
        });
        let out = c.step(&sp, 0.0);
        assert!((out.feedforward_nm - 0.2).abs() < 1e-15);
        assert!((out.torque_nm - 0.5).abs() < 1e-15);
        // preview: the feedforward uses `ahead`
        let mut cfg2 = cfg;
        cfg2.feedforward_preview = true;
        let mut c2 = CascadeController::new(cfg2).unwrap();
        let ahead = MotionSample {
            acceleration_rad_s2: 300.0,
            ..sp.now
        };
        let out = c2.step(&Setpoint::with_preview(sp.now, ahead), 0.0);
        assert!((out.feedforward_nm - 0.6).abs() < 1e-15);
    }

    /// Refinement (c), issue 12 (static error): after a move in + direction the
    /// Coulomb term holds `+tau_c` at standstill while the axis is short of
    /// its target, lets go for good when the error reaches zero, and never
    /// acts without the Coulomb term.
    #[test]
    fn the_coulomb_hold_completes_the_move_and_lets_go_at_the_target() {
        let tau_c = 0.1;
        let mut cfg = config();
        cfg.feedforward = Feedforward::nonlinear(0.0, 0.0, tau_c);
        let mut c = CascadeController::new(cfg).unwrap();
        let moving = |angle: f64| {
            Setpoint::at(MotionSample {
                angle_rad: angle,
                velocity_rad_s: 1.0,
                acceleration_rad_s2: 0.0,
            })
        };
        assert_eq!(c.step(&moving(0.0), 0.0).feedforward_nm, tau_c);
        assert_eq!(c.coulomb_hold(), 1.0);
        // The trajectory stops at 1 rad, the axis 1 mrad short: hold.
        let stop = Setpoint::hold(1.0);
        for _ in 0..10 {
            assert_eq!(c.step(&stop, 0.999).feedforward_nm, tau_c);
        }
        // It reaches the target: released, and stays released even if the
        // axis then rests short again (no breakaway configured).
        assert_eq!(c.step(&stop, 1.0).feedforward_nm, 0.0);
        assert_eq!(c.coulomb_hold(), 0.0);
        assert_eq!(c.step(&stop, 0.999).feedforward_nm, 0.0);
        // Overshoot after a move in - direction releases it too.
        let back = Setpoint::at(MotionSample {
            angle_rad: 1.0,
            velocity_rad_s: -1.0,
            acceleration_rad_s2: 0.0,
        });
        assert_eq!(c.step(&back, 1.0).feedforward_nm, -tau_c);
        assert_eq!(c.step(&Setpoint::hold(0.5), 0.6).feedforward_nm, -tau_c);
        assert_eq!(c.step(&Setpoint::hold(0.5), 0.4).feedforward_nm, 0.0);
        // Reset clears it.
        c.step(&moving(0.0), 0.0);
        c.reset_to(0.0);
        assert_eq!(c.coulomb_hold(), 0.0);
        // Without the Coulomb term nothing is held.
        let mut lin = config();
        lin.feedforward = Feedforward::linear(1e-3, 1e-3);
        let mut c = CascadeController::new(lin).unwrap();
        c.step(&moving(0.0), 0.0);
        assert_eq!(c.step(&stop, 0.5).feedforward_nm, 0.0);
    }

    /// The test cascade with Coulomb feedforward `tau_c` only and the
    /// breakaway threshold `threshold_rad`.
    fn breakaway_config(tau_c: f64, threshold_rad: f64) -> CascadeConfig<f64> {
        let mut cfg = config();
        cfg.feedforward = Feedforward::nonlinear(0.0, 0.0, tau_c);
        cfg.feedforward.params.coulomb_breakaway_rad = threshold_rad;
        cfg
    }

    /// Refinement (c) with the breakaway (static error): an axis
    /// resting beyond the threshold from its target, after an overshoot or
    /// short of it, gets the Coulomb push toward the target; inside the
    /// threshold nothing is pushed (dead zone), and the push ends at the
    /// target.
    #[test]
    fn the_coulomb_breakaway_pushes_a_resting_axis_back_toward_its_target() {
        let tau_c = 0.1;
        let th = 2e-3;
        let cfg = breakaway_config(tau_c, th);
        let mut c = CascadeController::new(cfg).unwrap();
        let stop = Setpoint::hold(1.0);
        // At rest inside the dead zone: no push either way.
        assert_eq!(c.step(&stop, 1.0 - 0.5 * th).feedforward_nm, 0.0);
        assert_eq!(c.step(&stop, 1.0 + 0.5 * th).feedforward_nm, 0.0);
        assert_eq!(c.coulomb_hold(), 0.0);
        // Overshot beyond it: pushed back (-), until the target is reached.
        for _ in 0..5 {
            assert_eq!(c.step(&stop, 1.0 + 2.0 * th).feedforward_nm, -tau_c);
        }
        assert_eq!(c.step(&stop, 1.0 + 0.5 * th).feedforward_nm, -tau_c);
        assert_eq!(c.step(&stop, 1.0).feedforward_nm, 0.0);
        assert_eq!(c.coulomb_hold(), 0.0);
        // Stuck short beyond the threshold, doubled by the push against the
        // previous one: pushed on (+).
        assert_eq!(c.step(&stop, 1.0 - 1.5 * th).feedforward_nm, 0.0);
        assert_eq!(c.step(&stop, 1.0 - 3.0 * th).feedforward_nm, tau_c);
        assert_eq!(c.coulomb_hold(), 1.0);
        // Without the Coulomb term there is no breakaway.
        let mut lin = config();
        lin.feedforward = Feedforward::linear(1e-3, 1e-3);
        lin.feedforward.params.coulomb_breakaway_rad = th;
        let mut c = CascadeController::new(lin).unwrap();
        assert_eq!(c.step(&stop, 1.0 + 2.0 * th).feedforward_nm, 0.0);
        // A negative or non-finite threshold is refused.
        for bad in [-1e-3, f64::NAN] {
            assert!(CascadeController::new(breakaway_config(tau_c, bad)).is_err());
        }
    }

    /// A light cart with high friction hunted for seconds after
    /// its move: each breakaway push overshot beyond the threshold the other
    /// way. A push against the previous one doubles the threshold, so a hunt
    /// of constant amplitude ends; pushes the same way keep it; a moving
    /// trajectory restores it.
    #[test]
    fn a_breakaway_hunt_ends_the_threshold_doubling() {
        let tau_c = 0.1;
        let th = 2e-3;
        let cfg = breakaway_config(tau_c, th);
        let mut c = CascadeController::new(cfg).unwrap();
        let stop = Setpoint::hold(1.0);
        // A hunt between +-5 th: pushed at th, then against it at 2 th and
        // 4 th, then left to the integrator (8 th).
        // Each push carries the axis through the target to 5 th on the other
        // side; without a push it stays.
        let mut pushes = 0;
        let mut at = 1.0 + 5.0 * th;
        for _ in 0..10 {
            if c.step(&stop, at).feedforward_nm != 0.0 {
                pushes += 1;
                // the push ends where the error changes sign
                c.step(&stop, 1.0);
                at = 2.0 - at;
            }
        }
        assert_eq!(pushes, 3);
        // Pushes the same way keep the threshold.
        let mut c = CascadeController::new(cfg).unwrap();
        for _ in 0..5 {
            assert_eq!(c.step(&stop, 1.0 - 1.5 * th).feedforward_nm, tau_c);
            c.step(&stop, 1.0);
        }
        // The trajectory moves: the configured threshold again.
        let moving = Setpoint::at(crate::control::MotionSample {
            angle_rad: 1.0,
            velocity_rad_s: 1.0,
            acceleration_rad_s2: 0.0,
        });
        c.step(&moving, 1.0);
        c.step(&stop, 1.0);
        assert_eq!(c.step(&stop, 1.0 + 1.5 * th).feedforward_nm, -tau_c);
    }

    #[test]
    fn saturates_and_never_emits_non_finite_torque() {
        let mut c = CascadeController::new(config()).unwrap();
        let out = c.step(&Setpoint::hold(1e6), 0.0);
        assert_eq!(out.torque_nm, 2.0);
        assert!(out.saturated);
        for bad in [f64::NAN, f64::INFINITY, 1e308] {
            let out = c.step(&Setpoint::hold(bad), 0.0);
            assert!(out.torque_nm.is_finite());
            let out = c.step(&Setpoint::hold(0.0), bad);
            assert!(out.torque_nm.is_finite());
        }
        // recovers after the fault
        c.reset_to(0.0);
        let out = c.step(&Setpoint::hold(0.0), 0.0);
        assert!(out.finite && out.torque_nm == 0.0);
    }

    #[test]
    fn invalid_configurations_are_errors() {
        let mut c = config();
        c.torque_max_nm = 0.0;
        assert!(CascadeController::new(c).is_err());
        let mut c = config();
        c.gains.k_p_nm_s_per_rad = -1.0;
        assert!(CascadeController::new(c).is_err());
        let mut c = config();
        c.prefilter[1].a2 = 1.5; // unstable
        assert!(CascadeController::new(c).is_err());
        let mut c = config();
        c.velocity_filter.b1 = 0.0; // not a differentiator
        assert!(CascadeController::new(c).is_err());
        assert!(
            CascadeConfig::<f64>::new(CascadeGains::new(1.0, 1.0, 1.0), TS, -1.0, 1.0).is_err()
        );
    }

    /// (6.26): while the error keeps pushing into the limit, the integrator is
    /// set so that the tentative next torque meets the limit exactly.
    #[test]
    fn conditional_integration_holds_the_torque_exactly_at_the_limit() {
        let mut cfg = config();
        cfg.prefilter = [SosCoeffs::IDENTITY; 2];
        cfg.torque_offset_nm = 0.25;
        let mut c = CascadeController::new(cfg).unwrap();
        let g = cfg.gains;
        for k in 0..50 {
            let out = c.step(&Setpoint::hold(5.0), 0.0);
            // first sample saturated, then exactly at the limit
            assert!((out.torque_nm - 2.0).abs() < 1e-12);
            let e_f = out.velocity_error_filtered_rad_s;
            let next = g.k_p_nm_s_per_rad * e_f + g.k_i_nm_per_rad * out.integrator_rad + 0.25;
            assert!((next - 2.0).abs() < 1e-12, "k {k}: {next}");
        }
        // plain integration (6.25) keeps integrating instead
        cfg.anti_windup = AntiWindup::Off;
        let mut c = CascadeController::new(cfg).unwrap();
        let mut x = 0.0;
        for _ in 0..50 {
            let out = c.step(&Setpoint::hold(5.0), 0.0);
            let expected = x + TS * out.velocity_error_filtered_rad_s;
            assert!((out.integrator_rad - expected).abs() < 1e-15);
            x = out.integrator_rad;
        }
    }

    /// `step` is `step_with_velocity` fed with `G_R` of the measured angle.
    #[test]
    fn step_equals_step_with_velocity_from_the_velocity_filter() {
        let cfg = config();
        let mut a = CascadeController::new(cfg).unwrap();
        let mut b = CascadeController::new(cfg).unwrap();
        let mut g_r = crate::filter::FirstOrder::new(cfg.velocity_filter);
        g_r.reset_to(0.0, 0.0);
        for k in 0..500 {
            let phi = libm::sin(k as f64 * 0.01);
            let sp = Setpoint::hold(0.3);
            let oa = a.step(&sp, phi);
            let ob = b.step_with_velocity(&sp, phi, g_r.step(phi));
            assert!((oa.torque_nm - ob.torque_nm).abs() < 1e-9);
            assert!((oa.velocity_estimate_rad_s - ob.velocity_estimate_rad_s).abs() < 1e-9);
        }
    }

    /// Refinement (a): the low-pass applied to `omega_d` gives what `G_R`
    /// makes of `phi_d` (`G_R = L_R D` with the Tustin differentiator `D`); for
    /// a cubic `phi_d` the two differ by the Tustin derivative error
    /// `T_s^2 phi''' / 12` only.
    #[test]
    fn desired_velocity_filter_equals_g_r_of_the_desired_angle() {
        let mut cfg = config();
        cfg.filter_desired_velocity = true;
        cfg.gains.k_pp_per_s = 0.0; // omega_ref = L(omega_d) exactly
        let mut c = CascadeController::new(cfg).unwrap();
        let mut g_r = crate::filter::FirstOrder::new(cfg.velocity_filter);
        g_r.reset_to(0.0, 0.0);
        let j = 3000.0;
        for k in 0..3000 {
            let t = k as f64 * TS;
            let sp = Setpoint::at(MotionSample {
                angle_rad: j * t * t * t / 6.0,
                velocity_rad_s: j * t * t / 2.0,
                acceleration_rad_s2: j * t,
            });
            let out = c.step(&sp, 0.0);
            let via_g_r = g_r.step(sp.now.angle_rad);
            let tol = TS * TS * j / 12.0 * 1.01 + 1e-12 * sp.now.velocity_rad_s;
            let diff = (out.velocity_reference_rad_s - via_g_r).abs();
            assert!(diff <= tol, "k {k}: {diff} > {tol}");
        }
    }

    /// Seeded sweep: for random valid configurations and random finite inputs
    /// over 60 decades (including overflow in f32), the command is finite and
    /// within the torque limit, and the controller keeps working.
    fn sweep_invariants<T: Real>(seed: u64) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let big = |rng: &mut rand_xoshiro::Xoshiro256PlusPlus| {
            let mag = libm::pow(10.0, rng.random_range(-10.0..50.0));
            if rng.random::<bool>() {
                mag
            } else {
                -mag
            }
        };
        for _ in 0..200 {
            let gains = CascadeGains::new(
                rng.random_range(0.0..100.0),
                rng.random_range(0.0..1.0),
                rng.random_range(0.0..10.0),
            );
            let max = rng.random_range(0.01..10.0);
            let mut cfg = CascadeConfig::new(gains, TS, rng.random_range(1e-4..1e-2), max).unwrap();
            if rng.random::<bool>() {
                cfg.prefilter[0] = butterworth_lowpass(rng.random_range(50.0..3000.0), TS).unwrap();
            }
            if rng.random::<bool>() {
                cfg.prefilter[1] =
                    crate::filter::notch(rng.random_range(100.0..3000.0), 4.6, TS).unwrap();
            }
            cfg.feedforward = Feedforward::nonlinear(1e-3, 1e-3, 0.1);
            cfg.feedforward_preview = rng.random::<bool>();
            cfg.filter_desired_velocity = rng.random::<bool>();
            if rng.random::<bool>() {
                cfg.anti_windup = AntiWindup::Off;
            }
            let mut c = CascadeController::<T>::new(cfg.cast()).unwrap();
            let lim = T::from_f64(max);
            for _ in 0..100 {
                let m = MotionSample {
                    angle_rad: T::from_f64(big(&mut rng)),
                    velocity_rad_s: T::from_f64(big(&mut rng)),
                    acceleration_rad_s2: T::from_f64(big(&mut rng)),
                };
                let out = c.step(&Setpoint::at(m), T::from_f64(big(&mut rng)));
                assert!(out.torque_nm.is_finite());
                assert!(out.torque_nm <= lim && out.torque_nm >= -lim);
            }
            c.reset_to(T::ZERO);
            let out = c.step(&Setpoint::hold(T::ZERO), T::ZERO);
            assert!(out.finite && out.torque_nm == T::ZERO);
        }
    }

    #[test]
    fn random_finite_inputs_give_bounded_finite_torque_f64() {
        sweep_invariants::<f64>(1);
    }

    #[test]
    fn random_finite_inputs_give_bounded_finite_torque_f32() {
        sweep_invariants::<f32>(2);
    }

    #[test]
    fn set_config_changes_gains_without_a_torque_step() {
        let mut c = CascadeController::new(config()).unwrap();
        c.reset_to_holding(0.0, 0.7);
        for _ in 0..10 {
            c.step(&Setpoint::hold(0.0), 0.0);
        }
        let before = c.step(&Setpoint::hold(0.0), 0.0).torque_nm;
        let mut cfg = config();
        cfg.gains.k_i_nm_per_rad *= 3.0;
        cfg.gains.k_p_nm_s_per_rad *= 2.0;
        c.set_config(cfg).unwrap();
        let after = c.step(&Setpoint::hold(0.0), 0.0).torque_nm;
        assert!((before - 0.7).abs() < 1e-12 && (after - before).abs() < 1e-12);
        cfg.torque_max_nm = -1.0;
        assert!(c.set_config(cfg).is_err());
        assert_eq!(c.config().gains.k_i_nm_per_rad, 3.0 * 1.39);
    }
}
