//! The measured records as the estimation core's records: which records and outputs an axis uses, the
//! columns it needs, and the nuisance terms per record (the parent module's doc).

use std::collections::BTreeSet;

use super::super::measured::{names_of, records_exciting, surface_moves, MeasuredError};
use crate::data::{self, Channel};
use crate::estimate::{Nuisance, Record};

/// The records of one axis ([`records_exciting`]).
pub(super) fn records_for(
    records: &[(String, data::FlightRecord)],
    longitudinal: bool,
) -> Vec<&(String, data::FlightRecord)> {
    records_exciting(records, longitudinal)
        .into_iter()
        .map(|i| &records[i])
        .collect()
}

/// The record's column, or a `MeasuredError::Record` naming it.
pub(super) fn need<'a>(
    name: &str,
    rec: &'a data::FlightRecord,
    column: &str,
    why: &str,
) -> Result<&'a [f64], MeasuredError> {
    rec.column(column).ok_or_else(|| MeasuredError::Record {
        file: name.to_string(),
        message: format!("no {column} column ({why})"),
    })
}

/// The control derivatives held at 0 because no record moves their surface (module doc); `controls` pairs
/// each control input with its derivatives.
pub(super) fn derivatives_of_still_surfaces(
    records: &[&(String, data::FlightRecord)],
    controls: &[(Channel, [&'static str; 3])],
) -> BTreeSet<&'static str> {
    let moves = |surface: Channel| {
        records
            .iter()
            .any(|(_, r)| r.column(surface).is_some_and(surface_moves))
    };
    controls
        .iter()
        .filter(|(surface, _)| !moves(*surface))
        .flat_map(|(_, derivatives)| *derivatives)
        .collect()
}

/// The outputs of an axis that every record carries, or an error naming the columns the axis could use.
pub(super) fn outputs_in_every_record<O: Copy>(
    all: &[O],
    column: fn(O) -> &'static str,
    records: &[&(String, data::FlightRecord)],
    axis: &str,
) -> Result<Vec<O>, MeasuredError> {
    let outputs: Vec<O> = all
        .iter()
        .copied()
        .filter(|&o| records.iter().all(|(_, r)| r.column(column(o)).is_some()))
        .collect();
    if outputs.is_empty() {
        return Err(MeasuredError::Record {
            file: names_of(records.iter().copied()),
            message: format!(
                "no {axis} output column ({}) in every record",
                all.iter()
                    .map(|&o| column(o))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        });
    }
    Ok(outputs)
}

/// One record of the core: the given inputs and initial state, the measured `outputs` columns of `raw`.
pub(super) fn core_record(
    name: &str,
    raw: &data::FlightRecord,
    inputs: Vec<Vec<f64>>,
    outputs: &[&str],
    initial_state: Vec<f64>,
) -> Result<Record, MeasuredError> {
    Ok(Record {
        name: name.to_string(),
        time_s: raw.time_s.clone(),
        inputs,
        outputs: outputs
            .iter()
            .map(|c| need(name, raw, c, "").map(<[f64]>::to_vec))
            .collect::<Result<_, _>>()?,
        initial_state,
    })
}

/// Nuisance terms (module doc): every record's four initial states, and an additive bias on each output
/// among `biased`.
pub(super) fn states_and_biases<O: PartialEq>(outputs: &[O], biased: &[O]) -> Nuisance {
    Nuisance {
        initial_state: (0..4).collect(),
        output_bias: (0..outputs.len())
            .filter(|&i| biased.contains(&outputs[i]))
            .collect(),
        ..Nuisance::default()
    }
}

/// Mean of `column` over every sample of the records that carry it (`None` when none does).
pub(super) fn mean_over_records(
    records: &[&(String, data::FlightRecord)],
    column: &str,
) -> Option<f64> {
    let values: Vec<f64> = records
        .iter()
        .filter_map(|(_, r)| r.column(column))
        .flat_map(|c| c.iter().copied())
        .filter(|v| v.is_finite())
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}
