//! A model-structure screen on the equation-error regressions: does what the linear model leaves of a
//! coefficient follow a nonlinear function of a state or a control?
//!
//! The built-in models are linear in α, β and the surfaces (a Taylor series to first order, Klein & Morelli
//! ch. 3). Where the aircraft is not, over the range a record flies, every method still returns numbers: the
//! slopes over that range, bent by the part of the nonlinearity that correlates with the other regressors.
//! Klein & Morelli §5.4 (model structure determination) admits a term on the evidence of the data; this screen
//! does the first step of their stepwise regression for one family of candidates and reports, not adopts: for
//! each coefficient regression (C_L, C_m, C_Y, C_l, C_n over all records stacked) and each candidate
//!
//! - (x − x̄)² for x = α, δe (curvature about the records' mean),
//! - x² and |x| for x = β, δa, δr (a symmetric aircraft's coefficients are odd in these about zero; an even
//!   part is a nonlinearity or an asymmetry),
//! - β (α − ᾱ) in C_Y, C_l and C_n when every record has α (a dihedral effect or a fin that changes with
//!   the angle of attack, as lift and the wing's wake change),
//!
//! the regression is repeated with the candidate added. A candidate is reported when it removes at least
//! [`MIN_SHARE`] of the linear model's residual sum of squares and its coefficient stands at least
//! [`MIN_T`] coloured-residual standard errors from zero (the standard error of [`lesq`], Morelli & Klein's
//! correction, because equation-error residuals are coloured and the white-noise F-test would pass almost
//! anything on thousands of samples). Per coefficient only the candidate that removes most is reported.

use std::collections::BTreeMap;

use serde::Serialize;

use super::super::regression::{lesq, RegressionResult};

/// Least share of the linear model's residual sum of squares a candidate must remove to be reported.
pub const MIN_SHARE: f64 = 0.10;

/// Least |t| of the candidate's coefficient (coloured-residual standard error).
pub const MIN_T: f64 = 8.0;

/// A nonlinear term the residual of a coefficient's linear regression follows.
#[derive(Debug, Clone, Serialize)]
pub struct Nonlinearity {
    /// The coefficient: `Cm`, `CL`, `Cl`, `Cn`, `CY`.
    pub coefficient: String,
    /// The linear term whose variable it is a function of (`Cl_beta`).
    pub of: String,
    /// The candidate, as written in the note (`|β|`, `(α − ᾱ)²`).
    pub term: String,
    /// Share of the linear model's residual sum of squares it removes.
    pub share: f64,
    /// Its coefficient over the coloured-residual standard error.
    pub t: f64,
    /// R² of the linear regression and with the term added.
    pub r_squared: [f64; 2],
    /// What it means for the coefficient (`not linear in β`, `its slope in β changes with α`).
    pub meaning: String,
}

impl Nonlinearity {
    /// One line for the report's notes.
    pub fn note(&self) -> String {
        format!(
            "model structure: what the linear model leaves of {} follows {} ({:.0} % of its residual; |t| {:.1} \
             with coloured residuals; R² {:.3} → {:.3} with it): {} {} over the range the records fly; the \
             linear estimates are slopes over that range, bent by whatever of the nonlinearity correlates with \
             the other terms, and can be far from the local derivatives at the trim",
            self.coefficient,
            self.term,
            100.0 * self.share,
            self.t.abs(),
            self.r_squared[0],
            self.r_squared[1],
            self.coefficient,
            self.meaning,
        )
    }
}

/// The variable of a linear term and whether it is odd about zero in a symmetric aircraft (β, δa, δr).
fn variable(term: &str) -> Option<(&'static str, bool)> {
    let (_, var) = term.split_once('_')?;
    Some(match var {
        "alpha" => ("α", false),
        "de" => ("δe", false),
        "beta" => ("β", true),
        "da" => ("δa", true),
        "dr" => ("δr", true),
        _ => return None,
    })
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// The candidates of one regressor column, with α along the rows when known: (written form, values, what it
/// means for the coefficient).
fn candidates(term: &str, x: &[f64], alpha: Option<&[f64]>) -> Vec<(String, Vec<f64>, String)> {
    let Some((symbol, odd)) = variable(term) else {
        return Vec::new();
    };
    let not_linear = format!("is not linear in {symbol}");
    if !odd {
        let m = mean(x);
        return vec![(
            format!("({symbol} − mean)²"),
            x.iter().map(|v| (v - m).powi(2)).collect(),
            not_linear,
        )];
    }
    let mut out = vec![
        (
            format!("{symbol}²"),
            x.iter().map(|v| v * v).collect(),
            not_linear.clone(),
        ),
        (
            format!("|{symbol}|"),
            x.iter().map(|v| v.abs()).collect(),
            not_linear,
        ),
    ];
    if let (Some(alpha), "β") = (alpha, symbol) {
        let m = mean(alpha);
        out.push((
            "β·(α − mean)".to_string(),
            x.iter().zip(alpha).map(|(b, a)| b * (a - m)).collect(),
            "has a slope in β that changes with α".to_string(),
        ));
    }
    out
}

fn residual_sum_of_squares(columns: &[Vec<f64>], theta: &[f64], z: &[f64]) -> f64 {
    z.iter()
        .enumerate()
        .map(|(i, zi)| {
            let fit: f64 = columns.iter().zip(theta).map(|(c, t)| c[i] * t).sum();
            (zi - fit).powi(2)
        })
        .sum()
}

/// The screen (module doc) over the regressions of an equation-error estimate; `alpha`, per coefficient, the
/// angle of attack along its rows where known.
pub fn screen(
    equations: &[RegressionResult],
    alpha: &BTreeMap<String, Vec<f64>>,
) -> Vec<Nonlinearity> {
    let mut found = Vec::new();
    for eq in equations {
        let alpha = alpha.get(eq.coefficient).map(Vec::as_slice).filter(|a| {
            a.len() == eq.response.len() && matches!(eq.coefficient, "CY" | "Cl" | "Cn")
        });
        let names: Vec<String> = eq.terms.iter().map(|t| t.name.clone()).collect();
        let theta: Vec<f64> = eq.terms.iter().map(|t| t.value).collect();
        let rss = residual_sum_of_squares(&eq.regressors, &theta, &eq.response);
        if rss <= 0.0 {
            continue;
        }
        let mut best: Option<Nonlinearity> = None;
        for (k, name) in names.iter().enumerate() {
            for (term, column, meaning) in candidates(name, &eq.regressors[k], alpha) {
                let mut cols = eq.regressors.clone();
                cols.push(column);
                let mut with = names.clone();
                with.push(term.clone());
                let Ok(res) = lesq(eq.coefficient, &with, &cols, &eq.response, None) else {
                    continue;
                };
                let added = &res.terms[res.terms.len() - 1];
                let theta: Vec<f64> = res.terms.iter().map(|t| t.value).collect();
                let share = 1.0 - residual_sum_of_squares(&cols, &theta, &eq.response) / rss;
                let t = added.value / added.std_error_colored;
                let candidate = Nonlinearity {
                    coefficient: eq.coefficient.to_string(),
                    of: name.clone(),
                    term,
                    share,
                    t,
                    r_squared: [eq.r_squared, res.r_squared],
                    meaning,
                };
                if share >= MIN_SHARE
                    && t.abs() >= MIN_T
                    && best.as_ref().is_none_or(|b| share > b.share)
                {
                    best = Some(candidate);
                }
            }
        }
        found.extend(best);
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regression of `z` on an intercept, β and p (names as equation error writes them).
    fn regression(beta: &[f64], p: &[f64], z: &[f64]) -> RegressionResult {
        let names: Vec<String> = ["Cl_0", "Cl_beta", "Cl_p"].map(String::from).to_vec();
        let cols = vec![vec![1.0; z.len()], beta.to_vec(), p.to_vec()];
        lesq("Cl", &names, &cols, z, None).unwrap()
    }

    /// Deterministic inputs: a β doublet-like sweep, a roll rate out of phase with it, and coloured "noise"
    /// (a slow sine the regressors do not hold).
    fn signals(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.02).collect();
        let beta = t
            .iter()
            .map(|t| 0.06 * (1.3 * t).sin() + 0.02 * (3.1 * t).sin())
            .collect();
        let p = t.iter().map(|t| 0.1 * (2.2 * t).cos()).collect();
        let noise = t
            .iter()
            .map(|t| 2e-4 * (0.37 * t).sin() + 1e-4 * (17.0 * t).sin())
            .collect();
        (beta, p, noise)
    }

    #[test]
    fn a_coefficient_even_in_beta_is_named_and_a_linear_one_is_not() {
        let (beta, p, noise) = signals(3000);
        let linear: Vec<f64> = (0..beta.len())
            .map(|i| 0.001 - 0.08 * beta[i] - 0.45 * p[i] + noise[i])
            .collect();
        let none = BTreeMap::new();
        assert!(screen(&[regression(&beta, &p, &linear)], &none).is_empty());
        // the DHC6's C_l(β) at low α: 0.41 |β|, besides a small linear part
        let kinked: Vec<f64> = (0..beta.len())
            .map(|i| linear[i] + 0.41 * beta[i].abs())
            .collect();
        let found = screen(&[regression(&beta, &p, &kinked)], &none);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].coefficient, "Cl");
        assert_eq!(found[0].of, "Cl_beta");
        assert_eq!(found[0].term, "|β|");
        assert!(found[0].share > 0.9, "{found:?}");
        assert!(found[0].r_squared[1] > found[0].r_squared[0]);
        assert!(found[0].note().contains("Cl is not linear in β"));
        // the same linear response with a dihedral that grows with α: named as the cross term, with α known
        let alpha: Vec<f64> = (0..beta.len())
            .map(|i| 0.05 + 0.03 * (0.21 * i as f64 * 0.02).sin())
            .collect();
        let crossed: Vec<f64> = (0..beta.len())
            .map(|i| linear[i] - 2.0 * beta[i] * (alpha[i] - 0.05))
            .collect();
        let with_alpha = BTreeMap::from([("Cl".to_string(), alpha)]);
        let found = screen(&[regression(&beta, &p, &crossed)], &with_alpha);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].term, "β·(α − mean)");
        assert!(found[0].note().contains("slope in β that changes with α"));
    }

    #[test]
    fn a_small_even_part_below_the_share_is_not_named() {
        let (beta, p, noise) = signals(3000);
        // an even part that removes well under a tenth of a residual dominated by the coloured noise
        let z: Vec<f64> = (0..beta.len())
            .map(|i| -0.08 * beta[i] - 0.45 * p[i] + 20.0 * noise[i] + 0.002 * beta[i].abs())
            .collect();
        assert!(screen(&[regression(&beta, &p, &z)], &BTreeMap::new()).is_empty());
    }
}
