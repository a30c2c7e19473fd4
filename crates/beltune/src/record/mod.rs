//! The commissioning folder: what a run writes and what later runs, the
//! tuning page, `compare` and `export` read back.

/// Version of the record layout (`commissioning.json`, `controller.toml`, the
/// `identify --json` model). Files without `schema_version` are version 0 and
/// read with the old keys.
pub const SCHEMA_VERSION: u32 = 1;

pub mod controller;
pub mod folder;
pub mod model;
pub mod provenance;
