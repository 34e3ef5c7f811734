//! From the solution to the [`Estimate`]: Cramér–Rao bounds corrected for coloured residuals (Morelli & Klein
//! 1994), correlations, per-record fits, names of the nuisance terms.

use super::*;

/// diag(K C) at least this is the filter error method's bound (`fem` module doc) for the warning of
/// [`Problem::gain_on_bound`].
const GAIN_ON_BOUND: f64 = 0.99;

impl Problem<'_> {
    /// Filter error: a warning when the gain at φ sits on its bound diag(K C) ≤ 1 on some record. The innovation
    /// covariance R = C P Cᵀ + G Gᵀ then leaves no room for measurement noise on an output that reads a state
    /// the process noise drives: the records carry next to none there (a noise-free simulation, a channel
    /// computed from the others), the fit is pinned to the constraint rather than led by the likelihood, and
    /// its estimates are unreliable. On pa28 records through a vertical gust with noise-free sensors filter
    /// error put C_Lα, C_mα and C_mδe 22–39 % off where equation error was within 1.6 %; with the logger's
    /// sensor noise on the same gust, within 3.1 %.
    fn gain_on_bound(&self, phi: &[f64]) -> Option<String> {
        let (r, kc) = (0..self.records.len())
            .filter_map(|r| self.gain(phi, r).ok().map(|g| (r, g.kc_max)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        (kc >= GAIN_ON_BOUND).then(|| {
            format!(
                "the filter's gain is on its bound (diag(K C) up to {kc:.3} on {}): an output reads a state the \
                 process noise drives with next to no measurement noise, and filter error's estimates are then \
                 held by the constraint, not led by the likelihood; compare output error or equation error",
                self.records[r].name
            )
        })
    }

    /// Covariance, correlation, per-record fits and the named results.
    pub(super) fn summarise(&self, sol: Solution, method: Method, started: Instant) -> Estimate {
        let layout = &self.layout;
        let p = layout.len();
        let sig = self.model.signature();
        let res = self.residuals(&sol.predictions);
        let mut warnings = Vec::new();
        let names: Vec<String> = (0..p).map(|j| self.free_name(j)).collect();
        let (cov_white, cov) = match self.jacobian(&sol.phi, &sol.predictions, true) {
            Ok(cols) => {
                let (mut white, mut coloured) =
                    self.covariances(&cols, &res, &sol.noise, &names, &mut warnings);
                let minv = white.clone();
                let covs = [&mut white, &mut coloured];
                self.add_considered(&sol, &cols, &minv, covs, &mut warnings);
                (white, coloured)
            }
            Err(e) => {
                warnings.push(format!(
                    "no standard errors: a perturbed simulation failed ({e})"
                ));
                (vec![0.0; p * p], vec![0.0; p * p])
            }
        };
        let sd = |c: &[f64], j: usize| c[j * p + j].max(0.0).sqrt();
        let estimate = |j: usize, name: String, kind, record| {
            let value = sol.phi[j];
            let std_error = sd(&cov, j);
            let at_bound = value <= layout.lower[j] || value >= layout.upper[j];
            ParameterEstimate {
                name,
                kind,
                record,
                value,
                std_error,
                std_error_white: sd(&cov_white, j),
                t: if std_error > 0.0 {
                    value.abs() / std_error
                } else {
                    0.0
                },
                fixed: false,
                at_bound,
            }
        };
        let theta = layout.theta(&sol.phi);
        let parameters: Vec<ParameterEstimate> = sig
            .parameters
            .iter()
            .enumerate()
            .map(|(i, name)| match layout.free.iter().position(|&f| f == i) {
                Some(j) => estimate(j, name.clone(), None, None),
                None => ParameterEstimate {
                    name: name.clone(),
                    kind: None,
                    record: None,
                    value: theta[i],
                    std_error: 0.0,
                    std_error_white: 0.0,
                    t: 0.0,
                    fixed: true,
                    at_bound: false,
                },
            })
            .collect();
        let nf = layout.free.len();
        let nuisance: Vec<ParameterEstimate> = layout
            .slots
            .iter()
            .enumerate()
            .map(|(k, s)| {
                estimate(
                    nf + k,
                    s.target.clone(),
                    Some(s.kind),
                    s.record.map(|r| self.records[r].name.clone()),
                )
            })
            .collect();
        // a process-noise variance at 0 is the output-error answer, not a bound hit
        let noteworthy = |p: &&ParameterEstimate| {
            p.at_bound && !(p.kind == Some(NuisanceKind::ProcessNoise) && p.value == 0.0)
        };
        for pe in parameters.iter().chain(&nuisance).filter(noteworthy) {
            warnings.push(format!("{} ended on a bound ({})", pe.name, pe.value));
        }
        if method == Method::Fem {
            warnings.extend(self.gain_on_bound(&sol.phi));
        }
        let correlation: Vec<Vec<f64>> = (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| {
                        let d = sd(&cov, a) * sd(&cov, b);
                        if d > 0.0 {
                            (cov[a * p + b] / d).clamp(-1.0, 1.0)
                        } else if a == b {
                            1.0
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        let ny = sig.outputs.len();
        let residual_covariance = (0..ny)
            .map(|a| {
                (0..ny)
                    .map(|b| if a == b { sol.noise[a] } else { 0.0 })
                    .collect()
            })
            .collect();
        let records = self
            .records
            .iter()
            .zip(&sol.predictions)
            .map(|(rec, pred)| RecordFit {
                name: rec.name.clone(),
                time_s: rec.time_s.clone(),
                measured: rec.outputs.clone(),
                predicted: pred.clone(),
                fit_percent: rec
                    .outputs
                    .iter()
                    .zip(pred)
                    .map(|(z, y)| fit_percent(z, y))
                    .collect(),
            })
            .collect();
        Estimate {
            method,
            outputs: sig.outputs.clone(),
            parameters,
            nuisance,
            free: names,
            covariance: (0..p).map(|a| cov[a * p..(a + 1) * p].to_vec()).collect(),
            correlation,
            residual_covariance,
            records,
            iterations: sol.iterations,
            converged: sol.stop == StopReason::Converged,
            stop: sol.stop,
            cost: self.cost(&res, &sol.noise),
            cost_history: sol.cost_history,
            wall_s: started.elapsed().as_secs_f64(),
            covariance_method: COVARIANCE_METHOD,
            warnings,
            considered: layout
                .consider
                .iter()
                .map(|&(i, sd)| (sig.parameters[i].clone(), sd))
                .collect(),
        }
    }

    /// Name of φ entry `j`: the parameter, or `kind:target@record` for a nuisance term.
    pub(super) fn free_name(&self, j: usize) -> String {
        match self.layout.slot(j) {
            None => self.model.signature().parameters[self.layout.free[j]].clone(),
            Some(s) => {
                let kind = match s.kind {
                    NuisanceKind::InitialState => "x0",
                    NuisanceKind::OutputBias => "bias",
                    NuisanceKind::InputBias => "input_bias",
                    NuisanceKind::InputSkew => "skew",
                    NuisanceKind::ProcessNoise => "process_noise",
                };
                match s.record {
                    Some(r) => format!("{kind}:{}@{}", s.target, self.records[r].name),
                    None => format!("{kind}:{}", s.target),
                }
            }
        }
    }

    /// Adds the held parameters' uncertainty to the covariances `covs` ([`Parameter::considered`]): for each,
    /// its central-difference sensitivity column s_c at the estimate, d = −M⁻¹ SᵀR⁻¹ s_c (M⁻¹ = `minv`, the
    /// white-residual inverse information), and P += σ² d dᵀ.
    fn add_considered(
        &self,
        sol: &Solution,
        cols: &[Vec<f64>],
        minv: &[f64],
        mut covs: [&mut Vec<f64>; 2],
        warnings: &mut Vec<String>,
    ) {
        if self.layout.consider.is_empty() {
            return;
        }
        let p = cols.len();
        let res = self.residuals(&sol.predictions);
        let (x, _) = self.weighted(cols, &res, &sol.noise);
        let theta = self.layout.theta(&sol.phi);
        for &(i, sd) in &self.layout.consider {
            let name = &self.model.signature().parameters[i];
            let h = 1e-4 * theta[i].abs().max(sd);
            let at = |delta: f64| {
                let mut t = theta.clone();
                t[i] += delta;
                (0..self.records.len())
                    .map(|r| self.predict_at(&sol.phi, &t, r))
                    .collect::<Result<Vec<_>, _>>()
            };
            let (plus, minus) = match (at(h), at(-h)) {
                (Ok(a), Ok(b)) => (a, b),
                (Err(e), _) | (_, Err(e)) => {
                    warnings.push(format!(
                        "the uncertainty of the held {name} is not carried into the standard errors: a \
                         perturbed simulation failed ({e})"
                    ));
                    continue;
                }
            };
            let column: Vec<f64> = plus
                .iter()
                .zip(&minus)
                .flat_map(|(a, b)| {
                    a.iter()
                        .zip(b)
                        .flat_map(|(ao, bo)| ao.iter().zip(bo).map(|(u, v)| (u - v) / (2.0 * h)))
                        .collect::<Vec<f64>>()
                })
                .collect();
            let (xc, _) = self.weighted(&[column], &res, &sol.noise);
            let xtc: Vec<f64> = (0..p)
                .map(|j| (0..x.nrows()).map(|k| x[(k, j)] * xc[(k, 0)]).sum())
                .collect();
            let d: Vec<f64> = (0..p)
                .map(|a| -(0..p).map(|b| minv[a * p + b] * xtc[b]).sum::<f64>())
                .collect();
            for cov in covs.iter_mut() {
                for a in 0..p {
                    for b in 0..p {
                        cov[a * p + b] += sd * sd * d[a] * d[b];
                    }
                }
            }
        }
    }

    /// White and coloured-residual covariances (row-major p × p) from the sensitivity columns.
    pub(super) fn covariances(
        &self,
        cols: &[Vec<f64>],
        res: &Predictions,
        noise: &[f64],
        names: &[String],
        warnings: &mut Vec<String>,
    ) -> (Vec<f64>, Vec<f64>) {
        let p = cols.len();
        let (x, e) = self.weighted(cols, res, noise);
        let m: Mat<f64> = x.transpose() * &x;
        let minv = pseudo_inverse(&m, names, warnings);
        // W = Σ_records Σ_ij x_iᵀ R_vv(i−j) x_j over each record's weighted rows, R_vv the outputs'
        // whole correlation matrix (records mutually uncorrelated)
        let off = self.offsets();
        let mut w = vec![0.0; p * p];
        for (r, rec) in self.records.iter().enumerate() {
            let n = rec.len();
            let rows = |o: usize| off[r] + o * n..off[r] + (o + 1) * n;
            let blocks: Vec<Vec<Vec<f64>>> = (0..noise.len())
                .map(|o| {
                    (0..p)
                        .map(|j| rows(o).map(|k| x[(k, j)]).collect())
                        .collect()
                })
                .collect();
            let res_refs: Vec<&[f64]> = (0..noise.len()).map(|o| &e[rows(o)]).collect();
            let wr = cross_lag_weighted_products(&blocks, &res_refs);
            for (acc, v) in w.iter_mut().zip(&wr) {
                *acc += v;
            }
        }
        let coloured = sandwich(&minv, &w, p);
        (minv, coloured)
    }
}

/// Inverse of the symmetric information matrix by eigendecomposition; eigenvalues below 1e-12 of
/// the largest (an unidentifiable direction) are dropped and the parameters that dominate that
/// direction named in a warning.
fn pseudo_inverse(m: &Mat<f64>, names: &[String], warnings: &mut Vec<String>) -> Vec<f64> {
    let p = m.nrows();
    // scale to unit diagonal first so the threshold is independent of parameter units
    let d: Vec<f64> = (0..p)
        .map(|j| m[(j, j)].max(f64::MIN_POSITIVE).sqrt())
        .collect();
    let scaled = Mat::from_fn(p, p, |a, b| m[(a, b)] / (d[a] * d[b]));
    let mut inv = vec![0.0; p * p];
    let Ok(evd) = scaled.self_adjoint_eigen(Side::Lower) else {
        warnings.push("the information matrix could not be decomposed: no standard errors".into());
        return inv;
    };
    let (u, s) = (evd.U(), evd.S().column_vector());
    let largest = (0..p).map(|i| s[i]).fold(0.0_f64, f64::max);
    for i in 0..p {
        if s[i] <= 1e-12 * largest {
            let j = (0..p)
                .max_by(|&a, &b| u[(a, i)].abs().total_cmp(&u[(b, i)].abs()))
                .unwrap_or(0);
            warnings.push(format!(
                "the records do not determine {} (a combination led by it has no information)",
                names[j]
            ));
            continue;
        }
        for a in 0..p {
            for b in 0..p {
                inv[a * p + b] += u[(a, i)] * u[(b, i)] / s[i];
            }
        }
    }
    for a in 0..p {
        for b in 0..p {
            inv[a * p + b] /= d[a] * d[b];
        }
    }
    inv
}
