//! # beltune: self-commissioning of belt-driven servo axes
//!
//! The thesis (Gruber, "Self-Commissioning of Linear Toothed Belt Drives",
//! TU Wien 2017) is the specification; `docs/thesis-map.md` maps its sections
//! to the modules, with the unit conventions, known typos and reference values.
//! The modules follow the data flow:
//!
//! ```text
//! model -> sim -> ident -> design -> commission -> verdict -> record -> report
//! ```
//!
//! | module | what |
//! | --- | --- |
//! | [`model`] | physical parameters and the plant models of thesis chapter 2, the built-in axes |
//! | [`sim`] | a simulated axis behind the [`axis::Axis`] trait, and its truth |
//! | [`axis`] | the one cyclic exchange with an axis, simulated or real |
//! | [`ident`] | identification (chapter 3): FRF, fits, friction, dead time |
//! | [`design`] | the cascade design (chapter 4): prefilter, PI, P, feedforward, the robust rule |
//! | [`commission`] | the experiment: the stages on an axis under a safety supervisor, or from a recording |
//! | [`verdict`] | the one judgement of a result |
//! | [`record`] | the files a result is kept and handed on in: `commissioning.json`, `controller.toml`, firmware source |
//! | [`report`] | what a person reads: plot data, the report page, the comparison |
//! | [`study`] | the robustness study over seeded random axes |
//! | [`vibration`] | input shapers (Klipper's and model-based) and the vibration benchmark |
//!
//! [`lti`] is the frequency-domain toolkit used by `model`, `ident` and
//! `design`; [`io`] reads and writes files safely; [`units`] maps torque and
//! current units. The per-sample real-time parts live in the `no_std` crate
//! `beltune-rt`.
//!
//! Units are SI everywhere; the conventions (e.g. `d_m` in N s/m as a
//! translational equivalent, `i_t = r / i_g` in m) are those of docs/thesis-map.md.

pub mod axis;
pub mod commission;
pub mod design;
pub mod error;
pub mod health;
pub mod history;
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
pub mod vibration;

pub use error::{Error, Result};
