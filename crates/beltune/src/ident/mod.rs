//! Identification of thesis chapter 3 (being written).
