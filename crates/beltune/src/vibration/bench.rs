//! The vibration benchmark: moves of equal duration ending at 7 positions
//! across the commissioned range, at 3 payloads across the declared payload
//! range, simulated on the commissioning's axis with its delivered
//! controller, for the contestants
//!
//! - `fixed`: the delivered controller on the plain jerk-limited
//!   trajectory (slowed to the common duration);
//! - `klipper`: the same controller and trajectory shaped by the shaper
//!   Klipper's rules choose ([`super::klipper::find_best_shaper`]) from the
//!   spectra a Klipper user would record: the cart's acceleration per
//!   motor acceleration, `|(d s + c) / (m_c s^2 + d s + c)|^2`, of the
//!   identified model at the range's ends and middle, with the payload
//!   range's ends and middle on the cart (nine data sets; Klipper's bins of
//!   an accelerometer at 3.2 kHz with 2048-point windows, 1.5625 Hz; shaper
//!   frequencies from 5 Hz, `--shaper_freq=5,150,0.2`, since its default
//!   lowest frequencies of 21-48 Hz are tuned for printers);
//! - `shaped`: the same controller, the trajectory shaped per move from
//!   the identified mode where the cart stops (the stiffness profile `c(xi)`
//!   and the payload range's ends, [`super::shaping::choose_shaper`]).
//!
//! The common move duration is the fastest move within the limits plus
//! Klipper's shaper. Residual vibration is the cart's peak-to-peak in a
//! window of `5 / f_z,min` after the move ends; settling is to +-10 um of the
//! target.

use super::klipper::{self, FittedShaper, KlipperOptions, Spectrum};
use super::shaper::Shaper;
use super::shaping::{self, Mode, ShapedTrajectory};
use crate::commission::stiffness::TargetStiffness;
use crate::model::{Plant, TwoMassParams};
use crate::record::commissioning::CommissioningRecord;
use crate::record::controller::ControllerFile;
use crate::{Error, Result};
use beltune_rt::control::{
    BeltStretch, CartSample, CascadeConfig, CascadeController, Setpoint, SetpointConversion,
};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use serde::{Deserialize, Serialize};

/// Settling band of the benchmark, m.
pub const SETTLING_BAND_M: f64 = 10e-6;
/// Predicted residual of the cart mode the shaping treats as none, m: a
/// tenth of the settling band.
pub const NEGLIGIBLE_RESIDUAL_M: f64 = 0.1 * SETTLING_BAND_M;
/// Residual window in periods of the lowest cart mode.
pub const WINDOW_PERIODS: f64 = 5.0;
/// Time recorded after the residual window for settling, s.
pub const SETTLE_RECORD_S: f64 = 0.5;
/// Move end positions across the range.
pub const POSITIONS: usize = 7;
/// Payloads across the range.
pub const PAYLOADS: usize = 3;

/// Everything the benchmark needs.
#[derive(Clone, Debug)]
pub struct BenchSetup {
    /// The simulated axis as commissioned.
    pub plant: Plant,
    /// Its payload, kg.
    pub commissioned_payload_kg: f64,
    /// The declared payload range `(min, max)`, kg.
    pub payload_range_kg: (f64, f64),
    /// The delivered controller (feedback and feedforward).
    pub controller: CascadeConfig<f64>,
    /// The delivered setpoint conversion's belt model.
    pub belt: BeltStretch<f64>,
    /// Transmission, m/rad.
    pub i_t_m_per_rad: f64,
    /// Feedforward preview, samples.
    pub preview_samples: usize,
    /// Identified two-mass model (at the identification position).
    pub identified: TwoMassParams,
    /// Belt stiffness along the stroke.
    pub stiffness: TargetStiffness,
    /// Where moves end: `(first, last)`, m.
    pub range_m: (f64, f64),
    /// Trajectory limits of the commissioned payload (the validation move's).
    pub limits: Limits,
    /// Noise seed of the simulations.
    pub seed: u64,
}

impl BenchSetup {
    /// The setup of a commissioning's result: `record` (its simulated axis,
    /// identified model, stiffness profile and validation move) and
    /// `controller` (`controller.toml`), payloads across `payload_range_kg`
    /// (`None`: half to one and a half times the commissioned payload). Errors for a
    /// commissioning without a simulated physical axis (recorded data, a
    /// linear set: no payload to change) or without a validation move.
    pub fn from_result(
        record: &CommissioningRecord,
        controller: &ControllerFile,
        payload_range_kg: Option<(f64, f64)>,
    ) -> Result<BenchSetup> {
        let plant = record
            .axis
            .as_ref()
            .and_then(|a| a.simulated_plant())
            .cloned()
            .ok_or_else(|| Error::Infeasible {
                reason: "the vibration benchmark simulates the commissioned axis: this commissioning has no simulated axis (recorded data or a drive)".into(),
            })?;
        let payload = match &plant {
            Plant::Physical(p) => p.payload_kg,
            Plant::Linear(_) => {
                return Err(Error::Infeasible {
                    reason: "the vibration benchmark changes the payload: a linear simulation set has a fixed moving mass".into(),
                })
            }
        };
        let (lo, hi) = payload_range_kg.unwrap_or((0.5 * payload, 1.5 * payload));
        crate::error::require_non_negative("payload range min [kg]", lo)?;
        crate::error::require_non_negative("payload range max [kg]", hi)?;
        if hi < lo {
            return Err(Error::invalid(
                "payload range max [kg]",
                hi,
                "must not be below the minimum",
            ));
        }
        let mv = record
            .validation_move
            .as_ref()
            .ok_or_else(|| Error::Infeasible {
                reason: "the commissioning has no validation move to take the move limits from"
                    .into(),
            })?;
        let identified = record.identified.params();
        let stiffness = record.target_stiffness.unwrap_or_else(|| {
            TargetStiffness::constant(mv.target_m, identified.c, identified.f_z_hz(), false)
        });
        let (first, last) = (mv.start_m.min(mv.target_m), mv.start_m.max(mv.target_m));
        let limits = Limits {
            v_max: mv.v_max_m_s,
            v_min: -mv.v_max_m_s,
            a_max: mv.a_max_m_s2,
            a_min: -mv.a_max_m_s2,
            j_max: mv.j_max_m_s3,
            j_min: -mv.j_max_m_s3,
            position_min: first - 0.01,
            position_max: last + 0.01,
        };
        let preview_samples = (record.identified.dead_time_s / controller.ts_s).round() as usize;
        Ok(BenchSetup {
            plant,
            commissioned_payload_kg: payload,
            payload_range_kg: (lo, hi),
            controller: controller.cascade_config()?,
            belt: controller.setpoint.belt_stretch(),
            i_t_m_per_rad: controller.setpoint.i_t_m_per_rad,
            preview_samples,
            identified,
            stiffness,
            range_m: (first, last),
            limits,
            seed: 1,
        })
    }

    /// The payloads the benchmark runs, kg.
    pub fn payloads_kg(&self) -> [f64; PAYLOADS] {
        let (lo, hi) = self.payload_range_kg;
        [lo, 0.5 * (lo + hi), hi]
    }

    /// The move end positions, m.
    pub fn ends_m(&self) -> [f64; POSITIONS] {
        let (a, b) = self.range_m;
        core::array::from_fn(|k| a + (b - a) * k as f64 / (POSITIONS - 1) as f64)
    }

    /// Length of every move, m: a third of the range.
    pub fn move_length_m(&self) -> f64 {
        (self.range_m.1 - self.range_m.0) / 3.0
    }

    /// Start of the move ending at `end_m`: a move length before it, or
    /// after it where the range does not reach back.
    pub fn start_m(&self, end_m: f64) -> f64 {
        let l = self.move_length_m();
        if end_m - l >= self.range_m.0 - 1e-9 {
            end_m - l
        } else {
            end_m + l
        }
    }

    /// The identified model's cart mode at cart position `xi_m` with
    /// `payload_kg` on the cart.
    pub fn mode(&self, xi_m: f64, payload_kg: f64) -> Result<Mode> {
        let m_c = self.identified.m_c + (payload_kg - self.commissioned_payload_kg);
        Mode::cart_on_belt(self.stiffness.stiffness_at(xi_m), self.identified.d, m_c)
    }

    /// The trajectory limits of the benchmark: the validation move's, the
    /// acceleration and jerk scaled down by the rigid mass ratio when the
    /// heaviest payload is heavier than the commissioned one (the same
    /// torque then accelerates it).
    pub fn bench_limits(&self) -> Limits {
        let p = &self.identified;
        let rigid = |m_c: f64| p.theta_e / (p.i_t * p.i_t) + m_c;
        let heavy = self.payload_range_kg.1 - self.commissioned_payload_kg;
        let ratio = (rigid(p.m_c) / rigid(p.m_c + heavy.max(0.0))).min(1.0);
        Limits {
            a_max: self.limits.a_max * ratio,
            a_min: self.limits.a_min * ratio,
            j_max: self.limits.j_max * ratio,
            j_min: self.limits.j_min * ratio,
            ..self.limits
        }
    }

    /// The spectra a Klipper user records: at the range's ends and middle,
    /// with the payload range's ends and middle.
    pub fn klipper_spectra(&self) -> Result<Vec<Spectrum>> {
        let (a, b) = self.range_m;
        let mut out = Vec::new();
        for xi in [a, 0.5 * (a + b), b] {
            for p in self.payloads_kg() {
                let m = self.mode(xi, p)?;
                out.push(cart_spectrum(&m));
            }
        }
        Ok(out)
    }
}

/// The cart's acceleration per motor acceleration squared for `mode`, on
/// Klipper's bins (1.5625 Hz up to 200 Hz).
pub fn cart_spectrum(mode: &Mode) -> Spectrum {
    let w0 = 2.0 * std::f64::consts::PI * mode.freq_hz;
    let freq_hz: Vec<f64> = (0..=128).map(|k| k as f64 * 1.5625).collect();
    let psd = freq_hz
        .iter()
        .map(|&f| {
            let w = 2.0 * std::f64::consts::PI * f;
            // (d s + c) / (m s^2 + d s + c) with s = j w, per unit mass
            let (c, d) = (w0 * w0, 2.0 * mode.damping_ratio * w0);
            let num = c * c + (d * w).powi(2);
            let den = (c - w * w).powi(2) + (d * w).powi(2);
            num / den
        })
        .collect();
    Spectrum { freq_hz, psd }
}

/// One simulated move.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveOutcome {
    /// Where the move ends, m.
    pub end_m: f64,
    /// Payload on the cart, kg.
    pub payload_kg: f64,
    /// The model's cart mode there, Hz.
    pub f_z_model_hz: f64,
    /// Peak-to-peak cart position in the residual window, um.
    pub residual_um: f64,
    /// Time after the move's end until the cart stays within +-10 um of
    /// the target, s (`None`: not within the record).
    pub settling_s: Option<f64>,
    /// The shaper used (Klipper's name, or `none`).
    pub shaper: String,
}

/// One contestant's figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Contestant {
    /// `fixed`, `klipper` or `shaped`.
    pub name: String,
    /// What it is.
    pub description: String,
    /// Largest residual over the moves, um.
    pub worst_residual_um: f64,
    /// Median residual over the moves, um.
    pub median_residual_um: f64,
    /// Longest settling time, s (`None`: a move did not settle within the record).
    pub worst_settling_s: Option<f64>,
    /// Moves that settled within the record.
    pub settled_moves: usize,
    /// Duration of every move, s.
    pub move_time_s: f64,
    /// Each move.
    pub moves: Vec<MoveOutcome>,
}

/// Klipper's choice as the benchmark used it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KlipperChoice {
    /// Shaper name.
    pub shaper: String,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Remaining vibration on the recorded spectra, fraction.
    pub vibration: f64,
    /// Smoothing, m.
    pub smoothing_m: f64,
    /// Suggested maximum acceleration, m/s^2.
    pub max_accel_m_s2: f64,
    /// Duration, s.
    pub duration_s: f64,
}

impl KlipperChoice {
    fn of(f: &FittedShaper) -> Self {
        KlipperChoice {
            shaper: f.kind.name().into(),
            freq_hz: f.freq_hz,
            vibration: f.vibration,
            smoothing_m: f.smoothing_m,
            max_accel_m_s2: f.max_accel_m_s2,
            duration_s: f.shaper.duration_s(),
        }
    }
}

/// The benchmark's result (`vibration` in JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VibrationBenchmark {
    /// The contestants.
    pub contestants: Vec<Contestant>,
    /// Move end positions, m.
    pub ends_m: Vec<f64>,
    /// Payloads, kg.
    pub payloads_kg: Vec<f64>,
    /// Length of every move, m.
    pub move_length_m: f64,
    /// Lowest model cart mode over the moves, Hz.
    pub f_z_min_hz: f64,
    /// Residual window after the move, s (`5 / f_z,min`).
    pub window_s: f64,
    /// Klipper's choice.
    pub klipper: KlipperChoice,
    /// Trajectory limits (v m/s, a m/s^2, j m/s^3) of the base trajectory.
    pub limits_v_a_j: [f64; 3],
}

impl VibrationBenchmark {
    /// The contestant named `name`.
    pub fn contestant(&self, name: &str) -> Option<&Contestant> {
        self.contestants.iter().find(|c| c.name == name)
    }
}

/// Run the benchmark.
pub fn run(setup: &BenchSetup) -> Result<VibrationBenchmark> {
    let limits = setup.bench_limits();
    let ends = setup.ends_m();
    let payloads = setup.payloads_kg();
    let mut f_z_min = f64::MAX;
    for &e in &ends {
        for &p in &payloads {
            f_z_min = f_z_min.min(setup.mode(e, p)?.freq_hz);
        }
    }
    let window_s = WINDOW_PERIODS / f_z_min;
    let opts = KlipperOptions {
        shaper_freq_start_hz: Some(5.0),
        ..KlipperOptions::default()
    };
    let (kl, _) = klipper::find_best_shaper(&setup.klipper_spectra()?, &opts)?;
    let l = setup.move_length_m();
    let d_min = Trajectory::plan(
        &State::at_rest(setup.range_m.0),
        &State::at_rest(setup.range_m.0 + l),
        &limits,
    )?
    .duration_s();
    let move_time_s = d_min + kl.shaper.duration_s();
    let mut fixed = Vec::new();
    let mut klip = Vec::new();
    let mut shaped = Vec::new();
    for &end in &ends {
        let start = setup.start_m(end);
        let modes: Vec<Mode> = [payloads[0], payloads[2]]
            .iter()
            .map(|&p| setup.mode(end, p))
            .collect::<Result<_>>()?;
        let choice = shaping::choose_shaper(
            start,
            end,
            &limits,
            move_time_s,
            &modes,
            NEGLIGIBLE_RESIDUAL_M,
        )?;
        for &p in &payloads {
            let plant = setup.plant.with_payload(p)?;
            let f_z = setup.mode(end, p)?.freq_hz;
            let run_one = |shaper: &Shaper, name: &str| -> Result<MoveOutcome> {
                let base = shaping::scaled_trajectory(
                    start,
                    end,
                    &limits,
                    move_time_s - shaper.duration_s(),
                )?;
                let path = ShapedTrajectory {
                    base,
                    shaper: shaper.clone(),
                };
                let (residual_um, settling_s) = simulate(setup, &plant, &path, window_s)?;
                Ok(MoveOutcome {
                    end_m: end,
                    payload_kg: p,
                    f_z_model_hz: f_z,
                    residual_um,
                    settling_s,
                    shaper: name.into(),
                })
            };
            fixed.push(run_one(&Shaper::none(), "none")?);
            klip.push(run_one(&kl.shaper, kl.kind.name())?);
            let name = if choice.freq_hz > 0.0 {
                format!("{}@{:.1}Hz", choice.kind.name(), choice.freq_hz)
            } else {
                "none".into()
            };
            shaped.push(run_one(&choice.shaper, &name)?);
        }
    }
    let contestant = |name: &str, description: String, moves: Vec<MoveOutcome>| {
        let mut r: Vec<f64> = moves.iter().map(|m| m.residual_um).collect();
        r.sort_by(f64::total_cmp);
        let worst_settling_s = moves
            .iter()
            .map(|m| m.settling_s)
            .try_fold(0.0_f64, |acc, s| s.map(|s| acc.max(s)));
        Contestant {
            name: name.into(),
            description,
            worst_residual_um: r.last().copied().unwrap_or(0.0),
            median_residual_um: r[r.len() / 2],
            worst_settling_s,
            settled_moves: moves.iter().filter(|m| m.settling_s.is_some()).count(),
            move_time_s,
            moves,
        }
    };
    Ok(VibrationBenchmark {
        contestants: vec![
            contestant(
                "fixed",
                "the delivered controller, the plain jerk-limited trajectory".into(),
                fixed,
            ),
            contestant(
                "klipper",
                format!(
                    "the delivered controller, the trajectory shaped by Klipper's choice ({} at {:.1} Hz)",
                    kl.kind.name(),
                    kl.freq_hz
                ),
                klip,
            ),
            contestant(
                "shaped",
                "the delivered controller, the trajectory shaped per move from the identified mode where the cart stops over the payload range".into(),
                shaped,
            ),
        ],
        ends_m: ends.to_vec(),
        payloads_kg: payloads.to_vec(),
        move_length_m: l,
        f_z_min_hz: f_z_min,
        window_s,
        klipper: KlipperChoice::of(&kl),
        limits_v_a_j: [limits.v_max, limits.a_max, limits.j_max],
    })
}

/// Simulate `path` on `plant` with the delivered controller from rest at
/// the path's start; the cart's peak-to-peak in `window_s` after the path
/// ends (um) and the settling time to +-10 um of its end (s).
fn simulate(
    setup: &BenchSetup,
    plant: &Plant,
    path: &ShapedTrajectory,
    window_s: f64,
) -> Result<(f64, Option<f64>)> {
    let start = path.sample(0.0).position;
    let target = path.sample(path.duration_s() + 1.0).position;
    let config = crate::sim::SimConfig {
        seed: setup.seed,
        initial_cart_position_m: Some(start),
        ..crate::sim::SimConfig::default()
    };
    let mut axis = crate::sim::SimAxis::new(plant, config)?;
    let ts = plant.info().ts_s;
    let rad_per_count = plant.info().motor_rad_per_count;
    let mut ctrl = CascadeController::new(setup.controller)?;
    ctrl.reset_to(0.0);
    let conv = SetpointConversion::new(setup.i_t_m_per_rad, setup.belt)?;
    let origin = start;
    let motor = |t: f64| {
        let s = path.sample(t);
        conv.motor_sample(&CartSample {
            position_m: s.position - origin,
            velocity_m_s: s.velocity,
            acceleration_m_s2: s.acceleration,
            jerk_m_s3: s.jerk,
        })
    };
    let t_end = path.duration_s();
    let n = ((t_end + window_s + SETTLE_RECORD_S) / ts).ceil() as usize;
    let preview = setup.preview_samples as f64 * ts;
    let mut angle = 0.0;
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    let mut last_out: Option<f64> = None;
    let mut last_t = 0.0;
    for k in 0..n {
        let t = k as f64 * ts;
        let sp = Setpoint::with_preview(motor(t), motor(t + preview));
        let out = ctrl.step(&sp, angle);
        let m = axis.step(out.torque_nm);
        angle = m.motor_counts as f64 * rad_per_count;
        let x = axis.cart_position_m();
        if !x.is_finite() {
            return Err(Error::NonFinite {
                what: "simulated cart position".into(),
                index: k,
            });
        }
        let t1 = (k + 1) as f64 * ts;
        last_t = t1;
        if t1 >= t_end && t1 <= t_end + window_s {
            lo = lo.min(x);
            hi = hi.max(x);
        }
        if (x - target).abs() > SETTLING_BAND_M {
            last_out = Some(t1);
        }
    }
    let settling = match last_out {
        None => Some(0.0),
        Some(t) if t >= last_t - 0.5 * ts => None,
        Some(t) => Some((t - t_end).max(0.0)),
    };
    Ok(((hi - lo).max(0.0) * 1e6, settling))
}
