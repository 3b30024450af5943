//! stride-wbc (work in progress)
