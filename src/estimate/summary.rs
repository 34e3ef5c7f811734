//! The estimate as a table for people and as JSON for programs (contract in `docs/estimate.md`).

use serde_json::{json, Map, Value};

use super::fit::{Estimate, ParameterEstimate};

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
