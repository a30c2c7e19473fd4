//! The rigid-body inertia `m_e` (4.15) from the momentum balance of the
//! friction runs (stage 7).
//!
//! The feedforward's inertia acts over the validation move's large, slow
//! motion. The FRF fit (stage 5) measures it through the small-signal
//! response, where on heavy payloads on soft belts the fitted `m_c` came out
//! up to 38 % heavy (the fit's reported one-sigma: 1-8 %), and the inertia
//! feedforward's error was the largest part of the validation move's cart
//! error. The friction runs move the same rigid body back and forth: between
//! the plateau of one run and the plateau of the next, the torque impulse
//! minus the holding torque and the friction is `m_e` times the velocity
//! change, measured where the belt's oscillation averages out.

use super::super::motion::TrackRecord;
use super::super::runner::Sample;

/// Largest relative standard error of [`rigid_inertia_from_phases`] that
/// is accepted: beyond it the phases do not determine the inertia better
/// than the FRF fit's uncertainty on the heavy, soft axes of the robustness study
/// (m_c one-sigma up to 8 %).
pub const MAX_INERTIA_RELATIVE_SIGMA: f64 = 0.05;

/// The rigid-body inertia from the momentum balances between the runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidInertia {
    /// `m_e~ = Theta_e + i_t^2 m_c` (4.15), kg m^2.
    pub inertia_kg_m2: f64,
    /// Its standard error from the scatter of the phases, kg m^2.
    pub sigma_kg_m2: f64,
}

/// Samples `[start, start + len)` of a record over which the motor's mean
/// velocity is taken.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VelocityWindow {
    /// First sample.
    pub start: usize,
    /// Number of samples.
    pub len: usize,
}

/// One whole ringing period of `f_ring_hz` centred on the middle of the
/// plateau at speed `v` (m/s) of a run: there the belt's oscillation
/// averages out and the motor's mean velocity is the cart's. `None` when the
/// plateau is shorter than the period.
pub fn plateau_middle(rec: &TrackRecord, v: f64, f_ring_hz: f64) -> Option<VelocityWindow> {
    let n = rec.samples.len();
    let ts = rec.time_s.get(1).copied()? - rec.time_s[0];
    if !(f_ring_hz.is_finite() && f_ring_hz > 0.0 && ts > 0.0) {
        return None;
    }
    let on_plateau = |k: usize| (rec.desired_velocity_m_s[k].abs() - v).abs() < 1e-6 * v.max(1.0);
    let first = (0..n).find(|&k| on_plateau(k))?;
    let last = (0..n).rposition(on_plateau)?;
    let len = ((1.0 / (f_ring_hz * ts)).round() as usize).max(2);
    let centre = (first + last) / 2;
    (centre >= first + len / 2 && centre + len / 2 <= last).then_some(VelocityWindow {
        start: centre - len / 2,
        len,
    })
}

/// The momentum balance between the plateau of one run and the plateau of
/// the next (the deceleration, the reversal, the acceleration): what the
/// torque did between the two velocity windows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MomentumPhase {
    /// Torque impulse `int w tau dt` of the commanded torque, shifted by the
    /// current-loop dead time, N m s.
    pub impulse_nm_s: f64,
    /// Weighted duration `int w dt`, s.
    pub duration_s: f64,
    /// Weighted time in motion `int w sign(omega) dt` (the Coulomb
    /// friction's share), s.
    pub signed_duration_s: f64,
    /// Weighted motor angle travelled `int w omega dt`, rad.
    pub angle_rad: f64,
    /// Velocity change between the windows, rad/s.
    pub velocity_change_rad_s: f64,
}

impl MomentumPhase {
    /// The phase with the holding torque `holding_nm` and the friction
    /// `d_v omega + tau_c sign(omega)` (3.35) taken out of the impulse:
    /// what is left is `m_e dw` (plus the holding torque's error times the
    /// duration, [`rigid_inertia_from_phases`]).
    pub fn friction_compensated(
        &self,
        holding_nm: f64,
        viscous_nm_s_per_rad: f64,
        coulomb_nm: f64,
    ) -> MomentumPhase {
        MomentumPhase {
            impulse_nm_s: self.impulse_nm_s
                - holding_nm * self.duration_s
                - coulomb_nm * self.signed_duration_s
                - viscous_nm_s_per_rad * self.angle_rad,
            ..*self
        }
    }
}

/// The momentum balance over `samples` (a contiguous record, sample time
/// `ts_s`) between velocity windows `a` and `b` (mean slopes of the motor
/// angle). For a rigid body `m_e omega' = tau` the difference of the two
/// window means is exactly the impulse weighted by a trapezoid rising over
/// `a` and falling over `b`; the duration, the time in motion and the angle
/// get the same weight. The torque acting in a cycle is the one commanded
/// `preview` samples (the current-loop dead time) earlier. `None` unless
/// `a` ends before `b` starts inside the record.
pub fn momentum_phase(
    samples: &[Sample],
    ts_s: f64,
    a: VelocityWindow,
    b: VelocityWindow,
    preview: usize,
) -> Option<MomentumPhase> {
    if a.len < 1 || b.len < 1 || a.start + a.len > b.start || b.start + b.len >= samples.len() {
        return None;
    }
    let angle = |k: usize| samples[k].motor_angle_rad;
    let velocity =
        |w: VelocityWindow| (angle(w.start + w.len) - angle(w.start)) / (w.len as f64 * ts_s);
    let (mut impulse, mut duration, mut signed, mut travelled) = (0.0, 0.0, 0.0, 0.0);
    for k in a.start..b.start + b.len {
        let rising = ((k - a.start) as f64 / a.len as f64).min(1.0);
        let falling = (k.saturating_sub(b.start) as f64 / b.len as f64).min(1.0);
        let weight = rising - falling;
        let step = angle(k + 1) - angle(k);
        impulse += weight * samples[k.saturating_sub(preview)].torque_command_nm * ts_s;
        duration += weight * ts_s;
        signed += weight * step.signum() * if step == 0.0 { 0.0 } else { ts_s };
        travelled += weight * step;
    }
    Some(MomentumPhase {
        impulse_nm_s: impulse,
        duration_s: duration,
        signed_duration_s: signed,
        angle_rad: travelled,
        velocity_change_rad_s: velocity(b) - velocity(a),
    })
}

/// Least-squares rigid inertia from phases whose impulses `I` have the
/// fitted friction and the holding torque taken out
/// ([`MomentumPhase::friction_compensated`]): `I = m_e dw + b T` with the
/// phase's duration `T`, where `b` absorbs the holding torque's error.
/// Between plateaus of opposite direction the friction changes sign half
/// way, so an error of the friction fit nearly cancels. `None` with fewer
/// than three phases, a singular system, a non-positive or non-finite
/// result, or a relative standard error above [`MAX_INERTIA_RELATIVE_SIGMA`].
pub fn rigid_inertia_from_phases(phases: &[MomentumPhase]) -> Option<RigidInertia> {
    let n = phases.len();
    if n < 3 {
        return None;
    }
    let row = |p: &MomentumPhase| nalgebra::Vector2::new(p.velocity_change_rad_s, p.duration_s);
    let mut normal = nalgebra::Matrix2::<f64>::zeros();
    let mut rhs = nalgebra::Vector2::<f64>::zeros();
    for p in phases {
        let x = row(p);
        normal += x * x.transpose();
        rhs += x * p.impulse_nm_s;
    }
    let inverse = normal.try_inverse()?;
    let theta = inverse * rhs;
    let rss: f64 = phases
        .iter()
        .map(|p| (p.impulse_nm_s - row(p).dot(&theta)).powi(2))
        .sum();
    let j = theta[0];
    let sigma = (rss / (n - 2) as f64 * inverse[(0, 0)]).sqrt();
    (j.is_finite() && j > 0.0 && sigma.is_finite() && sigma <= MAX_INERTIA_RELATIVE_SIGMA * j)
        .then_some(RigidInertia {
            inertia_kg_m2: j,
            sigma_kg_m2: sigma,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TS: f64 = 1e-4;
    /// Rigid body of plant #270 of the issue-12 study (truth 3.66e-3 kg m^2).
    const J: f64 = 3.66e-3;

    /// A rigid body `J omega' = tau(t - T_d) - tau_hold - d_v omega - tau_c
    /// sign(omega)` under a velocity loop following plateaus at `speeds_rad_s`
    /// (alternating direction, jerk-free ramps of 40 ms), the torque acting
    /// `delay` samples after it is commanded. Returns the samples and the
    /// middle window of each plateau.
    fn back_and_forth(speeds_rad_s: &[f64], delay: usize) -> (Vec<Sample>, Vec<VelocityWindow>) {
        let (hold, d_v, tau_c) = (0.5, 1.0e-3, 0.3);
        let (ramp, plateau) = (400usize, 2000usize);
        // desired velocity profile
        let mut w_d = vec![0.0];
        let mut middles = Vec::new();
        let mut prev = 0.0;
        for (i, &s) in speeds_rad_s.iter().enumerate() {
            let target = if i % 2 == 0 { s } else { -s };
            for k in 1..=ramp {
                w_d.push(prev + (target - prev) * k as f64 / ramp as f64);
            }
            middles.push(VelocityWindow {
                start: w_d.len() + plateau / 2 - 500,
                len: 1000,
            });
            w_d.extend(std::iter::repeat_n(target, plateau));
            prev = target;
        }
        let (mut phi, mut omega) = (0.0, 0.0);
        let mut commanded: Vec<f64> = Vec::with_capacity(w_d.len());
        let mut samples = Vec::with_capacity(w_d.len());
        for k in 0..w_d.len() {
            let alpha_d = if k + 1 < w_d.len() {
                (w_d[k + 1] - w_d[k]) / TS
            } else {
                0.0
            };
            // feedforward with a 20 % wrong inertia, the feedback does the rest
            let tau = hold + 1.2 * J * alpha_d + 0.5 * (w_d[k] - omega);
            commanded.push(tau);
            let acting = if k >= delay {
                commanded[k - delay]
            } else {
                hold
            };
            let friction = d_v * omega + tau_c * omega.signum() * (omega != 0.0) as u8 as f64;
            omega += TS / J * (acting - hold - friction);
            phi += TS * omega;
            samples.push(Sample {
                torque_command_nm: tau,
                torque_actual_nm: acting,
                motor_angle_rad: phi,
                position_m: 0.0124 * phi,
                cart_position_m: None,
            });
        }
        (samples, middles)
    }

    /// Second method for the feedforward's inertia: the momentum
    /// balance between plateaus returns the rigid body's inertia although
    /// the friction fit it subtracts is 30 % off and the holding torque
    /// 0.05 N m (10 %) off. The residual error: the Coulomb error times the
    /// unequal time the two directions take between plateaus of different
    /// speeds, a few 0.1 % here.
    #[test]
    fn momentum_balance_gives_the_rigid_inertia_despite_a_wrong_friction_fit() {
        let speeds = [8.0, 8.0, 20.0, 20.0, 32.0, 32.0];
        let delay = 12;
        let (samples, middles) = back_and_forth(&speeds, delay);
        let estimate = |hold: f64, d_v: f64, tau_c: f64| {
            let phases: Vec<MomentumPhase> = middles
                .windows(2)
                .map(|w| {
                    momentum_phase(&samples, TS, w[0], w[1], delay)
                        .unwrap()
                        .friction_compensated(hold, d_v, tau_c)
                })
                .collect();
            rigid_inertia_from_phases(&phases).unwrap().inertia_kg_m2 / J - 1.0
        };
        // The method itself (exact friction): the trapezoid weighting is
        // exact up to the half-sample offset of the angle difference against
        // the zero-order-held torque, O(T_s / window) = 1e-4.
        const METHOD_TOLERANCE: f64 = 1e-3;
        let exact = estimate(0.5, 1.0e-3, 0.3);
        assert!(exact.abs() < METHOD_TOLERANCE, "{exact:e}");
        // A 30 % wrong friction fit and a 10 % wrong holding torque: the
        // holding error is fitted out; the Coulomb error (0.09 N m) acts over
        // the unequal times the two directions take between plateaus of
        // different speed (a few ms of the ramps), about 0.3 % of the
        // velocity changes' momentum here.
        const FRICTION_ERROR_TOLERANCE: f64 = 0.01;
        let off = estimate(0.55, 1.3e-3, 0.21);
        assert!(off.abs() < FRICTION_ERROR_TOLERANCE, "{off:e}");
    }

    #[test]
    fn too_few_or_inconsistent_phases_give_none() {
        let (samples, middles) = back_and_forth(&[8.0, 8.0, 20.0], 0);
        let phases: Vec<MomentumPhase> = middles
            .windows(2)
            .map(|w| momentum_phase(&samples, TS, w[0], w[1], 0).unwrap())
            .collect();
        assert_eq!(phases.len(), 2);
        assert!(rigid_inertia_from_phases(&phases).is_none());
        // windows in the wrong order or beyond the record
        assert!(momentum_phase(&samples, TS, middles[1], middles[0], 0).is_none());
        let beyond = VelocityWindow {
            start: samples.len() - 10,
            len: 20,
        };
        assert!(momentum_phase(&samples, TS, middles[0], beyond, 0).is_none());
        // a non-finite impulse is no inertia
        let mut bad = phases.clone();
        bad.push(MomentumPhase {
            impulse_nm_s: f64::NAN,
            ..phases[0]
        });
        assert!(rigid_inertia_from_phases(&bad).is_none());
    }
}
