//! Plant models of thesis chapter 2.
//!
//! - [`params`]: physical (data-sheet) parameters, belt segments (2.10),
//!   replacement stiffness/damping (2.26)/(2.27), linearization, friction totals (3.36).
//! - [`three_mass`]: the nonlinear three-mass model (2.20) and its linearization.
//! - [`equivalent`]: the two-mass equivalent of the three-mass physics (end pulley included).
//! - [`nonlinear_two_mass`]: the nonlinear two-mass model (2.30).
//! - [`two_mass`]: the linear two-mass model and its transfer functions (2.33)-(2.49).
//! - [`unmodeled`]: what real axes have and (2.30) does not (current loop, frame mode, cogging, ripple, encoder errors, tooth mesh).
//! - [`wear`]: ageing of an axis (belt stiffness, friction, a slack span, a worn guide).
//! - [`zoo`]: the axis zoo (data/axes/, public data sheets) and what a modest move needs.
//! - [`rigs`]: the built-in plants (`egc70`, `sim-a`, `sim-b`, `sim-c`) and TOML loading.

pub mod equivalent;
pub mod nonlinear_two_mass;
pub mod params;
pub mod rigs;
pub mod stroke;
pub mod three_mass;
pub mod two_mass;
pub mod unmodeled;
pub mod wear;
pub mod zoo;

pub use params::{BeltSegments, FrictionTotals, MeasurementNoise, PhysicalParams, SegmentLengths};
pub use rigs::{builtin, load_toml, LinearPlant, Plant, BUILTIN_NAMES};
pub use two_mass::TwoMassParams;
pub use unmodeled::Unmodeled;
pub use wear::Wear;
