//! Time responses of linear models to sampled inputs.

use super::discretize::{c2d, Discretization};
use super::ss::{tf2ss, StateSpace};
use super::tf::TransferFunction;

/// Response of a SISO transfer function to the input samples `u` (spacing `dt_s`), zero initial state.
///
/// Continuous: the input is held between samples (ZOH) and the model discretised exactly, so the
/// output samples are exact for that input (`scipy.signal.lsim(..., interp=False)`). Unstable poles
/// are simulated as they are (the response grows). Discrete: the difference equation
/// `a₀y[k] = Σ bⱼ u[k − r − j] − Σ_{i≥1} aᵢ y[k − i]` with r the relative degree; the model's own
/// `dt_s` applies. An improper discrete model keeps only its proper part.
pub fn lsim(tf: &TransferFunction, u: &[f64], dt_s: f64) -> Vec<f64> {
    if tf.is_discrete() {
        return difference_equation(tf, u);
    }
    let ss = tf2ss(tf);
    let out = lsim_ss(&ss, &[u.to_vec()], dt_s, None);
    out.into_iter().next().unwrap_or_else(|| vec![0.0; u.len()])
}

fn difference_equation(tf: &TransferFunction, u: &[f64]) -> Vec<f64> {
    let m = tf.monic();
    let (a, mut b) = (m.den, m.num);
    let na = a.len() - 1;
    if b.len() > a.len() {
        b = b[b.len() - a.len()..].to_vec();
    }
    let r = a.len() - b.len(); // delay in samples from u to y
    let mut y = vec![0.0; u.len()];
    if a[0] == 0.0 {
        return y;
    }
    for k in 0..u.len() {
        let mut acc = 0.0;
        for (j, &bj) in b.iter().enumerate() {
            if let Some(idx) = k.checked_sub(r + j) {
                acc += bj * u[idx];
            }
        }
        for i in 1..=na.min(k) {
            acc -= a[i] * y[k - i];
        }
        y[k] = acc;
    }
    y
}

/// Response of a (MIMO) state space model: `u[i]` holds the samples of input i; returns one vector per
/// output, as long as the shortest input channel.
///
/// A continuous model is discretised with ZOH at `dt_s` (see [`lsim`]); a discrete model is iterated
/// as it is. `x0` is the initial state (zero if `None` or of the wrong length). With no input channels
/// the record is empty.
pub fn lsim_ss(ss: &StateSpace, u: &[Vec<f64>], dt_s: f64, x0: Option<&[f64]>) -> Vec<Vec<f64>> {
    let ssd = if ss.is_discrete() {
        ss.clone()
    } else {
        c2d(ss, dt_s, Discretization::Zoh)
    };
    let (n, m, p) = (ssd.n_states(), ssd.n_inputs(), ssd.n_outputs());
    let len = u.iter().take(m).map(Vec::len).min().unwrap_or(0);
    // flat row-major copies: this loop is the hot path of output-error fitting
    let flat = |mat: &faer::Mat<f64>| -> Vec<f64> {
        (0..mat.nrows())
            .flat_map(|i| (0..mat.ncols()).map(move |j| mat[(i, j)]))
            .collect()
    };
    let (a, b, c, d) = (flat(&ssd.a), flat(&ssd.b), flat(&ssd.c), flat(&ssd.d));
    let mut x = match x0 {
        Some(x0) if x0.len() == n => x0.to_vec(),
        _ => vec![0.0; n],
    };
    let mut x_next = vec![0.0; n];
    let mut uk = vec![0.0; m];
    let mut y = vec![vec![0.0; len]; p];
    for k in 0..len {
        for (i, ui) in uk.iter_mut().enumerate() {
            *ui = u[i][k];
        }
        for (o, yo) in y.iter_mut().enumerate() {
            let crow = &c[o * n..(o + 1) * n];
            let drow = &d[o * m..(o + 1) * m];
            yo[k] = crow.iter().zip(&x).map(|(ci, xi)| ci * xi).sum::<f64>()
                + drow.iter().zip(&uk).map(|(di, ui)| di * ui).sum::<f64>();
        }
        for (i, xn) in x_next.iter_mut().enumerate() {
            let arow = &a[i * n..(i + 1) * n];
            let brow = &b[i * m..(i + 1) * m];
            *xn = arow.iter().zip(&x).map(|(ai, xi)| ai * xi).sum::<f64>()
                + brow.iter().zip(&uk).map(|(bi, ui)| bi * ui).sum::<f64>();
        }
        std::mem::swap(&mut x, &mut x_next);
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_response_of_first_order_lag_is_exact_at_the_samples() {
        // 1/(s + 2): y(t) = (1 − e^{−2t})/2 for a unit step held from t = 0
        let dt = 0.01;
        let u = vec![1.0; 301];
        let y = lsim(&TransferFunction::new(vec![1.0], vec![1.0, 2.0]), &u, dt);
        for (k, yk) in y.iter().enumerate() {
            let t = k as f64 * dt;
            assert!(
                (yk - (1.0 - (-2.0 * t).exp()) / 2.0).abs() < 1e-14,
                "t = {t}"
            );
        }
    }

    #[test]
    fn discrete_difference_equation_matches_hand_iteration() {
        // H(z) = (z + 0.5)/(z² − 0.5 z + 0.06): y[k] = 0.5y[k−1] − 0.06y[k−2] + u[k−1] + 0.5u[k−2]
        let tf = TransferFunction::discrete(vec![1.0, 0.5], vec![1.0, -0.5, 0.06], 0.1);
        let u = [1.0, 0.0, 0.0, 2.0, 0.0];
        let y = lsim(&tf, &u, 0.1);
        let mut expected = [0.0; 5];
        for k in 0..5 {
            let g = |i: isize, v: &[f64]| if i >= 0 { v[i as usize] } else { 0.0 };
            let k_i = k as isize;
            expected[k] = 0.5 * g(k_i - 1, &expected) - 0.06 * g(k_i - 2, &expected)
                + g(k_i - 1, &u)
                + 0.5 * g(k_i - 2, &u);
        }
        for (a, b) in y.iter().zip(expected) {
            assert!((a - b).abs() < 1e-15, "{y:?} vs {expected:?}");
        }
    }

    #[test]
    fn discrete_state_space_and_difference_equation_agree() {
        let tf = TransferFunction::discrete(vec![0.3, 0.1], vec![1.0, -1.2, 0.5], 0.05);
        let u: Vec<f64> = (0..50).map(|k| ((k as f64) * 0.37).sin()).collect();
        let y1 = lsim(&tf, &u, 0.05);
        let y2 = lsim_ss(&tf2ss(&tf), std::slice::from_ref(&u), 0.05, None).remove(0);
        for (a, b) in y1.iter().zip(y2) {
            assert!((a - b).abs() < 1e-13);
        }
    }

    #[test]
    fn initial_state_decays_freely() {
        // ẋ = −x, y = x, x0 = 2: y = 2e^{−t}
        let ss = StateSpace::from_rows(&[vec![-1.0]], &[vec![0.0]], &[vec![1.0]], &[]).unwrap();
        let y = lsim_ss(&ss, &[vec![0.0; 11]], 0.1, Some(&[2.0])).remove(0);
        assert!((y[10] - 2.0 * (-1.0_f64).exp()).abs() < 1e-14);
    }
}
