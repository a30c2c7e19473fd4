//! One file per subcommand.

pub mod commission;
pub mod compare;
pub mod design;
pub mod excitation;
pub mod export;
pub mod friction;
pub mod identify;
pub mod knobs;
pub mod plant;
pub mod serve;
pub mod trajectory;
pub mod util;
pub mod virtual_drive;
