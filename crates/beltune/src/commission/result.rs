//! What a commissioning run produced: the in-memory result of the stages, from
//! which the record (`crate::record`) and the report (`crate::report`) are made.

use super::stages::validation_moves::PlannedMove;
use super::stiffness::TargetStiffness;
use super::validation::{MoveResult, Validation, VariantMove};
use super::DataSheet;
use crate::design::robust::GuaranteedMargins;
use crate::design::ControllerDesign;
use crate::ident::dead_time::DeadTime;
use crate::ident::etfe::Frf;
use crate::ident::fit::TwoMassFit;
use crate::ident::friction::{ConstantVelocityRun, FrictionFit};
use crate::record::model::{FrictionResult, IdentifiedModel};
use crate::verdict::Verdict;

/// The identification experiment as recorded (stage 5): the PRBS torque
/// command and the motor-side position, with the limits it ran under.
#[derive(Clone, Debug, Default)]
pub struct ExcitationTrace {
    /// Time since the axis was taken, s.
    pub time_s: Vec<f64>,
    /// Torque command (holding torque plus PRBS), N m.
    pub torque_command_nm: Vec<f64>,
    /// Motor-side position `i_t phi_m`, m.
    pub position_m: Vec<f64>,
    /// Torque limit of the commissioning, N m.
    pub torque_max_nm: f64,
    /// Allowed travel, m.
    pub travel_min_m: f64,
    /// Allowed travel, m.
    pub travel_max_m: f64,
}

/// Everything a commissioning run produced.
#[derive(Clone, Debug)]
pub struct Commissioning {
    /// The data sheet used.
    pub datasheet: DataSheet,
    /// The torque limit the commissioning ran under: the smaller of the data
    /// sheet's and the drive's, N m.
    pub torque_max_nm: f64,
    /// Where the model was measured: the mean motor-side position over the
    /// compared periods of the excitation, m.
    pub identification_position_m: f64,
    /// Holding torque, N m.
    pub holding_torque_nm: f64,
    /// The belt stiffness where the validation move ends (stage 5b), which
    /// the static belt stretch uses.
    pub target_stiffness: TargetStiffness,
    /// PRBS amplitude `A_PRBS` used (values +-A/2), N m.
    pub excitation_amplitude_nm: f64,
    /// FRF from the torque command to the motor angle.
    pub frf: Frf,
    /// The identified model the design uses: the friction-aware fit of the
    /// nonlinear model (2.30) where it explains the record better
    /// ([`crate::ident::FitModel::Nonlinear`]), else the FRF fit.
    pub fit: TwoMassFit,
    /// The thesis' fit of the FRF's magnitude (3.5).
    pub frf_fit: TwoMassFit,
    /// The friction-aware fit, `None` where it failed.
    pub nonlinear: Option<crate::ident::NonlinearFit>,
    /// The dead time.
    pub dead_time: DeadTime,
    /// The model summary.
    pub identified: IdentifiedModel,
    /// The controller design.
    pub design: ControllerDesign,
    /// Friction points (motor velocity rad/s, torque N m).
    pub friction_points: Vec<ConstantVelocityRun>,
    /// Friction fit.
    pub friction_fit: FrictionFit,
    /// Friction summary.
    pub friction: FrictionResult,
    /// The validation moves that ran: none and linear feedforward where
    /// asked for ([`super::CommissioningConfig::compare_feedforward`]),
    /// then nonlinear, the delivered controller's (always last).
    pub moves: Vec<VariantMove>,
    /// Summaries of the moves.
    pub validation: Validation,
    /// The validation move run (Table A.8's or the fastest the axis can do).
    pub validation_move: PlannedMove,
    /// The margins the delivered controller keeps over the identification's
    /// uncertainty ([`crate::design::robust::guaranteed_margins`]).
    pub guaranteed: GuaranteedMargins,
    /// The one verdict on the delivered controller ([`crate::verdict`]).
    pub verdict: Verdict,
    /// The open-loop excitation of stage 5 and the axis' response.
    pub excitation: ExcitationTrace,
    /// Time the axis was busy, s.
    pub experiment_time_s: f64,
    /// The axis time of each stage, in the order they ran (they add up to
    /// [`Self::experiment_time_s`]).
    pub stage_axis_times: Vec<super::stages::StageAxisTime>,
    /// Wall-clock time spent computing (FFT, fit, design), s.
    pub computation_time_s: f64,
    /// One log line per stage.
    pub log: Vec<String>,
}

impl Commissioning {
    /// The delivered controller's validation move (nonlinear feedforward).
    pub fn delivered_move(&self) -> Option<&MoveResult> {
        self.moves
            .iter()
            .rev()
            .find(|m| m.variant == super::validation::FeedforwardVariant::Nonlinear)
            .map(|m| &m.result)
    }
}
