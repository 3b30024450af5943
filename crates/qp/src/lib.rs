//! stride-qp (work in progress)
