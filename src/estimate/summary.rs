//! The estimate as a table for people and as JSON for programs (contract in `docs/estimate.md`).

use serde_json::{json, Map, Value};

use super::fit::{Estimate, ParameterEstimate};
use super::record::InputHold;
use super::subspace::SubspaceModel;

/// Correlations above this magnitude are flagged in the table.
pub const HIGH_CORRELATION: f64 = 0.9;

impl Estimate {
    /// Parameter table: value, σ, t, σ %, and the parameters each one correlates with above 0.9.
    pub fn table(&self) -> String {
        let w = self
            .free
            .iter()
            .chain(self.parameters.iter().map(|p| &p.name))
            .map(|n| n.chars().count())
            .max()
            .unwrap_or(0)
            .max(18);
        let mut out = format!(
            "{:<w$} {:>13} {:>11} {:>8} {:>8}  {}\n",
            "parameter", "value", "std_error", "t", "σ %", "|corr| > 0.9"
        );
        let row = |p: &ParameterEstimate, label: String, out: &mut String| {
            let flags: Vec<String> = match self.free.iter().position(|n| *n == label) {
                Some(a) => self
                    .free
                    .iter()
                    .enumerate()
                    .filter(|(b, _)| *b != a && self.correlation[a][*b].abs() > HIGH_CORRELATION)
                    .map(|(b, n)| format!("{n} ({:+.2})", self.correlation[a][b]))
                    .collect(),
                None => Vec::new(),
            };
            if p.fixed {
                out.push_str(&format!(
                    "{label:<w$} {:>13.6} {:>11} {:>8} {:>8}  fixed\n",
                    p.value, "-", "-", "-"
                ));
            } else {
                out.push_str(&format!(
                    "{label:<w$} {:>13.6} {:>11.4e} {:>8.1} {:>8.1}  {}{}\n",
                    p.value,
                    p.std_error,
                    p.t,
                    p.std_error_percent(),
                    flags.join(", "),
                    if p.at_bound { " [at bound]" } else { "" }
                ));
            }
        };
        for p in &self.parameters {
            row(p, p.name.clone(), &mut out);
        }
        let nf = self.free.len() - self.nuisance.len();
        for (k, p) in self.nuisance.iter().enumerate() {
            row(p, self.free[nf + k].clone(), &mut out);
        }
        out.push_str(&format!(
            "\n{} records, {} iterations, {} ({:?}), cost {:.6e}, {:.3} s\nfit %:",
            self.records.len(),
            self.iterations,
            if self.converged {
                "converged"
            } else {
                "NOT converged"
            },
            self.stop,
            self.cost,
            self.wall_s
        ));
        for (o, name) in self.outputs.iter().enumerate() {
            out.push_str(&format!(" {name} {:.1}", self.fit_percent(o)));
        }
        out.push_str(&format!("\nstandard errors: {}\n", self.covariance_method));
        let process: Vec<String> = self
            .nuisance
            .iter()
            .filter(|p| p.kind == Some(super::NuisanceKind::ProcessNoise))
            .map(|p| format!("{} {:.4e}", p.name, p.value.max(0.0).sqrt()))
            .collect();
        if !process.is_empty() {
            out.push_str(&format!(
                "filter error: process_noise rows are q = F_ii² (R: innovation covariance); F_ii: {}\n",
                process.join(", ")
            ));
        }
        for w in &self.warnings {
            out.push_str(&format!("warning: {w}\n"));
        }
        out
    }

    /// JSON: `parameters`, `correlation` (with `correlation_names`), `nuisance`, `fit_percent`,
    /// `residual_covariance`, `iterations`, `converged`, `cost`, `wall_s`, and more.
    pub fn to_json(&self) -> Value {
        let entry = |p: &ParameterEstimate| {
            json!({"value": p.value, "std_error": p.std_error, "std_error_white": p.std_error_white,
                   "t": p.t, "fixed": p.fixed, "at_bound": p.at_bound})
        };
        let mut parameters = Map::new();
        for p in &self.parameters {
            parameters.insert(p.name.clone(), entry(p));
        }
        let nf = self.free.len() - self.nuisance.len();
        let mut nuisance = Map::new();
        for (k, p) in self.nuisance.iter().enumerate() {
            let mut e = entry(p);
            e["kind"] = json!(p.kind);
            e["target"] = json!(p.name);
            if let Some(r) = &p.record {
                e["record"] = json!(r);
            }
            nuisance.insert(self.free[nf + k].clone(), e);
        }
        let mut fit = Map::new();
        for (o, name) in self.outputs.iter().enumerate() {
            fit.insert(name.clone(), json!(self.fit_percent(o)));
        }
        let records: Vec<Value> = self
            .records
            .iter()
            .map(|r| {
                let f: Map<String, Value> = self
                    .outputs
                    .iter()
                    .zip(&r.fit_percent)
                    .map(|(n, v)| (n.clone(), json!(v)))
                    .collect();
                json!({"name": r.name, "samples": r.time_s.len(), "fit_percent": f})
            })
            .collect();
        json!({
            "method": self.method.name(),
            "parameters": parameters,
            "correlation_names": self.free,
            "correlation": self.correlation,
            "nuisance": nuisance,
            "fit_percent": fit,
            "records": records,
            "outputs": self.outputs,
            "residual_covariance": self.residual_covariance,
            "iterations": self.iterations,
            "converged": self.converged,
            "stop": self.stop,
            "cost": self.cost,
            "cost_history": self.cost_history,
            "wall_s": self.wall_s,
            "std_error_method": self.covariance_method,
            "warnings": self.warnings,
        })
    }
}

impl SubspaceModel {
    /// The model for people: order and singular values, the continuous-time matrices, the modes
    /// and the fit.
    pub fn table(&self) -> String {
        let how = if self.order_from_data {
            "the largest singular-value gap"
        } else {
            "given"
        };
        let hold = match self.hold {
            InputHold::Linear => "linear interpolation",
            InputHold::Zoh => "zero-order hold",
        };
        let mut out = format!(
            "subspace identification (PO-MOESP): order {} ({how}), {} block rows, {:.3} s\n",
            self.order, self.horizon, self.wall_s
        );
        let shown: Vec<String> = self
            .singular_values
            .iter()
            .take(12)
            .map(|v| format!("{v:.4}"))
            .collect();
        out.push_str(&format!("singular values: {}\n", shown.join(" ")));
        let states = self.state_labels();
        out.push_str(&format!(
            "continuous-time model (inputs between samples by {hold}); states: {}\n",
            match &self.state_names {
                Some(_) => states.join(", "),
                None => format!("{} internal states (no measured basis)", self.order),
            }
        ));
        let cont = &self.continuous;
        out.push_str(&matrix_block("A", &states, &states, &cont.a));
        out.push_str(&matrix_block("B", &states, &self.inputs, &cont.b));
        out.push_str(&matrix_block("C", &self.outputs, &states, &cont.c));
        out.push_str(&matrix_block("D", &self.outputs, &self.inputs, &cont.d));
        out.push_str("modes:\n");
        for mode in &self.modes {
            let pole = if mode.pole.im.abs() > 0.0 {
                format!("{:.4} ± {:.4}i", mode.pole.re, mode.pole.im.abs())
            } else {
                format!("{:.4}", mode.pole.re)
            };
            out.push_str(&format!(
                "  pole {pole:<22} ω_n {:>8.4} rad/s  ζ {:>7.4}\n",
                mode.omega_n_rad_s, mode.zeta
            ));
        }
        out.push_str(&format!(
            "fit: {}\n",
            fit_list(&self.outputs, &self.fit_percent)
        ));
        out
    }

    fn state_labels(&self) -> Vec<String> {
        match &self.state_names {
            Some(names) => names.clone(),
            None => (1..=self.order).map(|i| format!("x{i}")).collect(),
        }
    }

    /// The model for programs (`docs/estimate.md`).
    pub fn to_json(&self) -> Value {
        let rows = |m: &faer::Mat<f64>| -> Vec<Vec<f64>> {
            (0..m.nrows())
                .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
                .collect()
        };
        let per_output = |values: &[f64]| -> Map<String, Value> {
            self.outputs
                .iter()
                .zip(values)
                .map(|(n, v)| (n.clone(), json!(v)))
                .collect()
        };
        json!({
            "method": "n4sid",
            "order": self.order,
            "order_from_data": self.order_from_data,
            "horizon": self.horizon,
            "singular_values": self.singular_values,
            "states": self.state_names,
            "inputs": self.inputs,
            "outputs": self.outputs,
            "input_hold": self.hold,
            "a": rows(&self.continuous.a),
            "b": rows(&self.continuous.b),
            "c": rows(&self.continuous.c),
            "d": rows(&self.continuous.d),
            "discrete": {
                "dt_s": self.discrete.dt_s,
                "a": rows(&self.discrete.a),
                "b": rows(&self.discrete.b),
                "c": rows(&self.discrete.c),
                "d": rows(&self.discrete.d),
            },
            "modes": self.modes,
            "fit_percent": per_output(&self.fit_percent),
            "records": self.records.iter().map(|r| json!({
                "name": r.name,
                "fit_percent": per_output(&r.fit_percent),
            })).collect::<Vec<_>>(),
            "wall_s": self.wall_s,
        })
    }
}

/// `name` as a labelled matrix, one row per line.
fn matrix_block(name: &str, rows: &[String], cols: &[String], m: &faer::Mat<f64>) -> String {
    let w = rows
        .iter()
        .map(|r| r.chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let mut out = format!("{name:<w$}");
    for c in cols {
        out.push_str(&format!(" {c:>14}"));
    }
    out.push('\n');
    for (i, r) in rows.iter().enumerate() {
        out.push_str(&format!("{r:<w$}"));
        for j in 0..cols.len() {
            out.push_str(&format!(" {:>14.6}", m[(i, j)]));
        }
        out.push('\n');
    }
    out
}

/// Fit percent per output as `name 97.3 %`, comma-separated.
pub(super) fn fit_list(outputs: &[String], fit_percent: &[f64]) -> String {
    let fit: Vec<String> = outputs
        .iter()
        .zip(fit_percent)
        .map(|(n, f)| format!("{n} {f:.1} %"))
        .collect();
    fit.join(", ")
}
