//! The result file of one campaign case and its identifications (written by [`super::run`], stored by
//! [`super::store`]).

use super::spec::CaseSpec;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One identification of a case's record.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Identification {
    /// Estimator.
    pub method: String,
    /// Output noise, deg (1 σ).
    pub noise_std_deg: f64,
    /// Noise seed (0 when noise-free).
    pub seed: u64,
    /// Named modal parameters (see [`crate::compare::modal_summary`]).
    pub modal: BTreeMap<String, f64>,
    /// Identified numerator, highest power first.
    pub num: Vec<f64>,
    /// Identified monic denominator.
    pub den: Vec<f64>,
    /// Leading numerator coefficient: the high-frequency gain, a control-derivative proxy
    /// (≈ Mδe for θ/δe, Lδa for φ/δa; Morelli & Klein 2016 §3.6), rad/s² per rad.
    pub leading_num: Option<f64>,
    /// Simulation fit on the (noisy) record, NRMSE %.
    pub fit_sim_percent: Option<f64>,
    /// Why the estimator failed (then the other fields are empty).
    pub error: Option<String>,
}

/// The result file of one case: the case itself, the trim, the identifications — or the error.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct CaseResult {
    /// The case.
    pub case: CaseSpec,
    /// Simulation and sampling rate of the record, Hz (0 in results written before it was recorded).
    #[serde(default)]
    pub rate_hz: f64,
    /// Record length, s.
    #[serde(default)]
    pub duration_s: f64,
    /// Maneuver start, s.
    #[serde(default)]
    pub start_s: f64,
    /// SHA-256 of the case's definition (see [`super::store::definition_sha256`]); empty in old results.
    #[serde(default)]
    pub definition_sha256: String,
    /// `ok` or `failed`.
    pub status: String,
    /// Why the case failed (trim, simulator).
    pub error: Option<String>,
    /// Trim angle of attack, rad.
    pub trim_alpha_rad: Option<f64>,
    /// Trim true airspeed, m/s.
    pub trim_airspeed_m_s: Option<f64>,
    /// Identifications (method × noise × seed).
    pub identifications: Vec<Identification>,
}
