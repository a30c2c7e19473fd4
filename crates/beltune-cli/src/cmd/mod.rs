//! One file per subcommand.

pub mod commission;
pub mod compare;
pub mod completions;
pub mod config;
pub mod design;
pub mod diagnostic;
pub mod excitation;
pub mod export;
pub mod friction;
pub mod health;
pub mod history;
pub mod identify;
pub mod knobs;
pub mod man;
pub mod montecarlo;
pub mod plant;
pub mod plant_template;
pub mod record;
pub mod serve;
pub mod summary;
pub mod trajectory;
pub mod util;
pub mod verdict;
pub mod vibration;
pub mod virtual_drive;
