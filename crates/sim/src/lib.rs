//! stride-sim (work in progress)
