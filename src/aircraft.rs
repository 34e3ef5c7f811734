//! Per-aircraft configuration read from `aircraft/NAME.toml`.
