//! stride-simplified (work in progress)
