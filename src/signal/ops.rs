//! Operations on sampled signals: measurement noise, resampling, sums of squares and spread.

use rand::{rngs::StdRng, SeedableRng};
use rand_distr::{Distribution, Normal};

/// The cross product a × b of two 3-vectors.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// What an accelerometer at `r` from the CG (body axes, m) reads beyond the CG's acceleration, with the body
/// rates `w` (rad/s) and their derivatives `w_dot` (rad/s²): ω̇ × r + ω × (ω × r), the tangential and
/// centripetal terms of a rigid body (Klein & Morelli, *Aircraft System Identification*, ch. 10, the
/// instrument position corrections).
pub fn lever_arm_acceleration(w: [f64; 3], w_dot: [f64; 3], r: [f64; 3]) -> [f64; 3] {
    let t = cross(w_dot, r);
    let c = cross(w, cross(w, r));
    [t[0] + c[0], t[1] + c[1], t[2] + c[2]]
}

/// Σ xᵢ², summed in order (the cost `eᵀe` of a residual, the energy of a signal).
pub fn sum_sq(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

/// Mean x̄ = Σ xᵢ / n; 0 for an empty series.
pub fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

/// Population standard deviation √(Σ (xᵢ − x̄)² / n); 0 for an empty series.
pub fn std_dev(x: &[f64]) -> f64 {
    let n = x.len().max(1) as f64;
    let mean = mean(x);
    (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt()
}

/// Least-squares slope of `y` on `x` with an intercept, and their correlation (0, 0 where
/// either does not vary).
pub fn slope_and_correlation(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
        sxy += (a - mx) * (b - my);
    }
    if sxx <= 0.0 || syy <= 0.0 {
        return (0.0, 0.0);
    }
    (sxy / sxx, sxy / (sxx * syy).sqrt())
}

/// `x` plus zero-mean Gaussian white noise of standard deviation `std`, reproducible from `seed`.
///
/// A non-positive or non-finite `std` returns `x` unchanged.
pub fn add_white_noise(x: &[f64], std: f64, seed: u64) -> Vec<f64> {
    let normal = match Normal::new(0.0, std) {
        Ok(n) if std > 0.0 && std.is_finite() => n,
        _ => return x.to_vec(),
    };
    let mut rng = StdRng::seed_from_u64(seed);
    x.iter().map(|&v| v + normal.sample(&mut rng)).collect()
}

/// Series sampled at `time_s` on the uniform step `dt_s`, which every estimator assumes: unchanged when no
/// sample step departs from `dt_s` by more than 1 % of it, otherwise interpolated ([`resample_linear`]) onto
/// `t0 + k dt_s` up to the last sample. Returns the series and, when they were resampled, the largest step
/// departure, s.
pub fn on_uniform_step(
    time_s: &[f64],
    series: &[&[f64]],
    dt_s: f64,
) -> (Vec<Vec<f64>>, Option<f64>) {
    let worst_jitter_s = time_s
        .windows(2)
        .map(|w| ((w[1] - w[0]) - dt_s).abs())
        .fold(0.0, f64::max);
    if worst_jitter_s <= 0.01 * dt_s || time_s.is_empty() {
        return (series.iter().map(|x| x.to_vec()).collect(), None);
    }
    let t0 = time_s[0];
    let n = ((time_s[time_s.len() - 1] - t0) / dt_s).floor() as usize + 1;
    let grid: Vec<f64> = (0..n).map(|k| t0 + k as f64 * dt_s).collect();
    let resampled = series
        .iter()
        .map(|x| resample_linear(time_s, x, &grid))
        .collect();
    (resampled, Some(worst_jitter_s))
}

/// Linear interpolation of the samples `(t, x)` at the times `t_new`.
///
/// `t` must be increasing. Times before `t[0]` take `x[0]` and times after the last sample take the
/// last value (hold, no extrapolation). Empty `t` gives zeros; extra samples of the longer of `t`, `x`
/// are ignored.
pub fn resample_linear(t: &[f64], x: &[f64], t_new: &[f64]) -> Vec<f64> {
    let n = t.len().min(x.len());
    if n == 0 {
        return vec![0.0; t_new.len()];
    }
    let (t, x) = (&t[..n], &x[..n]);
    t_new
        .iter()
        .map(|&tq| {
            if tq <= t[0] || tq.is_nan() {
                return x[0];
            }
            if tq >= t[n - 1] {
                return x[n - 1];
            }
            // first index with t[i] > tq; 1 <= i <= n-1 here
            let i = t.partition_point(|&ti| ti <= tq);
            let (t0, t1, x0, x1) = (t[i - 1], t[i], x[i - 1], x[i]);
            let span = t1 - t0;
            if span <= 0.0 {
                x1
            } else {
                x0 + (x1 - x0) * (tq - t0) / span
            }
        })
        .collect()
}

/// The median of `v`, reordering it (the mean of the two middle values for an even count). NaN-free input.
pub fn median_in_place(v: &mut [f64]) -> f64 {
    let n = v.len();
    let mid = n / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    let m = *m;
    if n % 2 == 1 {
        m
    } else {
        let lower = v[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + m)
    }
}

/// White-noise standard deviation of a sampled signal, robust to steps: 1.4826 · MAD(Δu)/√2. For white
/// noise of σ the first difference has σ√2, and 1.4826 × its median absolute deviation estimates that; the
/// steps of a pulse train and slow motion occupy few or small differences and leave the median alone. 0 for
/// a signal that is piecewise constant over more than half its samples.
pub fn difference_noise_std(u: &[f64]) -> f64 {
    if u.len() < 3 {
        return 0.0;
    }
    let mut d: Vec<f64> = u.windows(2).map(|w| w[1] - w[0]).collect();
    let m = median_in_place(&mut d);
    let mut ad: Vec<f64> = d.iter().map(|x| (x - m).abs()).collect();
    1.4826 * median_in_place(&mut ad) / std::f64::consts::SQRT_2
}

/// Measurement-noise standard deviation from the second difference: for white noise of variance σ²,
/// var(Δ²y) = 6σ², while a smooth signal sampled fast contributes little (Morelli & Klein, §11.2 idea).
pub fn noise_std(y: &[f64]) -> f64 {
    if y.len() < 4 {
        return 0.0;
    }
    let d2: Vec<f64> = y.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]).collect();
    let m = d2.iter().sum::<f64>() / d2.len() as f64;
    let v = d2.iter().map(|x| (x - m).powi(2)).sum::<f64>() / d2.len() as f64;
    (v / 6.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_with_same_seed_is_reproducible_and_has_requested_std() {
        let x = vec![0.0; 20_000];
        let a = add_white_noise(&x, 0.5, 42);
        let b = add_white_noise(&x, 0.5, 42);
        assert_eq!(a, b);
        let mean = a.iter().sum::<f64>() / a.len() as f64;
        let std = (a.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
        // 20 000 samples: the sample std has a relative standard error of 1/sqrt(2N) = 0.5 %.
        assert!((std - 0.5).abs() < 0.01, "std {std}");
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert_ne!(a, add_white_noise(&x, 0.5, 43));
    }

    #[test]
    fn sum_of_squares_and_population_std_of_a_short_series() {
        // exact in binary floating point: 1 + 4 + 4 = 9; mean 2, deviations ±1 → σ = 1
        assert_eq!(sum_sq(&[1.0, -2.0, 2.0]), 9.0);
        assert_eq!(std_dev(&[1.0, 3.0]), 1.0);
        // an empty series has no spread (not NaN), so a scale built from it falls back to its floor
        assert_eq!(std_dev(&[]), 0.0);
    }

    #[test]
    fn zero_noise_returns_input() {
        assert_eq!(add_white_noise(&[1.0, 2.0], 0.0, 1), vec![1.0, 2.0]);
    }

    #[test]
    fn resample_interpolates_linearly_and_holds_ends() {
        let t = [0.0, 1.0, 3.0];
        let x = [0.0, 2.0, -2.0];
        let y = resample_linear(&t, &x, &[-1.0, 0.0, 0.5, 1.0, 2.0, 2.5, 3.0, 4.0]);
        assert_eq!(y, vec![0.0, 0.0, 1.0, 2.0, 0.0, -1.0, -2.0, -2.0]);
    }

    #[test]
    fn resample_of_a_line_is_exact_on_a_finer_grid() {
        let t: Vec<f64> = (0..11).map(|k| k as f64 * 0.1).collect();
        let x: Vec<f64> = t.iter().map(|ti| 3.0 * ti - 1.0).collect();
        let t_new: Vec<f64> = (0..101).map(|k| k as f64 * 0.01).collect();
        for (tq, y) in t_new.iter().zip(resample_linear(&t, &x, &t_new)) {
            assert!((y - (3.0 * tq - 1.0)).abs() < 1e-12);
        }
    }
}

/// Unwraps an angle sequence (rad) so that consecutive samples differ by less than π.
pub fn unwrap_rad(x: &[f64]) -> Vec<f64> {
    let tau = std::f64::consts::TAU;
    let mut out = Vec::with_capacity(x.len());
    let mut offset = 0.0;
    for (i, &v) in x.iter().enumerate() {
        if i > 0 {
            offset -= tau * ((v - x[i - 1]) / tau).round();
        }
        out.push(v + offset);
    }
    out
}

/// A heading sequence (rad) unwrapped and shifted by whole turns so that it starts within (−π, π]: JSBSim reports
/// ψ in [0, 2π), so a trim at heading 0 that settles a hair left of north would start at 6.283185 rad.
pub fn heading_from_zero_rad(psi: &[f64]) -> Vec<f64> {
    let tau = std::f64::consts::TAU;
    let mut out = unwrap_rad(psi);
    if let Some(&first) = out.first() {
        let turns = (first / tau).round();
        let turns = if first - turns * tau <= -std::f64::consts::PI {
            turns - 1.0
        } else {
            turns
        };
        out.iter_mut().for_each(|v| *v -= turns * tau);
    }
    out
}

#[cfg(test)]
mod heading_tests {
    use super::*;

    /// A trim a hair left of north starts at −1e−7 rad, not 2π − 1e−7, and crossing north stays continuous.
    #[test]
    fn heading_starts_within_half_a_turn_of_zero() {
        let tau = std::f64::consts::TAU;
        let psi = [tau - 1e-7, tau - 2e-7, 1e-7, 0.2];
        let h = heading_from_zero_rad(&psi);
        assert!((h[0] + 1e-7).abs() < 1e-12, "{h:?}");
        assert!((h[2] - 1e-7).abs() < 1e-12, "{h:?}");
        assert!((h[3] - 0.2).abs() < 1e-12, "{h:?}");
        assert!((heading_from_zero_rad(&[3.0 * tau + 0.5])[0] - 0.5).abs() < 1e-12);
    }
}
