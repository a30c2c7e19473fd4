//! Identification, thesis chapter 3: from a recorded excitation to the
//! frequency response (ETFE with Clary's method II and coherence), the
//! identification strategies, the current-loop dead time, the parametric
//! two-mass fit, and friction.
//!
//! - [`etfe`]: (3.7)-(3.15), averaging (Figure 3.7), coherence, log-spaced subset (Figure 3.9)
//! - [`features`]: resonance peak, antiresonance dip, rigid-body asymptote (start values)
//! - [`fit`]: Levenberg-Marquardt fit of (2.42), (3.32)-(3.34), with uncertainties
//! - [`friction`]: constant-velocity runs (3.35)-(3.36) and regression on any motion
//! - [`nonlinear`]: the nonlinear two-mass model (2.30) with its Coulomb friction, from the excitation
//! - [`strategy`]: open loop, direct and indirect closed loop (3.18)-(3.24), the excitation at `omega_d` (3.23)-(3.24)
//! - [`closed_loop`]: closed-loop identification from a record, with the known controller's frequency responses
//! - [`dead_time`]: current-loop dead time (3.25)-(3.30)
//! - [`csv_columns`]: the columns of a recorded CSV file, validated
//! - [`residual`]: what the two-mass fit does not explain, per line; a second resonance named
//! - [`recorded`]: the whole identification from a CSV record (CLI `identify`, `commission --csv`)

pub mod closed_loop;
pub mod csv_columns;
pub mod dead_time;
pub mod etfe;
pub mod features;
pub mod fit;
pub mod friction;
pub mod nonlinear;
pub mod recorded;
pub mod residual;
pub mod strategy;

#[cfg(test)]
mod tests_closed_loop;
#[cfg(test)]
mod tests_measured;
#[cfg(test)]
mod tests_sim;
#[cfg(test)]
mod tests_unmodeled;
#[cfg(test)]
pub(crate) mod testutil;

pub use closed_loop::{ClosedLoopMethod, IdentificationStrategy, KnownController, ReferenceKind};
pub use csv_columns::{read_csv_columns, CsvColumns, Sampling};
pub use dead_time::{estimate_dead_time, DeadTime};
pub use etfe::{etfe, log_spaced_subset, EtfeConfig, Frf, LineCounts, LineStatus};
pub use features::{frf_features, FrfFeatures};
pub use fit::{fit_two_mass, FitConfig, FitModel, ModelUnits, ParamUncertainty, TwoMassFit};
pub use friction::{
    fit_constant_velocity, fit_viscous_only, fit_with_offset, identify_from_motion, run_means,
    ConstantVelocityRun, FrictionFit, MotionFriction, MotionFrictionConfig, OffsetFrictionFit,
    THESIS_VELOCITY_SEQUENCE_M_S,
};
pub use nonlinear::{fit_nonlinear, NonlinearConfig, NonlinearFit};
pub use recorded::{detect_period, identify_recorded, RecordedExcitation, RecordedIdentification};
pub use residual::{fit_residual, FitResidual, SecondResonance};
pub use strategy::{
    direct_closed_loop, indirect_closed_loop, indirect_closed_loop_reference,
    indirect_closed_loop_velocity, open_loop,
};
