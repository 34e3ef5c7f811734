//! Linear time-invariant systems: transfer functions, state space, conversions, simulation.
