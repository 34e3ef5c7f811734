//! The estimate as a report (`flightid estimate --report DIR`): per record and output the measured
//! and model outputs overlaid and the residuals, the parameter table, and the correlation matrix of
//! the free quantities.

use crate::report::{LinePlot, Report, Section, Series, Table};

use super::fit::Estimate;
use super::summary::{fit_list, HIGH_CORRELATION};

impl Estimate {
    /// The report (write it with [`crate::report::write_report_dir`], with [`Estimate::to_json`]).
    pub fn report(&self) -> Report {
        let mut sections = vec![self.parameter_section(), self.correlation_section()];
        for (r, rec) in self.records.iter().enumerate() {
            let mut plots = Vec::new();
            for (o, name) in self.outputs.iter().enumerate() {
                let overlay = LinePlot {
                    title: format!("{name}: measured and model ({})", rec.name),
                    x_label: "time, s".into(),
                    y_label: name.clone(),
                    series: vec![
                        Series::new("measured", rec.time_s.clone(), rec.measured[o].clone()),
                        Series::new(
                            format!("model ({})", self.method.name()),
                            rec.time_s.clone(),
                            rec.predicted[o].clone(),
                        ),
                    ],
                    log_x: false,
                };
                let residual: Vec<f64> = rec.measured[o]
                    .iter()
                    .zip(&rec.predicted[o])
                    .map(|(z, y)| z - y)
                    .collect();
                let residuals = LinePlot {
                    title: format!("{name}: residual z − ŷ ({})", rec.name),
                    x_label: "time, s".into(),
                    y_label: name.clone(),
                    series: vec![Series::new("residual", rec.time_s.clone(), residual)],
                    log_x: false,
                };
                plots.push((format!("record{r}_{name}"), overlay));
                plots.push((format!("record{r}_{name}_residual"), residuals));
            }
            sections.push(Section {
                heading: format!("Record {}", rec.name),
                paragraphs: vec![format!(
                    "{} samples; fit {}.",
                    rec.time_s.len(),
                    fit_list(&self.outputs, &rec.fit_percent)
                )],
                tables: Vec::new(),
                plots,
            });
        }
        Report {
            title: format!("Estimate ({})", self.method.name()),
            sections,
        }
    }

    fn parameter_section(&self) -> Section {
        let row = |label: &str, p: &super::ParameterEstimate| {
            vec![
                label.to_string(),
                format!("{:.6}", p.value),
                if p.fixed {
                    "fixed".into()
                } else {
                    format!("{:.4e}", p.std_error)
                },
                format!("{:.1}", p.t),
                format!("{:.1}", p.std_error_percent()),
            ]
        };
        let nf = self.free.len() - self.nuisance.len();
        let mut rows: Vec<Vec<String>> = self.parameters.iter().map(|p| row(&p.name, p)).collect();
        for (k, p) in self.nuisance.iter().enumerate() {
            rows.push(row(&self.free[nf + k], p));
        }
        Section {
            heading: "Parameters".into(),
            paragraphs: vec![
                format!(
                    "{} iterations, {} ({:?}), cost {:.6e}.",
                    self.iterations,
                    if self.converged {
                        "converged"
                    } else {
                        "not converged"
                    },
                    self.stop,
                    self.cost
                ),
                format!("Standard errors: {}.", self.covariance_method),
            ]
            .into_iter()
            .chain(self.warnings.iter().map(|w| format!("Warning: {w}")))
            .collect(),
            tables: vec![Table::new(
                "estimates",
                &["name", "value", "σ", "t", "σ %"],
                rows,
            )],
            plots: Vec::new(),
        }
    }

    fn correlation_section(&self) -> Section {
        let rows = self
            .free
            .iter()
            .zip(&self.correlation)
            .map(|(name, row)| {
                std::iter::once(name.clone())
                    .chain(row.iter().map(|c| format!("{c:+.2}")))
                    .collect()
            })
            .collect();
        let high = (0..self.free.len())
            .flat_map(|a| (a + 1..self.free.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| self.correlation[a][b].abs() > HIGH_CORRELATION)
            .map(|(a, b)| {
                format!(
                    "{} / {} ({:+.2})",
                    self.free[a], self.free[b], self.correlation[a][b]
                )
            })
            .collect::<Vec<_>>();
        Section {
            heading: "Correlation matrix".into(),
            paragraphs: vec![if high.is_empty() {
                format!("No pair above |{HIGH_CORRELATION}|.")
            } else {
                format!("Above |{HIGH_CORRELATION}|: {}.", high.join("; "))
            }],
            tables: vec![Table {
                caption: "correlation of the free quantities".into(),
                header: std::iter::once(String::new())
                    .chain(self.free.iter().cloned())
                    .collect(),
                rows,
            }],
            plots: Vec::new(),
        }
    }
}
