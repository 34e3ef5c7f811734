//! A continuous-time model the user writes in a TOML file (contract in `docs/estimate.md`):
//! states, inputs and outputs named by flight-data columns, parameters with start values,
//! right-hand sides as expressions ([`super::expr`]), optional observation equations and the
//! nuisance terms to estimate.

use std::path::Path;

use super::expr::{Expr, ExprError, Program, Slot};
use super::layout::Nuisance;
use super::model::{Parameter, Signature, StateModel};
use super::record::Record;
use crate::data::FlightRecord;

/// A problem in a model file (or between a model file and a record), with the file, line and name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}:{line}: {message}")]
pub struct ModelFileError {
    /// The model file.
    pub file: String,
    /// 1-based line (0 when the problem is not on one line).
    pub line: usize,
    /// The name involved.
    pub name: String,
    /// What is wrong.
    pub message: String,
}

/// A model read from a TOML file.
#[derive(Clone, Debug)]
pub struct UserModel {
    file: String,
    text: String,
    signature: Signature,
    /// Per state: its right-hand side, compiled.
    equations: Vec<Program>,
    /// Per output: its observation equation compiled, or the index of the state it equals.
    observations: Vec<Result<Program, usize>>,
    /// Every parameter (estimated ones first, then `[fixed]`), start values and bounds.
    pub parameters: Vec<Parameter>,
    /// Nuisance terms declared in `[nuisance]`.
    pub nuisance: Nuisance,
    /// Initial states estimated (`initial_state = "estimate"`) rather than measured.
    pub estimate_initial_state: bool,
    /// Parameters written `"auto"`: their start values come from the records
    /// ([`super::start_values`]).
    pub auto_start: Vec<usize>,
}

const TOP_KEYS: [&str; 9] = [
    "states",
    "inputs",
    "outputs",
    "parameters",
    "fixed",
    "bounds",
    "equations",
    "observations",
    "nuisance",
];

impl UserModel {
    /// Reads and checks a model file.
    pub fn load(path: &Path) -> Result<UserModel, ModelFileError> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| ModelFileError {
            file: file.clone(),
            line: 0,
            name: String::new(),
            message: format!("cannot read the model file: {e}"),
        })?;
        UserModel::parse(&text, &file)
    }

    /// Parses and checks model text (`file` names it in errors).
    pub fn parse(text: &str, file: &str) -> Result<UserModel, ModelFileError> {
        let err = |line: usize, name: &str, message: String| ModelFileError {
            file: file.to_string(),
            line,
            name: name.to_string(),
            message,
        };
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let line = e.span().map_or(0, |s| {
                text[..s.start.min(text.len())].lines().count().max(1)
            });
            err(line, "", format!("not valid TOML: {}", e.message()))
        })?;
        for key in table.keys() {
            if !TOP_KEYS.contains(&key.as_str()) {
                return Err(err(
                    key_line(text, None, key),
                    key,
                    format!(
                        "unknown key '{key}' (expected one of {})",
                        TOP_KEYS.join(", ")
                    ),
                ));
            }
        }
        let names = |key: &str| -> Result<Vec<String>, ModelFileError> {
            let not_a_list = || {
                err(
                    key_line(text, None, key),
                    key,
                    format!("'{key}' must be a list of column names"),
                )
            };
            match table.get(key) {
                None => Ok(Vec::new()),
                Some(toml::Value::Array(a)) => a
                    .iter()
                    .map(|v| v.as_str().map(String::from).ok_or_else(not_a_list))
                    .collect(),
                Some(_) => Err(not_a_list()),
            }
        };
        let states = names("states")?;
        let inputs = names("inputs")?;
        let outputs = names("outputs")?;
        if states.is_empty() || outputs.is_empty() {
            return Err(err(0, "", "a model needs 'states' and 'outputs'".into()));
        }
        let section = |name: &str| -> Result<Vec<(String, toml::Value)>, ModelFileError> {
            match table.get(name) {
                None => Ok(Vec::new()),
                Some(toml::Value::Table(t)) => {
                    Ok(t.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
                }
                Some(_) => Err(err(
                    key_line(text, None, name),
                    name,
                    format!("[{name}] must be a table"),
                )),
            }
        };
        let number = |sec: &str, k: &str, v: &toml::Value| {
            v.as_float()
                .or_else(|| v.as_integer().map(|i| i as f64))
                .ok_or_else(|| {
                    err(
                        key_line(text, Some(sec), k),
                        k,
                        if sec == "parameters" {
                            format!("{k} must be a number or \"auto\"")
                        } else {
                            format!("{k} must be a number")
                        },
                    )
                })
        };
        let mut parameters = Vec::new();
        let mut auto_start = Vec::new();
        for (k, v) in section("parameters")? {
            if v.as_str() == Some("auto") {
                auto_start.push(parameters.len());
                parameters.push(Parameter::free(k.clone(), 0.0));
                continue;
            }
            parameters.push(Parameter::free(k.clone(), number("parameters", &k, &v)?));
        }
        for (k, v) in section("fixed")? {
            parameters.push(Parameter::fixed(k.clone(), number("fixed", &k, &v)?));
        }
        for (k, v) in section("bounds")? {
            let line = key_line(text, Some("bounds"), &k);
            let Some(p) = parameters.iter_mut().find(|p| p.name == k) else {
                return Err(err(
                    line,
                    &k,
                    format!("bounds for '{k}', which is not a parameter"),
                ));
            };
            let pair: Option<Vec<f64>> = v.as_array().map(|a| {
                a.iter()
                    .filter_map(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                    .collect()
            });
            match pair.as_deref() {
                Some([lo, hi]) if lo <= hi => {
                    p.lower = *lo;
                    p.upper = *hi;
                }
                _ => {
                    return Err(err(
                        line,
                        &k,
                        format!("bounds of '{k}' must be [lower, upper]"),
                    ))
                }
            }
        }
        // every name once: states, inputs and parameters share one namespace
        let mut seen: Vec<&str> = Vec::new();
        for n in states
            .iter()
            .chain(&inputs)
            .chain(parameters.iter().map(|p| &p.name))
        {
            if seen.contains(&n.as_str()) && !outputs.contains(n) {
                return Err(err(
                    word_line(text, n),
                    n,
                    format!("'{n}' is declared twice"),
                ));
            }
            seen.push(n);
        }
        let resolve = |n: &str| -> Option<Slot> {
            if let Some(i) = states.iter().position(|s| s == n) {
                return Some(Slot::State(i));
            }
            if let Some(i) = inputs.iter().position(|s| s == n) {
                return Some(Slot::Input(i));
            }
            parameters.iter().position(|p| p.name == n).map(Slot::Param)
        };
        let compile = |sec: &str, k: &str, v: &toml::Value| -> Result<Expr, ModelFileError> {
            let line = key_line(text, Some(sec), k);
            let Some(src) = v.as_str() else {
                return Err(err(
                    line,
                    k,
                    format!("the equation of '{k}' must be a string"),
                ));
            };
            Expr::parse(src, &resolve).map_err(|e| {
                let name = match &e {
                    ExprError::UnknownName(n) => n.clone(),
                    ExprError::Arity { name, .. } => name.clone(),
                    ExprError::Syntax(_) => k.to_string(),
                };
                err(line, &name, format!("in the equation of '{k}': {e}"))
            })
        };
        // Section `sec`, every key of which names one of `known`; `unknown(k)` says what a stray key would have
        // been.
        let keyed_section = |sec: &str,
                             known: &[String],
                             unknown: &dyn Fn(&str) -> String|
         -> Result<Vec<(String, toml::Value)>, ModelFileError> {
            let entries = section(sec)?;
            match entries.iter().find(|(k, _)| !known.contains(k)) {
                Some((k, _)) => Err(err(key_line(text, Some(sec), k), k, unknown(k))),
                None => Ok(entries),
            }
        };
        let eq_section = keyed_section("equations", &states, &|k| {
            format!("equation for '{k}', which is not a state")
        })?;
        let mut equations = Vec::new();
        for s in &states {
            let Some((_, v)) = eq_section.iter().find(|(k, _)| k == s) else {
                return Err(err(
                    word_line(text, s),
                    s,
                    format!("state '{s}' has no equation in [equations]"),
                ));
            };
            equations.push(compile("equations", s, v)?.compile());
        }
        let obs_section = keyed_section("observations", &outputs, &|k| {
            format!("observation of '{k}', which is not an output")
        })?;
        let mut observations = Vec::new();
        for o in &outputs {
            match obs_section.iter().find(|(k, _)| k == o) {
                Some((_, v)) => observations.push(Ok(compile("observations", o, v)?.compile())),
                None => match states.iter().position(|s| s == o) {
                    Some(i) => observations.push(Err(i)),
                    None => {
                        return Err(err(
                            word_line(text, o),
                            o,
                            format!("output '{o}' is neither a state nor in [observations]"),
                        ))
                    }
                },
            }
        }
        // [nuisance]
        let mut nuisance = Nuisance::default();
        let mut estimate_initial_state = false;
        for (k, v) in section("nuisance")? {
            let line = key_line(text, Some("nuisance"), &k);
            let list = |among: &[String], what: &str| -> Result<Vec<usize>, ModelFileError> {
                let Some(a) = v.as_array() else {
                    return Err(err(
                        line,
                        &k,
                        format!("'{k}' must be a list of {what} names"),
                    ));
                };
                a.iter()
                    .map(|x| {
                        let n = x.as_str().unwrap_or_default();
                        among.iter().position(|s| s == n).ok_or_else(|| {
                            err(
                                line,
                                n,
                                format!("'{n}' in '{k}' is not one of the model's {what}s"),
                            )
                        })
                    })
                    .collect()
            };
            match k.as_str() {
                "initial_state" => match v.as_str() {
                    Some("estimate") => {
                        estimate_initial_state = true;
                        nuisance.initial_state = (0..states.len()).collect();
                    }
                    Some("measured") => {}
                    _ => match v.as_array() {
                        Some(_) => {
                            estimate_initial_state = true;
                            nuisance.initial_state = list(&states, "state")?;
                        }
                        None => {
                            return Err(err(line, &k, "initial_state must be \"estimate\", \"measured\" or a list of states".into()))
                        }
                    },
                },
                "output_bias" => nuisance.output_bias = list(&outputs, "output")?,
                "input_bias" => nuisance.input_bias = list(&inputs, "input")?,
                "input_skew" => nuisance.input_skew = list(&inputs, "input")?,
                "process_noise" => nuisance.process_noise = Some(list(&states, "state")?),
                _ => {
                    return Err(err(
                        line,
                        &k,
                        format!("unknown nuisance term '{k}' (initial_state, output_bias, input_bias, input_skew, process_noise)"),
                    ))
                }
            }
        }
        Ok(UserModel {
            file: file.to_string(),
            text: text.to_string(),
            signature: Signature {
                parameters: parameters.iter().map(|p| p.name.clone()).collect(),
                states,
                inputs,
                outputs,
            },
            equations,
            observations,
            parameters,
            nuisance,
            estimate_initial_state,
            auto_start,
        })
    }

    /// The record with the model's inputs and its states as the outputs (for start values from
    /// the records: every state must be a column).
    pub fn state_record(&self, rec: &FlightRecord, name: &str) -> Result<Record, ModelFileError> {
        let outputs = self
            .signature
            .states
            .iter()
            .map(|s| {
                rec.column(s).map(<[f64]>::to_vec).ok_or_else(|| ModelFileError {
                    file: self.file.clone(),
                    line: word_line(&self.text, s),
                    name: s.clone(),
                    message: format!(
                        "start values \"auto\" need every state measured: '{s}' is not a column of {name}"
                    ),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut record = self.record(rec, name)?;
        record.initial_state = outputs.iter().map(|c| c[0]).collect();
        record.outputs = outputs;
        Ok(record)
    }

    /// The record's columns in this model's terms. A missing input or output column, or a
    /// missing state column whose initial value is not estimated, is an error naming the model
    /// file's line that asks for it.
    pub fn record(&self, rec: &FlightRecord, name: &str) -> Result<Record, ModelFileError> {
        let missing = |col: &str, what: &str| ModelFileError {
            file: self.file.clone(),
            line: word_line(&self.text, col),
            name: col.to_string(),
            message: format!("{what} '{col}' is not a column of {name}"),
        };
        let column = |col: &str, what: &str| {
            rec.column(col)
                .map(<[f64]>::to_vec)
                .ok_or_else(|| missing(col, what))
        };
        let columns = |names: &[String], what: &str| {
            names
                .iter()
                .map(|c| column(c, what))
                .collect::<Result<Vec<_>, _>>()
        };
        let inputs = columns(&self.signature.inputs, "input")?;
        let outputs = columns(&self.signature.outputs, "output")?;
        let mut initial_state = Vec::new();
        for (i, s) in self.signature.states.iter().enumerate() {
            match rec.column(s) {
                Some(c) if !c.is_empty() => initial_state.push(c[0]),
                _ if self.nuisance.initial_state.contains(&i) => initial_state.push(0.0),
                _ => return Err(missing(s, "state (initial value measured)")),
            }
        }
        Ok(Record {
            name: name.to_string(),
            time_s: rec.time_s.clone(),
            inputs,
            outputs,
            initial_state,
        })
    }
}

/// Line (1-based) of `key = …` in `[section]` (None: before any section); 0 if not found.
fn key_line(text: &str, section: Option<&str>, key: &str) -> usize {
    let mut current: Option<String> = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            current = Some(t.trim_matches(|c| c == '[' || c == ']').trim().to_string());
            continue;
        }
        let k = t.split('=').next().unwrap_or("").trim().trim_matches('"');
        if t.contains('=') && k == key && current.as_deref() == section {
            return i + 1;
        }
    }
    word_line(text, key)
}

/// Line (1-based) of the first mention of `word` as a whole word; 0 if none.
fn word_line(text: &str, word: &str) -> usize {
    let is_word = |c: char| c.is_alphanumeric() || c == '_';
    for (i, line) in text.lines().enumerate() {
        let code = line.split('#').next().unwrap_or("");
        for (pos, _) in code.match_indices(word) {
            let before = code[..pos].chars().next_back();
            let after = code[pos + word.len()..].chars().next();
            if !before.is_some_and(is_word) && !after.is_some_and(is_word) {
                return i + 1;
            }
        }
    }
    0
}

impl StateModel for UserModel {
    fn signature(&self) -> &Signature {
        &self.signature
    }

    fn derivatives(&self, theta: &[f64], x: &[f64], u: &[f64], dx: &mut [f64]) {
        for (d, e) in dx.iter_mut().zip(&self.equations) {
            *d = e.eval(theta, x, u);
        }
    }

    fn outputs(&self, theta: &[f64], x: &[f64], u: &[f64], y: &mut [f64]) {
        for (yo, obs) in y.iter_mut().zip(&self.observations) {
            *yo = match obs {
                Ok(e) => e.eval(theta, x, u),
                Err(i) => x[*i],
            };
        }
    }
}

crate::model_from_state_model!(UserModel);
