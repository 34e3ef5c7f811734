//! The simulator: a trait, the JSBSim bridge (Python subprocess), and a linear-model stand-in.
