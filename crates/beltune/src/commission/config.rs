//! What the commissioning is told before it starts: the data sheet, the
//! excitation settings, the design rule, the limits of its moves and of its
//! verdict. Every setting is in seconds, hertz or SI units, never in samples:
//! the sample counts are derived for the axis' cycle time
//! ([`crate::axis::AxisInfo::ts_s`]), so the same configuration commissions a
//! 10 kHz simulator and a 1 kHz fieldbus master.

use super::validation::MoveSpec;
use crate::design::robust::DesignRule;
use crate::design::DesignKnobs;
use crate::{Error, Result};
use beltune_rt::trajectory::Limits;

/// What the drive knows before commissioning: data sheets and mounting.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DataSheet {
    /// Motor-side inertia `Theta_e` (motor, coupling, pulley), kg m^2.
    pub theta_e_kg_m2: f64,
    /// Transmission `i_t = r / i_g`, m/rad.
    pub i_t_m: f64,
    /// Moving mass as far as known (cart plus the payload the user states), kg.
    pub moving_mass_kg: f64,
    /// Cart position at motor encoder count 0 (from homing), m.
    pub origin_m: f64,
    /// Allowed travel, m (inside the stroke).
    pub travel_min_m: f64,
    /// Allowed travel, m.
    pub travel_max_m: f64,
    /// Torque limit for the commissioning, N m.
    pub torque_max_nm: f64,
    /// Speed limit for the commissioning, m/s.
    pub velocity_max_m_s: f64,
    /// The antiresonance range `[lowest, highest]` the data sheet allows over
    /// the stroke, Hz ([`super::band::antiresonance_band_hz`]); `None`:
    /// unknown (the PRBS and the bootstrap stay as configured).
    #[serde(default)]
    pub antiresonance_band_hz: Option<[f64; 2]>,
    /// How the two-mass model changes from the identification position to
    /// the ends of the stroke, from the data sheet's physics
    /// ([`crate::model::stroke`]); `None`: unknown (a linear set, a
    /// recording), the design is checked at the identification position only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stroke_variation: Option<crate::model::stroke::StrokeVariation>,
}

impl DataSheet {
    /// Stage 1: plausibility. Typed errors for non-physical values.
    pub fn validate(&self) -> Result<()> {
        use crate::error::{require_finite, require_positive};
        require_positive("theta_e [kg m^2]", self.theta_e_kg_m2)?;
        require_positive("i_t [m/rad]", self.i_t_m)?;
        require_positive("moving mass [kg]", self.moving_mass_kg)?;
        require_finite("origin [m]", self.origin_m)?;
        require_positive("torque limit [N m]", self.torque_max_nm)?;
        require_positive("velocity limit [m/s]", self.velocity_max_m_s)?;
        if !(self.travel_min_m.is_finite()
            && self.travel_max_m.is_finite()
            && self.travel_max_m - self.travel_min_m > 0.05)
        {
            return Err(Error::invalid(
                "travel window [m]",
                self.travel_max_m - self.travel_min_m,
                "needs min < max with at least 50 mm of travel",
            ));
        }
        if self.origin_m < self.travel_min_m || self.origin_m > self.travel_max_m {
            return Err(Error::invalid(
                "start position [m]",
                self.origin_m,
                format!(
                    "the axis starts outside the travel window [{:.3}, {:.3}] m",
                    self.travel_min_m, self.travel_max_m
                ),
            ));
        }
        if let Some(v) = &self.stroke_variation {
            v.validate()?;
        }
        Ok(())
    }

    /// What a technician enters for a plant: its data-sheet inertia,
    /// transmission, moving mass (cart plus stated payload), torque limit, and a
    /// travel window inside the stroke (Table A.8: -10 mm to stroke - 30 mm;
    /// a linear set without stroke gets 0.6 m). `origin_m` is the homing result,
    /// `travel_window_m` overrides the window.
    pub fn for_plant(
        plant: &crate::model::rigs::Plant,
        origin_m: f64,
        travel_window_m: Option<(f64, f64)>,
    ) -> Self {
        use crate::model::rigs::Plant;
        let (theta_e, i_t, mass, stroke) = match plant {
            Plant::Physical(p) => (p.theta_e(), p.i_t(), p.m_c(), p.stroke_m),
            Plant::Linear(l) => (l.two_mass.theta_e, l.two_mass.i_t, l.two_mass.m_c, 0.6),
        };
        let (lo, hi) = travel_window_m.unwrap_or((-0.01, stroke - 0.03));
        let mut ds = DataSheet {
            theta_e_kg_m2: theta_e,
            i_t_m: i_t,
            moving_mass_kg: mass,
            origin_m,
            travel_min_m: lo,
            travel_max_m: hi,
            torque_max_nm: plant.info().torque_max_nm,
            velocity_max_m_s: 2.5,
            antiresonance_band_hz: super::band::antiresonance_band_hz(plant),
            stroke_variation: None,
        };
        ds.stroke_variation = crate::model::stroke::StrokeVariation::of(
            plant,
            super::stages::take_axis::identification_position_m(&ds),
        );
        ds
    }

    /// Rigid-body inertia from the data sheet, `Theta_e + i_t^2 m`, kg m^2.
    pub fn rigid_inertia(&self) -> f64 {
        self.theta_e_kg_m2 + self.i_t_m * self.i_t_m * self.moving_mass_kg
    }
}

/// How far a travel window may reach beyond either end of the stroke, m (the
/// default window's -10 mm, Table A.8).
pub const TRAVEL_WINDOW_OVERTRAVEL_M: f64 = 0.01;

/// Error if a travel window `(min, max)` reaches beyond the plant's stroke
/// (by more than [`TRAVEL_WINDOW_OVERTRAVEL_M`]): the supervisor would let the
/// cart run into the end stop.
pub fn check_travel_window(
    plant: &crate::model::rigs::Plant,
    travel_window_m: Option<(f64, f64)>,
) -> Result<()> {
    let Some((lo, hi)) = travel_window_m else {
        return Ok(());
    };
    let stroke = plant.stroke_m().unwrap_or(0.6);
    let m = TRAVEL_WINDOW_OVERTRAVEL_M;
    if !(lo.is_finite() && hi.is_finite() && lo >= -m && hi <= stroke + m && lo < hi) {
        return Err(Error::invalid(
            "travel window [m]",
            if lo < -m { lo } else { hi },
            format!(
                "the window {lo}..{hi} m must lie inside the stroke 0..{stroke} m (up to {} mm beyond either end)",
                m * 1e3
            ),
        ));
    }
    Ok(())
}

/// Excitation settings (thesis 3.1, 3.4).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExcitationConfig {
    /// PRBS order `n_PRBS` (the lowest; higher where a shorter clock needs
    /// it for the same period, [`Self::for_band`]).
    pub prbs_order: u32,
    /// PRBS clock period `P_PRBS`, s (rounded to whole samples of the axis'
    /// cycle time, at least one; 1.6 ms = 16 samples at 10 kHz): the
    /// longest clock; shorter where the data sheet allows higher resonances
    /// ([`Self::for_band`]).
    pub clock_period_s: f64,
    /// Periods averaged (`n_m`).
    pub periods: usize,
    /// Leading periods discarded as transient.
    pub skip_periods: usize,
    /// A fixed amplitude `A_PRBS` in N m instead of the search (expert use).
    pub fixed_amplitude_nm: Option<f64>,
    /// First amplitude tried, as a fraction of the torque limit.
    pub amplitude_start_fraction: f64,
    /// Factor between successive amplitudes.
    pub amplitude_growth: f64,
    /// Largest amplitude allowed, as a fraction of the torque limit.
    pub amplitude_max_fraction: f64,
    /// The chosen amplitude is the first that moves the axis, times this margin
    /// (Coulomb friction must be small against the excitation for the
    /// small-signal FRF to show the linear model).
    pub amplitude_margin: f64,
    /// Lowest frequency used by the fit, Hz: below it the stick-slip of
    /// Coulomb friction dominates the response to a PRBS.
    pub fit_band_min_hz: f64,
    /// Fraction of windows of [`Self::moving_window_s`] in which the encoder
    /// must move for an amplitude to count.
    pub moving_fraction: f64,
    /// Length of the windows of the movement test, s.
    pub moving_window_s: f64,
    /// Length of one amplitude test burst, s.
    pub burst_s: f64,
    /// Log-spaced lines used by the fit.
    pub n_log_lines: usize,
    /// Whether the clock and order follow the resonance range of the data
    /// sheet and the sampling rate ([`Self::for_band`]; off where the user
    /// set them).
    #[serde(default = "default_true")]
    pub band_from_data_sheet: bool,
}

fn default_true() -> bool {
    true
}

impl Default for ExcitationConfig {
    fn default() -> Self {
        ExcitationConfig {
            prbs_order: 9,
            clock_period_s: 1.6e-3,
            periods: 2,
            skip_periods: 1,
            fixed_amplitude_nm: None,
            amplitude_start_fraction: 0.02,
            amplitude_growth: 1.5,
            amplitude_max_fraction: 0.5,
            amplitude_margin: 6.0,
            fit_band_min_hz: 3.0,
            moving_fraction: 0.9,
            moving_window_s: 2e-3,
            burst_s: 0.15,
            n_log_lines: 60,
            band_from_data_sheet: true,
        }
    }
}

/// Whole samples of `ts_s` in `duration_s`, rounded, at least one.
fn samples_in(duration_s: f64, ts_s: f64) -> usize {
    let n = (duration_s / ts_s).round();
    if n.is_finite() && n >= 1.0 {
        n.min(u32::MAX as f64) as usize
    } else {
        1
    }
}

impl ExcitationConfig {
    /// The PRBS clock period in samples of `ts_s`.
    pub fn clock_samples(&self, ts_s: f64) -> u32 {
        samples_in(self.clock_period_s, ts_s) as u32
    }

    /// The movement-test window in samples of `ts_s` (at least 2).
    pub fn moving_window_samples(&self, ts_s: f64) -> usize {
        samples_in(self.moving_window_s, ts_s).max(2)
    }

    /// One amplitude test burst in samples of `ts_s`.
    pub fn burst_samples(&self, ts_s: f64) -> usize {
        samples_in(self.burst_s, ts_s)
    }
}

/// Everything the commissioning can be told.
#[derive(Clone, Debug, PartialEq)]
pub struct CommissioningConfig {
    /// Design knobs (thesis 4.2-4.3).
    pub knobs: DesignKnobs,
    /// Excitation settings.
    pub excitation: ExcitationConfig,
    /// Velocity-filter time constant `T_R`, s (default
    /// [`crate::design::DEFAULT_T_R_S`]).
    pub t_r_s: f64,
    /// Speeds of the friction runs (each in both directions), m/s.
    pub friction_speeds_m_s: Vec<f64>,
    /// Time each friction run spends at its constant speed, s: the run is
    /// as long as that plateau and its acceleration and deceleration need
    /// (at most the travel window allows). With runs of a fixed
    /// 0.1 m, the 0.4 m/s plateau of a heavy cart on a soft belt lasted
    /// 0.2 s, two periods of its ringing and less than the velocity loop's
    /// settling, and the fitted viscous friction came out at a third of the
    /// truth (the feedforward then lacked 0.1 N m at the validation move's
    /// cruise speed).
    pub friction_plateau_s: f64,
    /// The validation move.
    pub validation: MoveSpec,
    /// Also run the validation move with no and with linear feedforward
    /// before the delivered controller's (thesis chapter 5's comparison).
    /// Neither is judged nor delivered; they keep the axis busy about 3.5 s
    /// each, so they run only on request (`--compare-feedforward`).
    pub compare_feedforward: bool,
    /// Largest following error allowed in closed-loop stages, m.
    pub following_error_max_m: f64,
    /// How the controller is designed from the identified model
    /// ([`crate::design::robust`]): by default the robust rule for lightly
    /// damped axes (friction separated from damping, prefilter and
    /// nominal margins chosen for margins that hold over the
    /// identification's uncertainty); [`DesignRule::Knobs`] uses exactly
    /// [`Self::knobs`]; [`DesignRule::Thesis`] the thesis' design on the fit as
    /// identified.
    pub design_rule: DesignRule,
    /// What the verdict judges the delivered controller against.
    pub limits: crate::verdict::Limits,
}

impl Default for CommissioningConfig {
    fn default() -> Self {
        CommissioningConfig {
            knobs: DesignKnobs::default(),
            excitation: ExcitationConfig::default(),
            t_r_s: crate::design::DEFAULT_T_R_S,
            friction_speeds_m_s: vec![0.1, 0.4],
            friction_plateau_s: 0.3,
            validation: MoveSpec::default(),
            compare_feedforward: false,
            following_error_max_m: 0.05,
            design_rule: DesignRule::Robust,
            limits: crate::verdict::Limits::default(),
        }
    }
}

/// Speed of the positioning moves, m/s (low: a tenth of Table A.8's 5 m/s).
pub const POSITIONING_SPEED_M_S: f64 = 0.5;
/// Acceleration of the positioning moves, m/s^2 (a tenth of Table A.8's 45 m/s^2).
pub const POSITIONING_ACCELERATION_M_S2: f64 = 4.0;
/// Jerk of the positioning moves, m/s^3 (Table A.8's).
pub const POSITIONING_JERK_M_S3: f64 = 40.0;

/// Limits of the positioning moves (the commissioning's moves between its
/// experiments) inside the travel window `position_min_m ..= position_max_m`:
/// [`POSITIONING_SPEED_M_S`], [`POSITIONING_ACCELERATION_M_S2`],
/// [`POSITIONING_JERK_M_S3`].
pub fn positioning_limits_in(position_min_m: f64, position_max_m: f64) -> Limits {
    Limits {
        v_max: POSITIONING_SPEED_M_S,
        v_min: -POSITIONING_SPEED_M_S,
        a_max: POSITIONING_ACCELERATION_M_S2,
        a_min: -POSITIONING_ACCELERATION_M_S2,
        j_max: POSITIONING_JERK_M_S3,
        j_min: -POSITIONING_JERK_M_S3,
        position_min: position_min_m,
        position_max: position_max_m,
    }
}

/// The positioning limits inside the travel window of `ds`
/// ([`positioning_limits_in`]).
pub fn positioning_limits(ds: &DataSheet) -> Limits {
    positioning_limits_in(ds.travel_min_m, ds.travel_max_m)
}
