//! The commissioning folder: what a run writes and what later runs, the
//! tuning page, `compare` and `export` read back. One reader and one writer
//! per file:
//!
//! | file | what | module |
//! | --- | --- | --- |
//! | `commissioning.json` | every number of the run, the verdict, the log | [`commissioning`] |
//! | `controller.toml` | what a drive or firmware needs | [`controller`] |
//! | firmware source (Rust module, C header) | `controller.toml` as constants | [`export`] |
//! | `report.html` | what a person reads | [`crate::report`] |
//! | `health.json` | a health check (its own folder) | [`health`] |
//! | `frf.csv`, `loops.csv`, `moves.csv`, `excitation.csv`, `friction.csv` | the report's data | [`crate::report::data_files`] |
//!
//! [`model`] reads the identified model of `commissioning.json` (and of
//! `identify --json` or a hand-written TOML); [`folder`] says where a result
//! goes and writes its files as one set, all together or none;
//! [`provenance`] is the stamp of who wrote a file. A whole folder is read by
//! [`crate::report::folder::ResultFolder::read`].

/// Version of the record layout (`commissioning.json`, `controller.toml`, the
/// `identify --json` model). Files without `schema_version` are version 0 and
/// read with the old keys.
pub const SCHEMA_VERSION: u32 = 1;

/// Every number of a run.
pub const COMMISSIONING_FILE: &str = "commissioning.json";
/// The controller for the drive.
pub const CONTROLLER_FILE: &str = "controller.toml";
/// The report page.
pub const REPORT_FILE: &str = "report.html";

/// Every file a result set may hold (what a folder written before result sets
/// had manifests is known to hold of beltune's; everything else in it is the
/// user's).
pub const RESULT_FILE_NAMES: [&str; 8] = [
    COMMISSIONING_FILE,
    CONTROLLER_FILE,
    REPORT_FILE,
    crate::report::data_files::FRF_CSV,
    crate::report::data_files::LOOPS_CSV,
    crate::report::data_files::MOVES_CSV,
    crate::report::data_files::EXCITATION_CSV,
    crate::report::data_files::FRICTION_CSV,
];

pub mod commissioning;
pub mod controller;
pub mod export;
pub mod folder;
pub mod health;
pub mod model;
pub mod provenance;
