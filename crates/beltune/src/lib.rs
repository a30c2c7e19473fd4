//! # beltune: self-commissioning of belt-driven servo axes
//!
//! The thesis (Gruber, "Self-Commissioning of Linear Toothed Belt Drives",
//! TU Wien 2017) is the specification; `docs/thesis-map.md` maps its sections
//! to the modules, with the unit conventions, known typos and reference values.
//! Data flows one way:
//!
//! ```text
//! model (parameters, plant models) -> sim (a simulated axis behind the `Axis` trait)
//!   -> ident (FRF, fit, friction) -> design (prefilter, PI, P, feedforward)
//!   -> procedure (the commissioning stages) -> report (plots, HTML)
//! ```
//!
//! `lti` is the frequency-domain toolkit used by `model`, `ident` and `design`.
//! The per-sample real-time parts live in the `no_std` crate `beltune-rt`.
//!
//! Units are SI everywhere; the conventions (e.g. `d_m` in N s/m as a
//! translational equivalent, `i_t = r / i_g` in m) are those of docs/thesis-map.md.

pub mod axis;
pub mod commission;
pub mod design;
pub mod error;
pub mod export;
pub mod ident;
pub mod io;
pub mod lti;
pub mod model;
pub mod record;
pub mod report;
pub mod sim;
pub mod study;
pub mod units;
pub mod verdict;

pub use error::{Error, Result};
