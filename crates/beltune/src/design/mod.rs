//! Controller design of thesis chapter 4 (being written).
