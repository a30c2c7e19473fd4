//! Automatic controller design of thesis chapter 4 from the identified model:
//!
//! - [`prefilter`]: notch (4.1)/(4.2) or Butterworth (4.3)/(4.4),
//! - [`velocity`]: PI velocity controller (4.5)-(4.9),
//! - [`position`]: P position controller (4.10)-(4.14),
//! - [`feedforward`]: inertia and friction feedforward (4.15)-(4.17),
//! - [`sampled`]: the coefficients at `T_s` and the stability check of the discretized loops,
//! - [`dynamics`]: the one-knob mode,
//! - [`robust`]: the design rule for lightly damped axes: friction separated from
//!   damping, the prefilter chosen for margins that hold over the identification's uncertainty,
//!
//! Interpretation (docs/thesis-map.md, "The printed controller gains"): the prefilter sits
//! inside the velocity loop in series with the PI controller and is part of the
//! resonance condition (4.7); `G_R` has `T_R` (default 2 ms); the dead time is exact.
//! The conditions (4.7)-(4.9) and (4.13)/(4.14) are the specification; the printed
//! gains of Tables A.6/A.7 do not follow from them and are not reproduced.

pub mod drive_form;
pub mod dynamics;
pub mod feedforward;
pub mod position;
pub mod prefilter;
pub mod robust;
pub mod sampled;
pub mod velocity;

pub use drive_form::DriveForm;
pub use dynamics::Dynamics;
pub use feedforward::{Feedforward, FrictionParams};
pub use prefilter::{Prefilter, PrefilterKind};
pub use sampled::{DiscreteController, DiscreteLoops, DiscreteStability};
pub use velocity::{PiGains, VelocityPlant, VelocityRule};

use crate::error::{require_non_negative, require_positive};
use crate::lti::discrete::check_delay_samples;
use crate::lti::margins::StabilityMargins;
use crate::lti::{bode, log_grid, BodePoint, C64};
use crate::model::TwoMassParams;
use crate::{Error, Result};

/// Default velocity filter time constant `T_R`, s (Table A.4 setup).
pub const DEFAULT_T_R_S: f64 = 2e-3;
/// Default sampling time `T_s`, s (10 kHz, docs/thesis-map.md).
pub const DEFAULT_TS_S: f64 = 1e-4;
/// Longest current-loop dead time a design accepts, s: ten times the
/// thesis' 1 ms (Table A.4 setup). The identification looks no further
/// (stage 5), and a velocity loop behind a longer delay cannot reach the
/// bandwidth a belt axis needs.
pub const MAX_DEAD_TIME_S: f64 = 10e-3;
/// Points per decade of the verification grid: the dead-time phase moves less
/// than 0.03 rad between points up to Nyquist (1 ms, 10 kHz), and resonances with
/// a relative width above 0.5 % are resolved.
const GRID_POINTS_PER_DECADE: f64 = 500.0;

/// What the design needs from the identification.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DesignInput {
    /// The identified two-mass model (2.42).
    pub model: TwoMassParams,
    /// Current-loop dead time `t_T`, s (3.25).
    pub dead_time_s: f64,
    /// Velocity filter time constant `T_R`, s (6.1).
    pub t_r_s: f64,
    /// Sampling time `T_s`, s.
    pub ts_s: f64,
    /// Friction for the feedforward (Section 3.6); `None`: inertia-only feedforward.
    pub friction: Option<FrictionParams>,
}

impl DesignInput {
    /// With default `T_R` = 2 ms, `T_s` = 100 us and no friction.
    pub fn new(model: TwoMassParams, dead_time_s: f64) -> Self {
        DesignInput {
            model,
            dead_time_s,
            t_r_s: DEFAULT_T_R_S,
            ts_s: DEFAULT_TS_S,
            friction: None,
        }
    }

    /// Typed error for non-physical values (also checks that the resonance lies
    /// below the Nyquist frequency).
    pub fn validate(&self) -> Result<()> {
        self.model.validate()?;
        require_non_negative("dead_time_s", self.dead_time_s)?;
        require_positive("t_r_s", self.t_r_s)?;
        require_positive("ts_s", self.ts_s)?;
        if self.dead_time_s > MAX_DEAD_TIME_S {
            return Err(Error::invalid(
                "dead_time_s",
                self.dead_time_s,
                format!(
                    "must be at most {MAX_DEAD_TIME_S} s (a drive's current loop and bus delay)"
                ),
            ));
        }
        check_delay_samples(self.ts_s, self.dead_time_s)?;
        if let Some(f) = &self.friction {
            f.validate()?;
        }
        let nyquist = std::f64::consts::PI / self.ts_s;
        if self.model.resonance_rad_s() >= 0.5 * nyquist {
            return Err(Error::invalid(
                "ts_s",
                self.ts_s,
                format!(
                    "the resonance {:.1} rad/s must lie below half the Nyquist frequency {nyquist:.1} rad/s",
                    self.model.resonance_rad_s()
                ),
            ));
        }
        Ok(())
    }
}

/// The expert tuning knobs (thesis 4.2-4.3). Defaults: Butterworth, 60 deg / 80 deg,
/// `A_sup = -10 dB`, filter attenuation per prefilter default, dynamics standard.
/// The thesis' conditions ([`design`]) use exactly these values; the robust rule
/// ([`robust::robust_design`]) takes only `dynamics` from them and chooses
/// prefilter and nominal margins itself.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DesignKnobs {
    /// Prefilter type.
    pub prefilter: PrefilterKind,
    /// Velocity-loop phase margin `phi_r^omega` (4.9), deg.
    pub pm_velocity_deg: f64,
    /// Position-loop phase margin `phi_r^phi` (4.13), deg.
    pub pm_position_deg: f64,
    /// Resonance suppression `A_sup` (4.7), dB (< 0).
    pub resonance_suppression_db: f64,
    /// Filter gain at the antiresonance, `A_Notch` (4.2) or `A_bw` (4.4), dB;
    /// `None`: the prefilter's default (-6 dB notch, -3 dB Butterworth).
    pub filter_attenuation_db: Option<f64>,
    /// The one-knob setting: the margins the robust rule guarantees over the
    /// identification's uncertainty ([`Dynamics`]); files without it read as standard.
    #[serde(default)]
    pub dynamics: Dynamics,
}

impl Default for DesignKnobs {
    fn default() -> Self {
        DesignKnobs {
            prefilter: PrefilterKind::Butterworth,
            pm_velocity_deg: 60.0,
            pm_position_deg: 80.0,
            resonance_suppression_db: -10.0,
            filter_attenuation_db: None,
            dynamics: Dynamics::STANDARD,
        }
    }
}

impl DesignKnobs {
    /// The attenuation actually used.
    pub fn attenuation_db(&self) -> f64 {
        self.filter_attenuation_db
            .unwrap_or(self.prefilter.default_attenuation_db())
    }
}

/// The complete cascade design: continuous gains, prefilter, achieved margins,
/// discrete coefficients and feedforward.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ControllerDesign {
    /// What the design was computed from.
    pub input: DesignInput,
    /// The knobs used.
    pub knobs: DesignKnobs,
    /// The prefilter with its parameters (`omega_bw_rad_s` or `omega_r_rad_s` and `d_n`).
    pub prefilter: Prefilter,
    /// Model resonance `w_r` (2.44), rad/s.
    pub omega_r_rad_s: f64,
    /// Model antiresonance `w_z` (2.45), rad/s.
    pub omega_z_rad_s: f64,
    /// `K_P`, N m s/rad.
    pub k_p: f64,
    /// `K_I`, N m/rad.
    pub k_i: f64,
    /// `K_PP`, 1/s.
    pub k_pp: f64,
    /// Margins of the continuous velocity open loop.
    pub velocity_margins: StabilityMargins,
    /// Margins of the continuous position open loop.
    pub position_margins: StabilityMargins,
    /// Velocity open-loop gain at `w_r`, dB (achieved `A_sup`).
    pub gain_at_resonance_db: f64,
    /// Which condition fixed the PI gains with the phase margin ((4.7), or the
    /// maximum-`K_I` fallback for phase-limited loops, see [`VelocityRule`]).
    pub velocity_rule: VelocityRule,
    /// Coefficients at `T_s`.
    pub discrete: DiscreteController,
    /// Closed-loop pole radii of the discretized loops.
    pub discrete_stability: DiscreteStability,
    /// Feedforward parameters.
    pub feedforward: Feedforward,
}

/// Design the whole cascade. Errors: invalid input, [`Error::Infeasible`] when the
/// conditions have no solution, [`Error::Unstable`] when a discretized loop is unstable.
pub fn design(input: &DesignInput, knobs: &DesignKnobs) -> Result<ControllerDesign> {
    input.validate()?;
    let model = &input.model;
    let prefilter = Prefilter::design(knobs.prefilter, model, knobs.attenuation_db())?;
    let plant = VelocityPlant::new(input, &prefilter);
    let grid = verification_grid(input)?;
    let w_r = model.resonance_rad_s();
    let v = velocity::design_pi(
        &plant,
        w_r,
        knobs.pm_velocity_deg,
        knobs.resonance_suppression_db,
        &grid,
    )?;
    let p = position::design_p(&v.gains, &plant, knobs.pm_position_deg, &grid)?;
    let discrete = DiscreteController::new(&prefilter, &v.gains, p.k_pp, input)?;
    let loops = DiscreteLoops::new(&discrete, input)?;
    let discrete_stability = sampled::check_stability(&loops)?;
    Ok(ControllerDesign {
        input: *input,
        knobs: *knobs,
        prefilter,
        omega_r_rad_s: w_r,
        omega_z_rad_s: model.antiresonance_rad_s(),
        k_p: v.gains.k_p,
        k_i: v.gains.k_i,
        k_pp: p.k_pp,
        velocity_margins: v.margins,
        position_margins: p.margins,
        gain_at_resonance_db: v.gain_at_resonance_db,
        velocity_rule: v.rule,
        discrete,
        discrete_stability,
        feedforward: Feedforward::design(model, input.friction.as_ref())?,
    })
}

/// The grid on which margins are verified: from `w_z / 1e4` to the larger of the
/// Nyquist frequency and `20 w_r`.
pub fn verification_grid(input: &DesignInput) -> Result<Vec<f64>> {
    let w_min = input.model.antiresonance_rad_s() * 1e-4;
    let w_max = (std::f64::consts::PI / input.ts_s).max(20.0 * input.model.resonance_rad_s());
    let n = ((w_max / w_min).log10() * GRID_POINTS_PER_DECADE).ceil() as usize + 1;
    log_grid(w_min, w_max, n)
}

impl ControllerDesign {
    /// The PI gains.
    pub fn pi_gains(&self) -> PiGains {
        PiGains {
            k_p: self.k_p,
            k_i: self.k_i,
        }
    }

    /// Continuous velocity open loop `L(j w)` (4.5)-(4.6).
    pub fn velocity_open_loop(&self, w_rad_s: f64) -> C64 {
        let plant = VelocityPlant::new(&self.input, &self.prefilter);
        self.pi_gains().freq_response(w_rad_s) * plant.g_omega(w_rad_s)
    }

    /// Continuous closed velocity loop `G_w,cl(j w)` (4.10).
    pub fn velocity_closed_loop(&self, w_rad_s: f64) -> C64 {
        let plant = VelocityPlant::new(&self.input, &self.prefilter);
        position::closed_velocity_loop(&self.pi_gains(), &plant, w_rad_s)
    }

    /// Continuous position open loop `K_PP G_w,cl(j w)`.
    pub fn position_open_loop(&self, w_rad_s: f64) -> C64 {
        self.k_pp * self.velocity_closed_loop(w_rad_s)
    }

    /// The gains for the real-time controller (`K_v = 1`, (4.17)).
    pub fn cascade_gains(&self) -> beltune_rt::control::CascadeGains<f64> {
        beltune_rt::control::CascadeGains::new(self.k_pp, self.k_p, self.k_i)
    }

    /// A real-time controller configuration with this design's gains, velocity
    /// filter, prefilter (first section; the second is the identity) and nonlinear
    /// feedforward (4.16); torque limit `torque_max_nm`. Refinements and anti-windup
    /// keep the rt crate's defaults.
    pub fn cascade_config(
        &self,
        torque_max_nm: f64,
    ) -> Result<beltune_rt::control::CascadeConfig<f64>> {
        let mut cfg = beltune_rt::control::CascadeConfig::new(
            self.cascade_gains(),
            self.input.ts_s,
            self.input.t_r_s,
            torque_max_nm,
        )?;
        cfg.velocity_filter = self.discrete.velocity_filter;
        cfg.prefilter = [
            self.discrete.prefilter,
            beltune_rt::filter::SosCoeffs::IDENTITY,
        ];
        cfg.feedforward = beltune_rt::control::Feedforward::nonlinear(
            self.feedforward.inertia_kg_m2,
            self.feedforward.viscous_nm_s_per_rad,
            self.feedforward.coulomb_nm,
        );
        cfg.validate()?;
        Ok(cfg)
    }

    /// The discretized loops (state space) of this design.
    pub fn discrete_loops(&self) -> Result<DiscreteLoops> {
        DiscreteLoops::new(&self.discrete, &self.input)
    }

    /// Bode data for reports and the tuning page on `n` log-spaced points between
    /// `w_min_rad_s` and `w_max_rad_s`.
    pub fn plot_data(&self, w_min_rad_s: f64, w_max_rad_s: f64, n: usize) -> Result<PlotData> {
        let grid = log_grid(w_min_rad_s, w_max_rad_s, n)?;
        let plant = VelocityPlant::new(&self.input, &self.prefilter);
        let gains = self.pi_gains();
        let l_v = |w: f64| gains.freq_response(w) * plant.g_omega(w);
        let g_cl = |w: f64| position::closed_velocity_loop(&gains, &plant, w);
        let l_p = |w: f64| self.k_pp * g_cl(w);
        Ok(PlotData {
            velocity_open_loop: bode(l_v, &grid)?,
            velocity_closed_loop: bode(|w| crate::lti::feedback(l_v(w)), &grid)?,
            position_open_loop: bode(l_p, &grid)?,
            position_closed_loop: bode(|w| crate::lti::feedback(l_p(w)), &grid)?,
            prefilter: bode(|w| self.prefilter.tf().freq_response(w), &grid)?,
            plant: bode(|w| plant.plant.freq_response(w), &grid)?,
        })
    }

    /// The flat summary with the CLI's key names.
    pub fn summary(&self) -> DesignSummary {
        let (omega_bw, d_n) = match self.prefilter {
            Prefilter::Butterworth { omega_bw_rad_s } => (Some(omega_bw_rad_s), None),
            Prefilter::Notch { d_n, .. } => (None, Some(d_n)),
            Prefilter::None => (None, None),
        };
        DesignSummary {
            prefilter: self.prefilter.kind(),
            k_p: self.k_p,
            k_i: self.k_i,
            k_pp: self.k_pp,
            omega_bw,
            d_n,
            omega_r: self.omega_r_rad_s,
            omega_c_velocity: self.velocity_margins.crossover_rad_s,
            phase_margin_velocity_deg: self.velocity_margins.phase_margin_deg,
            gain_margin_velocity_db: self.velocity_margins.gain_margin_db,
            gain_at_resonance_db: self.gain_at_resonance_db,
            velocity_rule: self.velocity_rule,
            omega_c_position: self.position_margins.crossover_rad_s,
            phase_margin_position_deg: self.position_margins.phase_margin_deg,
            gain_margin_position_db: self.position_margins.gain_margin_db,
            m_e: self.feedforward.inertia_kg_m2,
            ts_s: self.discrete.ts_s,
        }
    }
}

/// Flat summary of a design (the `beltune design --json` keys). Units: gains as in
/// [`ControllerDesign`], frequencies in rad/s, margins in deg / dB, `m_e` in kg m^2.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DesignSummary {
    /// Prefilter type.
    pub prefilter: PrefilterKind,
    /// `K_P`, N m s/rad.
    pub k_p: f64,
    /// `K_I`, N m/rad.
    pub k_i: f64,
    /// `K_PP`, 1/s.
    pub k_pp: f64,
    /// Butterworth cut-off, rad/s.
    pub omega_bw: Option<f64>,
    /// Notch width parameter.
    pub d_n: Option<f64>,
    /// Resonance `w_r`, rad/s.
    pub omega_r: f64,
    /// Velocity-loop crossover, rad/s.
    pub omega_c_velocity: f64,
    /// Velocity-loop phase margin, deg.
    pub phase_margin_velocity_deg: f64,
    /// Velocity-loop gain margin, dB.
    pub gain_margin_velocity_db: f64,
    /// Velocity open-loop gain at `w_r`, dB.
    pub gain_at_resonance_db: f64,
    /// Which condition fixed the PI gains with the phase margin.
    pub velocity_rule: VelocityRule,
    /// Position-loop crossover, rad/s.
    pub omega_c_position: f64,
    /// Position-loop phase margin, deg.
    pub phase_margin_position_deg: f64,
    /// Position-loop gain margin, dB.
    pub gain_margin_position_db: f64,
    /// Feedforward inertia `m_e~`, kg m^2.
    pub m_e: f64,
    /// Sampling time, s.
    pub ts_s: f64,
}

/// Bode data (plain data, no plotting) of a design.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlotData {
    /// Velocity open loop `L`.
    pub velocity_open_loop: Vec<BodePoint>,
    /// `L / (1 + L)` of the velocity loop.
    pub velocity_closed_loop: Vec<BodePoint>,
    /// Position open loop `K_PP G_w,cl`.
    pub position_open_loop: Vec<BodePoint>,
    /// Closed position loop.
    pub position_closed_loop: Vec<BodePoint>,
    /// Prefilter `G_pre`.
    pub prefilter: Vec<BodePoint>,
    /// Model (2.42), torque to motor angle.
    pub plant: Vec<BodePoint>,
}

#[cfg(test)]
mod tests;
