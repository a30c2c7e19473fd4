//! Shared test support (include with `mod support;`); each test file uses a
//! part of it.
#![allow(dead_code)]

pub mod cases;
pub mod discrete_lp;
