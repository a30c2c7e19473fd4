//! Time-domain simulation of an axis (being written).
