//! stride-model (work in progress)
