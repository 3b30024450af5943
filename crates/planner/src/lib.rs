//! stride-planner (work in progress)
