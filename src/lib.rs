//! flightid — aircraft system identification coupled to the JSBSim flight dynamics model.
//!
//! Data flows one way: `sim`/`data` produce records → `ident` estimates models (built on `lti`
//! and `signal`) → comparison → `report`. The `cli` module only parses arguments and calls in.

pub mod aero;
pub mod aircraft;
pub mod campaign;
pub mod cli;
pub mod compare;
pub mod data;
pub mod diagnose;
pub mod estimate;
pub mod exit;
pub mod ident;
pub mod limits;
pub mod lti;
pub mod optimise;
pub mod paper;
pub mod report;
pub mod signal;
pub mod sim;
pub mod study;
pub mod text;
