//! Shared test support (include with `mod support;`).

pub mod discrete_lp;
