//! Identification, thesis chapter 3: from a recorded excitation to the
//! frequency response (ETFE with Clary's method II and coherence), the
//! identification strategies, the current-loop dead time, the parametric
//! two-mass fit, and friction.
//!
//! - [`etfe`]: (3.7)-(3.15), averaging (Figure 3.7), coherence, log-spaced subset (Figure 3.9)
//! - [`features`]: resonance peak, antiresonance dip, rigid-body asymptote (start values)
//! - [`fit`]: Levenberg-Marquardt fit of (2.42), (3.32)-(3.34), with uncertainties
//! - [`record`]: CSV records with validation

pub mod etfe;
pub mod features;
pub mod fit;
pub mod record;

#[cfg(test)]
mod tests_measured;
#[cfg(test)]
pub(crate) mod testutil;

pub use etfe::{etfe, log_spaced_subset, EtfeConfig, Frf, LineStatus};
pub use features::{frf_features, FrfFeatures};
pub use fit::{fit_two_mass, FitConfig, FitModel, ModelUnits, ParamUncertainty, TwoMassFit};
pub use record::{read_csv_columns, CsvColumns, Sampling};
