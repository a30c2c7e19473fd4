//! The `beltune` command as a library: every subcommand (`cmd`), the progress
//! display and the tuning-page server (`serve`), so that integration tests call
//! them directly. The binary (`main.rs`) only parses the command line and maps
//! errors to [`exit::ExitStatus`].

pub mod cmd;
pub mod exit;
pub mod help;
pub mod progress;
pub mod serve;
pub mod term;
