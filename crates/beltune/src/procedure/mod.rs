//! The commissioning procedure (being written).
