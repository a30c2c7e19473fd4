//! The seeded plant generator: egc70's data sheet with the issue-12 ranges
//! (payload 0-25 kg, belt stiffness x0.5-2, all viscous and all Coulomb
//! friction x0.3-3, tilt -90..90 deg, dead time 0.5-2 ms, encoder resolution
//! x0.5-4, measurement noise x0-5) and stroke and geometry variations (stroke
//! 0.4-1.0 m with the pulley distance following it, cart clamp span and end
//! compliance x0.7-1.3). Plant `index` of seed `seed` is drawn from its own
//! generator (`seed`, `index`), so any plant can be re-run alone.

use crate::model::params::{MeasurementNoise, PhysicalParams};
use crate::model::rigs::egc70_params;
use crate::sim::SimConfig;
use crate::Result;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::Serialize;

/// The ranges the generator draws from (uniform; the factors log-uniform).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Ranges {
    /// Payload on the cart, kg.
    pub payload_kg: (f64, f64),
    /// Factor on the belt's specific stiffness `c_b`.
    pub stiffness: (f64, f64),
    /// Factor on all viscous friction coefficients.
    pub viscous: (f64, f64),
    /// Factor on all Coulomb friction terms.
    pub coulomb: (f64, f64),
    /// Tilt, deg.
    pub tilt_deg: (f64, f64),
    /// Current-loop dead time, s.
    pub dead_time_s: (f64, f64),
    /// Factor on the belt travel per encoder count (coarser above 1).
    pub encoder: (f64, f64),
    /// Factor on the measurement noise (uniform, may be 0).
    pub noise: (f64, f64),
    /// Usable stroke, m.
    pub stroke_m: (f64, f64),
    /// Factor on the cart clamp span and the end compliance length.
    pub geometry: (f64, f64),
}

impl Default for Ranges {
    fn default() -> Self {
        Ranges {
            payload_kg: (0.0, 25.0),
            stiffness: (0.5, 2.0),
            viscous: (0.3, 3.0),
            coulomb: (0.3, 3.0),
            tilt_deg: (-90.0, 90.0),
            dead_time_s: (0.5e-3, 2e-3),
            encoder: (0.5, 4.0),
            noise: (0.0, 5.0),
            stroke_m: (0.4, 1.0),
            geometry: (0.7, 1.3),
        }
    }
}

/// Measurement noise of the baseline axis: actual-torque noise, N m, and
/// motor-encoder interpolation noise, counts (one sigma).
pub const BASE_TORQUE_NOISE_NM: f64 = 2e-3;
/// See [`BASE_TORQUE_NOISE_NM`].
pub const BASE_ENCODER_NOISE_COUNTS: f64 = 0.1;

/// The baseline axis' measurement noise, which the study scales by its noise
/// factor.
pub fn base_noise() -> MeasurementNoise {
    MeasurementNoise {
        torque_nm: BASE_TORQUE_NOISE_NM,
        encoder_counts: BASE_ENCODER_NOISE_COUNTS,
    }
}

/// One generated plant and the variations it was drawn with.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GeneratedPlant {
    /// Seed of the study.
    pub seed: u64,
    /// Index in the study.
    pub index: u64,
    /// The physical parameters.
    pub params: PhysicalParams,
    /// Payload, kg.
    pub payload_kg: f64,
    /// Factor on `c_b`.
    pub stiffness_factor: f64,
    /// Factor on the viscous friction.
    pub viscous_factor: f64,
    /// Factor on the Coulomb friction.
    pub coulomb_factor: f64,
    /// Tilt, deg.
    pub tilt_deg: f64,
    /// Factor on the belt travel per count.
    pub encoder_factor: f64,
    /// Factor on the measurement noise.
    pub noise_factor: f64,
    /// Seed of the simulation's noise.
    pub noise_seed: u64,
}

impl GeneratedPlant {
    /// The simulator settings: its own noise seed (the noise is the plant's,
    /// [`GeneratedPlant::params`]`.noise`).
    pub fn sim_config(&self, initial_cart_position_m: f64) -> SimConfig {
        SimConfig {
            seed: self.noise_seed,
            initial_cart_position_m: Some(initial_cart_position_m),
            ..SimConfig::default()
        }
    }
}

fn uniform(rng: &mut Xoshiro256PlusPlus, (lo, hi): (f64, f64)) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

fn log_uniform(rng: &mut Xoshiro256PlusPlus, (lo, hi): (f64, f64)) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.random::<f64>()).exp()
}

/// Plant `index` of the study seeded `seed`.
pub fn generate(seed: u64, index: u64, r: &Ranges) -> Result<GeneratedPlant> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(
        seed ^ index.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
    );
    let payload = uniform(&mut rng, r.payload_kg);
    let mut p = egc70_params(payload);
    let stiffness = log_uniform(&mut rng, r.stiffness);
    let viscous = log_uniform(&mut rng, r.viscous);
    let coulomb = log_uniform(&mut rng, r.coulomb);
    let tilt = uniform(&mut rng, r.tilt_deg);
    let dead = uniform(&mut rng, r.dead_time_s);
    let encoder = log_uniform(&mut rng, r.encoder);
    let noise = uniform(&mut rng, r.noise);
    let stroke = uniform(&mut rng, r.stroke_m);
    let geometry = uniform(&mut rng, r.geometry);
    let noise_seed = rng.random::<u64>();
    p.c_b_n *= stiffness;
    p.d_b_n_s *= stiffness;
    p.d_m_n_s_per_m *= viscous;
    p.d_c_n_s_per_m *= viscous;
    p.d_end_pulley_n_s_per_m *= viscous;
    p.tau_c_motor_nm *= coulomb;
    p.f_c_cart_n *= coulomb;
    p.tau_c_end_pulley_nm *= coulomb;
    p.tilt_rad = tilt.to_radians();
    // whole samples of the drive's cycle, as the simulator applies it
    p.dead_time_s = (dead / p.ts_s).round() * p.ts_s;
    p.motor_rad_per_count *= encoder;
    // egc70: 0.84 m between the pulleys for a 0.6 m stroke
    p.pulley_distance_m += stroke - p.stroke_m;
    p.stroke_m = stroke;
    p.cart_belt_span_m *= geometry;
    p.end_compliance_length_m *= geometry;
    p.noise = base_noise().scaled(noise);
    p.validate()?;
    Ok(GeneratedPlant {
        seed,
        index,
        params: p,
        payload_kg: payload,
        stiffness_factor: stiffness,
        viscous_factor: viscous,
        coulomb_factor: coulomb,
        tilt_deg: tilt,
        encoder_factor: encoder,
        noise_factor: noise,
        noise_seed,
    })
}
