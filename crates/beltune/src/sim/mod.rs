//! The simulated test rig: [`SimAxis`] runs any [`Plant`] behind the
//! [`Axis`] trait, sample by sample, as a drive sees it.
//!
//! Per sample of `T_s` (10 kHz for the built-ins):
//! 1. the torque command is saturated at the torque limit and enters the
//!    current loop, modelled as a dead time of `n = round(T_d / T_s)` samples
//!    (a delay line; the thesis identifies the current loop as a dead time, 3.4)
//!    followed, when the plant's `[unmodeled]` table asks for them
//!    (`unmodeled.rs`), by a second-order current loop, torque ripple,
//!    cogging and tooth mesh on the rotor, a frame mode and encoder line
//!    errors in the measured angle;
//! 2. the delayed torque is held constant over the sample (zero-order hold) and
//!    drives the plant: a physical plant with the nonlinear three-mass model
//!    (2.20) (or, by [`SimConfig::model`], the nonlinear two-mass model (2.30)),
//!    integrated with RK4 in `n_sub` sub-steps chosen from the stiffest belt
//!    mode, and Coulomb friction with a velocity-level stick-slip model
//!    (`mech.rs`); a linear set exactly (ZOH discretization of (2.33));
//! 3. the drive measures at the end of the sample: the motor encoder counts
//!    `floor((phi_m - phi_m(0)) / q)`, the actual torque (the delayed torque plus
//!    seeded Gaussian noise) and, for evaluation only, the cart position from a
//!    linear encoder.
//!
//! The input-output relation of one sample is therefore
//! `counts_k ~ phi_m((k+1) T_s)` driven by `tau_{k-n}` held over `[k T_s, (k+1) T_s)`:
//! in the frequency domain `G(j w) e^{-j w n T_s} e^{+j w T_s / 2}` (the ZOH's
//! half-sample lag and the measurement at the end of the sample), which the
//! tests compare against.

pub mod closed_loop;
mod linear;
mod mech;
pub mod truth;
mod unmodeled;

pub(crate) use mech::coulomb_step;
pub use truth::Truth;

use crate::axis::{Axis, AxisError, AxisInfo, Measurement};
use crate::error::{require_finite, require_positive};
use crate::model::params::{FrictionTotals, MeasurementNoise, PhysicalParams};
use crate::model::three_mass::ThreeMassState;
use crate::model::{Plant, TwoMassParams};
use crate::{Error, Result};
use mech::Mech;
use nalgebra::{SMatrix, SVector};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use unmodeled::UnmodeledSim;

/// Which model simulates a physical plant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SimModel {
    /// The nonlinear three-mass model (2.20) (default).
    #[default]
    ThreeMass,
    /// The nonlinear two-mass model (2.30).
    TwoMass,
}

/// Simulation settings (public fields, `Default`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct SimConfig {
    /// Seed of the noise generator (Xoshiro256++): equal seeds, equal runs;
    /// another seed, another realization of the plant's measurement noise.
    pub seed: u64,
    /// Measurement noise instead of the plant's own
    /// ([`crate::model::MeasurementNoise`], the plant file's `[noise]`);
    /// `None`: the plant's.
    pub noise: Option<MeasurementNoise>,
    /// Initial cart position, m (`None`: the middle of the stroke; 0 for a linear set).
    pub initial_cart_position_m: Option<f64>,
    /// Tilt override, rad (`None`: the plant's own tilt).
    pub tilt_rad: Option<f64>,
    /// Model used for a physical plant.
    pub model: SimModel,
    /// Resolution of the (evaluation-only) linear encoder on the cart, m per count.
    pub cart_encoder_resolution_m: f64,
    /// Largest internal sub-step, s (`None`: chosen from the stiffest mode so
    /// that `w_max h <= 0.25`).
    pub max_substep_s: Option<f64>,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            seed: 0x5EED,
            noise: None,
            initial_cart_position_m: None,
            tilt_rad: None,
            model: SimModel::ThreeMass,
            cart_encoder_resolution_m: 1e-6,
            max_substep_s: None,
        }
    }
}

/// RK4 accuracy target: the largest `w_max h` of a sub-step. RK4's relative
/// frequency error is about `(w h)^4 / 120`, below 4e-5 at 0.25.
const MAX_OMEGA_H: f64 = 0.25;

/// Most RK4 sub-steps per sample. egc70 needs a few dozen; a plant that
/// needs more (a stiffness or damping far beyond any belt axis) would run
/// for hours, so it is refused instead.
pub const MAX_SUBSTEPS: usize = 4096;

#[derive(Clone, Debug)]
enum Dynamics {
    ThreeMass(Box<Mech<3, 3>>),
    TwoMass(Box<Mech<2, 1>>),
    Linear {
        phi: SMatrix<f64, 4, 4>,
        gamma: SVector<f64, 4>,
        x: SVector<f64, 4>,
    },
}

/// A simulated axis (see the module docs).
#[derive(Clone, Debug)]
pub struct SimAxis {
    plant: Plant,
    /// A physical plant as aged ([`PhysicalParams::aged`]): what the
    /// dynamics run on.
    aged: Option<Box<PhysicalParams>>,
    config: SimConfig,
    info: AxisInfo,
    dynamics: Dynamics,
    n_sub: usize,
    h_sub: f64,
    delay: Vec<f64>,
    delay_pos: usize,
    applied_torque_nm: f64,
    rng: Xoshiro256PlusPlus,
    noise: MeasurementNoise,
    steps: u64,
    phi_m_zero_rad: f64,
    rejected_commands: u64,
    /// The plant's `[unmodeled]` dynamics (`None`: all off, or a linear set).
    unmodeled: Option<Box<UnmodeledSim>>,
}

impl SimAxis {
    /// A simulated axis for `plant`, at rest with an unstretched belt at the
    /// configured initial cart position. Typed errors for an invalid plant or
    /// configuration (position outside the stroke, negative noise, ...).
    pub fn new(plant: &Plant, config: SimConfig) -> Result<Self> {
        plant.validate()?;
        if let Some(n) = &config.noise {
            n.validate()?;
        }
        require_positive(
            "cart_encoder_resolution_m",
            config.cart_encoder_resolution_m,
        )?;
        if let Some(h) = config.max_substep_s {
            require_positive("max_substep_s", h)?;
        }
        let mut plant = plant.clone();
        if let Some(tilt) = config.tilt_rad {
            match &mut plant {
                Plant::Physical(p) => p.tilt_rad = tilt,
                Plant::Linear(_) => {
                    return Err(Error::invalid(
                        "tilt_rad",
                        tilt,
                        "a linear simulation set has no gravity; use a physical plant",
                    ))
                }
            }
            plant.validate()?;
        }
        if let (Plant::Physical(p), SimModel::TwoMass) = (&plant, config.model) {
            if p.wear.belt_pretension_n.is_some() {
                return Err(Error::invalid(
                    "wear.belt_pretension_n",
                    p.wear.belt_pretension_n.unwrap_or(f64::NAN),
                    "a slack span needs the three-mass model (the two-mass model has one replacement spring)",
                ));
            }
        }
        let info = plant.info();
        let noise = config.noise.unwrap_or_else(|| plant.noise());
        let aged = match &plant {
            Plant::Physical(p) => Some(Box::new(p.aged())),
            Plant::Linear(_) => None,
        };
        let xi0 = match (&plant, config.initial_cart_position_m) {
            (Plant::Physical(p), None) => 0.5 * p.stroke_m,
            (Plant::Linear(_), None) => 0.0,
            (_, Some(x)) => x,
        };
        let n_delay = (plant.dead_time_s() / info.ts_s).round() as usize;
        let unmodeled = match &aged {
            Some(p) if !p.unmodeled.is_off() => Some(Box::new(UnmodeledSim::new(
                &p.unmodeled,
                p.theta_e(),
                p.i_t(),
                info.ts_s,
            ))),
            _ => None,
        };
        let mut axis = SimAxis {
            dynamics: Dynamics::Linear {
                phi: SMatrix::zeros(),
                gamma: SVector::zeros(),
                x: SVector::zeros(),
            },
            plant,
            aged,
            rng: Xoshiro256PlusPlus::seed_from_u64(config.seed),
            noise,
            config,
            info,
            n_sub: 1,
            h_sub: info.ts_s,
            delay: vec![0.0; n_delay],
            delay_pos: 0,
            applied_torque_nm: 0.0,
            steps: 0,
            phi_m_zero_rad: 0.0,
            rejected_commands: 0,
            unmodeled,
        };
        axis.set_cart_position(xi0)?;
        axis.phi_m_zero_rad = axis.motor_angle_rad();
        Ok(axis)
    }

    /// Put the cart at rest at `xi_m` with an unstretched belt (velocities
    /// zero). The encoder is not reset: the counts jump like a real encoder
    /// whose axis was moved by hand. Error if `xi_m` is outside the stroke.
    pub fn set_cart_position(&mut self, xi_m: f64) -> Result<()> {
        require_finite("cart position [m]", xi_m)?;
        match self.plant.clone() {
            Plant::Physical(p) => {
                let p = self.aged.as_deref().cloned().unwrap_or(p);
                if !(0.0..=p.stroke_m).contains(&xi_m) {
                    return Err(Error::invalid(
                        "cart position [m]",
                        xi_m,
                        format!("outside the stroke [0, {}] m", p.stroke_m),
                    ));
                }
                self.dynamics = match self.config.model {
                    SimModel::ThreeMass => Dynamics::ThreeMass(Box::new(three_mass_mech(&p, xi_m))),
                    SimModel::TwoMass => Dynamics::TwoMass(Box::new(two_mass_mech(&p, xi_m))),
                };
                // sub-steps from the stiffest configuration (both stroke ends)
                let mut w_max: f64 = 0.0;
                let mut d_max: f64 = 0.0;
                for x in [0.0, p.stroke_m] {
                    let (w, d) = match self.config.model {
                        SimModel::ThreeMass => three_mass_mech(&p, x).rate_bounds(),
                        SimModel::TwoMass => two_mass_mech(&p, x).rate_bounds(),
                    };
                    w_max = w_max.max(w);
                    d_max = d_max.max(d);
                }
                let mut h = MAX_OMEGA_H / w_max.max(d_max).max(1e-12);
                if let Some(hmax) = self.config.max_substep_s {
                    h = h.min(hmax);
                }
                let n = (p.ts_s / h).ceil();
                if !n.is_finite() || n > MAX_SUBSTEPS as f64 {
                    return Err(Error::invalid(
                        "plant",
                        n,
                        format!(
                            "too stiff or too damped to simulate: a sample of {} us needs {n:.0} \
                             integration sub-steps (limit {MAX_SUBSTEPS}); check the stiffness, \
                             damping and inertia values",
                            p.ts_s * 1e6
                        ),
                    ));
                }
                self.n_sub = (n as usize).max(1);
                self.h_sub = p.ts_s / self.n_sub as f64;
            }
            Plant::Linear(l) => {
                let (phi, gamma) = linear::zoh(&l.two_mass, l.ts_s);
                let x = SVector::<f64, 4>::new(xi_m / l.two_mass.i_t, 0.0, xi_m, 0.0);
                self.dynamics = Dynamics::Linear { phi, gamma, x };
                self.n_sub = 1;
                self.h_sub = l.ts_s;
            }
        }
        Ok(())
    }

    /// The simulated plant (with the tilt override applied).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// The measurement noise simulated (the configuration's or the plant's).
    pub fn noise(&self) -> MeasurementNoise {
        self.noise
    }

    /// Simulated time, s (samples times `T_s`).
    pub fn time_s(&self) -> f64 {
        self.steps as f64 * self.info.ts_s
    }

    /// Samples simulated so far.
    pub fn samples(&self) -> u64 {
        self.steps
    }

    /// Internal sub-steps per sample.
    pub fn substeps(&self) -> usize {
        self.n_sub
    }

    /// True motor angle `phi_m`, rad.
    pub fn motor_angle_rad(&self) -> f64 {
        match &self.dynamics {
            Dynamics::ThreeMass(m) => m.q[0],
            Dynamics::TwoMass(m) => m.q[0],
            Dynamics::Linear { x, .. } => x[0],
        }
    }

    /// True motor velocity `omega_m`, rad/s.
    pub fn motor_velocity_rad_s(&self) -> f64 {
        match &self.dynamics {
            Dynamics::ThreeMass(m) => m.v[0],
            Dynamics::TwoMass(m) => m.v[0],
            Dynamics::Linear { x, .. } => x[1],
        }
    }

    /// True cart position `xi`, m.
    pub fn cart_position_m(&self) -> f64 {
        match &self.dynamics {
            Dynamics::ThreeMass(m) => m.q[2],
            Dynamics::TwoMass(m) => m.q[1],
            Dynamics::Linear { x, .. } => x[2],
        }
    }

    /// True cart velocity `xi'`, m/s.
    pub fn cart_velocity_m_s(&self) -> f64 {
        match &self.dynamics {
            Dynamics::ThreeMass(m) => m.v[2],
            Dynamics::TwoMass(m) => m.v[1],
            Dynamics::Linear { x, .. } => x[3],
        }
    }

    /// Whether the cart is outside the usable stroke `[0, stroke]` (a real
    /// axis would hit its end stop; the simulation has none and keeps the belt
    /// stiffness of the nearest stroke end). Always `false` for a linear set.
    pub fn cart_outside_stroke(&self) -> bool {
        match self.plant.stroke_m() {
            Some(stroke) => !(0.0..=stroke).contains(&self.cart_position_m()),
            None => false,
        }
    }

    /// The full three-mass state (2.18), if the three-mass model runs.
    pub fn three_mass_state(&self) -> Option<ThreeMassState> {
        match &self.dynamics {
            Dynamics::ThreeMass(m) => Some(ThreeMassState {
                phi_m_rad: m.q[0],
                omega_m_rad_s: m.v[0],
                phi_2_rad: m.q[1],
                omega_2_rad_s: m.v[1],
                xi_m: m.q[2],
                xi_dot_m_s: m.v[2],
            }),
            _ => None,
        }
    }

    /// The torque acting on the motor during the last sample (after
    /// saturation and dead time, without measurement noise), N m.
    pub fn applied_torque_nm(&self) -> f64 {
        self.applied_torque_nm
    }

    /// The linear two-mass parameters at the current cart position (the truth
    /// an identification should find).
    pub fn linearized_truth(&self) -> TwoMassParams {
        let xi = self.cart_position_m();
        // validated at construction; positions outside the stroke are clamped
        self.plant
            .linearize(xi)
            .or_else(|_| self.plant.linearize(0.0))
            .expect("plant validated at construction")
    }

    /// The simulated dead time, `n T_s` (the plant's dead time rounded to whole samples), s.
    pub fn dead_time_s(&self) -> f64 {
        self.delay.len() as f64 * self.info.ts_s
    }

    /// The friction totals seen at the motor (3.36): the mean torque at
    /// constant motor velocity `omega` is `d_v~ omega + tau_c~ sign(omega)`
    /// in both directions (checked in the tests), provided the motor does not
    /// reverse; a velocity loop that limit-cycles through zero averages the
    /// motor-side Coulomb friction out.
    pub fn friction_truth(&self) -> FrictionTotals {
        self.plant.friction_totals()
    }

    /// Non-finite torque commands received (each applied as 0 N m).
    pub fn rejected_commands(&self) -> u64 {
        self.rejected_commands
    }

    fn advance(&mut self, tau: f64) {
        let params = self.aged.as_deref();
        match &mut self.dynamics {
            Dynamics::ThreeMass(m) => {
                let p = params.expect("three-mass dynamics belong to a physical plant");
                let fixed = FixedSegment::of(p);
                for _ in 0..self.n_sub {
                    set_three_mass_segments(m, p, &fixed);
                    m.step(tau, self.h_sub);
                }
            }
            Dynamics::TwoMass(m) => {
                let p = params.expect("two-mass dynamics belong to a physical plant");
                for _ in 0..self.n_sub {
                    set_two_mass_segments(m, p);
                    m.step(tau, self.h_sub);
                }
            }
            Dynamics::Linear { phi, gamma, x } => {
                *x = *phi * *x + *gamma * tau;
            }
        }
    }
}

impl SimAxis {
    /// One sample: apply `torque_command_nm` (saturated, through the
    /// current-loop dead time) for one sample period and measure. A simulated
    /// exchange cannot fail; [`Axis::exchange`] wraps this.
    pub fn step(&mut self, torque_command_nm: f64) -> Measurement {
        let cmd = if torque_command_nm.is_finite() {
            torque_command_nm
        } else {
            self.rejected_commands += 1;
            0.0
        };
        let lim = self.info.torque_max_nm;
        let sat = cmd.clamp(-lim, lim);
        let tau = if self.delay.is_empty() {
            sat
        } else {
            let out = self.delay[self.delay_pos];
            self.delay[self.delay_pos] = sat;
            self.delay_pos += 1;
            if self.delay_pos == self.delay.len() {
                self.delay_pos = 0;
            }
            out
        };
        let phi_start = self.motor_angle_rad();
        let (tau, rotor) = match self.unmodeled.as_deref_mut() {
            Some(u) => {
                let loop_out = u.current_loop(tau);
                (loop_out, u.rotor_torque(loop_out, phi_start))
            }
            None => (tau, tau),
        };
        self.applied_torque_nm = tau;
        self.advance(rotor);
        self.steps += 1;
        let phi_end = self.motor_angle_rad();
        let angle = match self.unmodeled.as_deref_mut() {
            Some(u) => u.measured_angle(rotor, phi_end),
            None => phi_end,
        };
        let noise = if self.noise.torque_nm > 0.0 {
            let z: f64 = StandardNormal.sample(&mut self.rng);
            self.noise.torque_nm * z
        } else {
            0.0
        };
        let jitter = if self.noise.encoder_counts > 0.0 {
            let z: f64 = StandardNormal.sample(&mut self.rng);
            self.noise.encoder_counts * z
        } else {
            0.0
        };
        let counts =
            floor_i64((angle - self.phi_m_zero_rad) / self.info.motor_rad_per_count + jitter);
        let cart = floor_i64(self.cart_position_m() / self.config.cart_encoder_resolution_m) as f64
            * self.config.cart_encoder_resolution_m;
        Measurement {
            motor_counts: counts,
            torque_actual_nm: tau + noise,
            cart_position_m: Some(cart),
        }
    }
}

impl Axis for SimAxis {
    fn info(&self) -> AxisInfo {
        self.info
    }

    fn exchange(&mut self, torque_command_nm: f64) -> Result<Measurement, AxisError> {
        Ok(self.step(torque_command_nm))
    }

    /// The simulated drive has no stop function of its own: it removes the
    /// torque that is still on its way through the current-loop dead time.
    fn quick_stop(&mut self) -> Result<(), AxisError> {
        self.delay.iter_mut().for_each(|t| *t = 0.0);
        if let Some(u) = self.unmodeled.as_deref_mut() {
            u.stop();
        }
        Ok(())
    }
}

/// `floor(x)` as an integer without a libm call (x86-64 without SSE4.1 has no
/// floor instruction); saturates like `as` for huge values.
#[inline(always)]
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t - 1
    } else {
        t
    }
}

/// Three-mass model (2.20) as a generalized system, `q = [phi_m, phi_2, xi]`:
/// segment stretches `g_1.q = i_t phi_m - xi`, `g_2.q = r phi_2 - xi`,
/// `g_3.q = i_t phi_m - r phi_2` (`= r (phi_1 - phi_2)`).
fn three_mass_mech(p: &PhysicalParams, xi_m: f64) -> Mech<3, 3> {
    let (it, r) = (p.i_t(), p.r_m);
    let x0 = ThreeMassState::at_rest(p, xi_m);
    let mut m = Mech {
        q: [x0.phi_m_rad, x0.phi_2_rad, x0.xi_m],
        v: [0.0; 3],
        inv_mass: [
            1.0 / p.theta_e(),
            1.0 / p.theta_end_pulley_kg_m2,
            1.0 / p.m_c(),
        ],
        viscous: [
            it * it * p.d_m_n_s_per_m,
            r * r * p.d_end_pulley_n_s_per_m,
            p.d_c_n_s_per_m,
        ],
        coulomb: [p.tau_c_motor_nm, p.tau_c_end_pulley_nm, p.f_c_cart_n],
        input: [1.0, 0.0, 0.0],
        constant: [0.0, 0.0, p.gravity_force_n()],
        g: [[it, 0.0, -1.0], [0.0, r, -1.0], [it, -r, 0.0]],
        c: [0.0; 3],
        d: [0.0; 3],
        // the elongations: l_1 is `xi - i_t phi_m` (the cart end minus the
        // driving pulley's end, along the belt), l_2 `r phi_2 - xi`, l_3
        // `i_t phi_m - r phi_2`; they add up to zero around the belt
        slack: p.wear.belt_pretension_n.map(|pretension_n| mech::Slack {
            pretension_n,
            sign: [-1.0, 1.0, 1.0],
        }),
        gg: [[[0.0; 3]; 3]; 3],
    }
    .prepared();
    set_three_mass_segments(&mut m, p, &FixedSegment::of(p));
    m
}

/// Stiffness and damping of the segment `l_3` between the pulleys, which
/// does not depend on the cart position: computed once per sample instead
/// of once per sub-step (the same expression, so the same values).
struct FixedSegment {
    c_n_per_m: f64,
    d_n_s_per_m: f64,
}

impl FixedSegment {
    #[inline]
    fn of(p: &PhysicalParams) -> Self {
        let inv3 = 1.0 / (p.pulley_distance_m + p.end_compliance_length_m);
        FixedSegment {
            c_n_per_m: p.c_b_n * inv3,
            d_n_s_per_m: p.d_b_n_s * inv3,
        }
    }
}

/// Segment stiffness/damping at the current cart position: (2.10) as in
/// [`PhysicalParams::belt_segments`], written out for speed (two divisions;
/// the segment between the pulleys from `fixed`).
#[inline]
fn set_three_mass_segments(m: &mut Mech<3, 3>, p: &PhysicalParams, fixed: &FixedSegment) {
    let xi = m.q[2].clamp(0.0, p.stroke_m);
    let half = 0.5 * p.cart_belt_span_m;
    let le = p.end_compliance_length_m;
    let inv1 = 1.0 / (p.l_xi_m + xi - half + le);
    let inv2 = 1.0 / (p.pulley_distance_m - p.l_xi_m - xi - half + le);
    m.c = [p.c_b_n * inv1, p.c_b_n * inv2, fixed.c_n_per_m];
    m.d = [p.d_b_n_s * inv1, p.d_b_n_s * inv2, fixed.d_n_s_per_m];
    if p.wear.guide_wear_n > 0.0 {
        m.coulomb[2] = p.f_c_cart_n + p.wear.guide_friction_n(xi);
    }
}

/// Two-mass model (2.30), `q = [phi_m, xi]`, one replacement spring (2.26)/(2.27)
/// stretched by `i_t phi_m - xi`; end-pulley friction on the motor side.
fn two_mass_mech(p: &PhysicalParams, xi_m: f64) -> Mech<2, 1> {
    let it = p.i_t();
    let mut m = Mech {
        q: [xi_m / it, xi_m],
        v: [0.0; 2],
        inv_mass: [1.0 / p.theta_e(), 1.0 / p.m_c()],
        viscous: [
            it * it * (p.d_m_n_s_per_m + p.d_end_pulley_n_s_per_m),
            p.d_c_n_s_per_m,
        ],
        coulomb: [
            p.tau_c_motor_nm + p.tau_c_end_pulley_nm / p.i_g,
            p.f_c_cart_n,
        ],
        input: [1.0, 0.0],
        constant: [0.0, p.gravity_force_n()],
        g: [[it, -1.0]],
        gg: [[[0.0; 2]; 2]; 1],
        c: [0.0],
        d: [0.0],
        slack: None,
    }
    .prepared();
    set_two_mass_segments(&mut m, p);
    m
}

/// (2.26)/(2.27) at the current cart position, written out for speed:
/// `c = c_b (1/e_1 + 1/(e_2 + e_3))`, the same for `d` with `d_b`.
#[inline]
fn set_two_mass_segments(m: &mut Mech<2, 1>, p: &PhysicalParams) {
    let xi = m.q[1].clamp(0.0, p.stroke_m);
    let half = 0.5 * p.cart_belt_span_m;
    let le = p.end_compliance_length_m;
    let e1 = p.l_xi_m + xi - half + le;
    let e23 = (p.pulley_distance_m - p.l_xi_m - xi - half + le) + (p.pulley_distance_m + le);
    let k = 1.0 / e1 + 1.0 / e23;
    m.c = [p.c_b_n * k];
    m.d = [p.d_b_n_s * k];
    if p.wear.guide_wear_n > 0.0 {
        m.coulomb[1] = p.f_c_cart_n + p.wear.guide_friction_n(xi);
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_wear;
