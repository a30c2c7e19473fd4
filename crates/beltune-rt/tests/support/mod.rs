//! Shared by the integration tests; each test crate uses a part of it.
#![allow(dead_code)]

pub mod cases;
