//! The commissioning procedure (thesis chapters 3-5): stages driven sample by
//! sample through the [`crate::plant::Axis`] trait, under a safety supervisor.

pub mod progress;
pub mod safety;

pub use progress::{LogProgress, NoProgress, Progress};
pub use safety::{SafetyLimits, SafetySupervisor, Violation};

pub mod acceptance;
pub mod bootstrap;
pub mod commission;
pub mod compare;
pub mod controller_file;
pub mod motion;
pub mod outputs;
pub mod plots;
pub mod recorded;
pub mod report_build;
pub mod result;
pub mod runner;
pub mod stages;
pub mod validation;
pub mod verdict;
