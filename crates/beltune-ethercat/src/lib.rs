//! EtherCAT for beltune: a CiA 402 servo drive as a [`beltune::axis::Axis`].
//!
//! - [`cia402`], [`pdo`], [`scaling`]: the drive profile without a bus (state
//!   machine, process-data codec, units);
//! - [`esc`] and [`drive`]: a virtual CiA 402 servo drive, an EtherCAT SubDevice
//!   emulator (registers, SII EEPROM, AL state machine, sync managers, FMMUs,
//!   CoE SDO mailbox, distributed clocks, sync-manager watchdog) whose physics
//!   is [`beltune::sim::SimAxis`];
//! - [`master`]: the axis on the master side through `ethercrab`, over a raw
//!   socket or in-process against the virtual drive;
//! - [`sched`]: real-time scheduling of the bus thread;
//! - `netns` (feature `test-util`): a veth pair in a network namespace for wire tests.

pub mod cia402;
pub mod drive;
pub mod error;
pub mod esc;
pub mod esi;
pub mod loops;
pub mod master;
#[cfg(feature = "test-util")]
pub mod netns;
pub mod objects;
pub mod od;
pub mod pdo;
pub mod profile;
pub mod scaling;
pub mod sched;
pub mod serve;

pub use error::Error;
