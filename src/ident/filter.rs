//! State-variable filters: exact sampled responses of `s^j / A(s)` to a sampled signal.
//!
//! For a monic `A(s) = s^n + a_1 s^{n−1} + … + a_n` the controllable canonical realisation with
//! state `x = [ξ, ξ', …, ξ^{(n−1)}]`, `ξ = v / A(s)`, gives every filtered derivative
//! `s^j / A(s) · v` (j < n) as one state. This is the state-variable-filter (SVF) bank used by
//! the SRIVC prefilter (Young & Jakeman 1980; Garnier, Mensler & Richard 2003, "Continuous-time
//! model identification from sampled data", IJC 76(13)) and, with `A²`, by the output-error
//! sensitivities.
//!
//! The continuous system is discretised exactly for the assumed inter-sample behaviour
//! (Franklin, Powell & Workman, *Digital Control of Dynamic Systems*, 3rd ed., §4.3 / §6.3):
//! - [`Hold::Zoh`] — piecewise-constant input (a sampled control surface command), optionally
//!   with a pure delay that need not be a multiple of the sample time (modified z-transform);
//! - [`Hold::Foh`] — piecewise-linear input (a sampled smooth response such as `y`), error O(h²).

use super::linalg::identity;
use crate::lti::expm_rows;

/// Inter-sample behaviour assumed for the filtered signal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Hold {
    /// Zero-order hold with a pure delay in seconds (0 for none).
    Zoh { delay_s: f64 },
    /// First-order (linear) interpolation between samples.
    Foh,
}

/// A discretised SVF bank for `1/A(s)`.
#[derive(Clone, Debug)]
pub(crate) struct Svf {
    /// Order n of `A(s)`.
    pub n: usize,
    /// Monic denominator, highest power first (length n+1).
    den: Vec<f64>,
    phi: Vec<f64>,
    /// Weight on the current sample u_{k−d} (ZOH) or u_k (FOH).
    g_now: Vec<f64>,
    /// Weight on u_{k−d−1} (ZOH, fractional delay) or on u_{k+1} − u_k (FOH).
    g_other: Vec<f64>,
    hold: Hold,
    delay_samples: usize,
}

impl Svf {
    /// Discretises the canonical realisation of `1/A(s)` (A monic, highest power first).
    pub fn new(den_monic: &[f64], dt_s: f64, hold: Hold) -> Svf {
        let n = den_monic.len() - 1;
        let a = companion(den_monic);
        let (phi, g_now, g_other, delay_samples) = match hold {
            Hold::Zoh { delay_s } => {
                let delay = delay_s.max(0.0) / dt_s;
                let d = delay.floor();
                let f = delay - d;
                // Γb = ∫₀^{(1−f)h} e^{Aσ}dσ B,  Γa = e^{A(1−f)h} ∫₀^{fh} e^{Aσ}dσ B
                let (e1, g1) = phi_gamma(&a, n, (1.0 - f) * dt_s);
                let (_, g2) = phi_gamma(&a, n, f * dt_s);
                let ga: Vec<f64> = (0..n)
                    .map(|i| (0..n).map(|j| e1[i * n + j] * g2[j]).sum())
                    .collect();
                let (phi, _) = phi_gamma(&a, n, dt_s);
                (phi, g1, ga, d as usize)
            }
            Hold::Foh => {
                // expm([[A, B, 0],[0, 0, 1],[0, 0, 0]] h): block (1,2) = Γ0, block (1,3) = hΓ0 − Γ1
                let m = n + 2;
                let e = augmented_exponential(&a, n, m, dt_s, |big| big[n * m + n + 1] = dt_s);
                let phi: Vec<f64> = (0..n * n).map(|k| e[(k / n) * m + k % n]).collect();
                let g0: Vec<f64> = (0..n).map(|i| e[i * m + n]).collect();
                // e[i, n+1] = ∫₀^h e^{Aσ}B (h−σ)/h dσ · h / h → divide by h for the slope weight
                let gf: Vec<f64> = (0..n).map(|i| e[i * m + n + 1] / dt_s).collect();
                (phi, g0, gf, 0)
            }
        };
        Svf {
            n,
            den: den_monic.to_vec(),
            phi,
            g_now,
            g_other,
            hold,
            delay_samples,
        }
    }

    /// Runs the filter from rest on `v`; returns the states column by column (n × N), so
    /// `out.col(j)[k]` is `(s^j / A(s) · v)(kh)`: each filtered derivative is one contiguous
    /// signal, the layout the regressions' inner products want.
    pub fn run(&self, v: &[f64]) -> Columns {
        let len = v.len();
        let mut data = vec![0.0; len * self.n];
        self.recurse(v, |k, x| {
            for (j, xj) in x.iter().enumerate() {
                data[j * len + k] = *xj;
            }
        });
        Columns { len, data }
    }

    /// The state recursion `x(k+1) = Φ x(k) + Γ_now w_now + Γ_other w_other` from rest, handing
    /// `x(kh)` to `emit` for k = 0 … N−1. Dispatches to a recursion on fixed-size arrays (the
    /// order rounded up, padding states that stay zero), which the compiler unrolls: 2–3× faster
    /// than loops over slices at the orders used here.
    fn recurse(&self, v: &[f64], emit: impl FnMut(usize, &[f64])) {
        match self.n {
            0 => {}
            1 => self.recurse_fixed::<1>(v, emit),
            2 => self.recurse_fixed::<2>(v, emit),
            3 => self.recurse_fixed::<3>(v, emit),
            4 => self.recurse_fixed::<4>(v, emit),
            5 => self.recurse_fixed::<5>(v, emit),
            6 => self.recurse_fixed::<6>(v, emit),
            7 => self.recurse_fixed::<7>(v, emit),
            8 => self.recurse_fixed::<8>(v, emit),
            9..=12 => self.recurse_fixed::<12>(v, emit),
            13..=16 => self.recurse_fixed::<16>(v, emit),
            17..=32 => self.recurse_fixed::<32>(v, emit),
            33..=64 => self.recurse_fixed::<64>(v, emit),
            n => panic!("state filter of order {n}: above 2 × MAX_POLES"),
        }
    }

    /// [`Svf::recurse`] with the state padded to `N ≥ n`.
    fn recurse_fixed<const N: usize>(&self, v: &[f64], mut emit: impl FnMut(usize, &[f64])) {
        let n = self.n;
        let len = v.len();
        let mut phi = [[0.0; N]; N];
        let (mut g_now, mut g_other) = ([0.0; N], [0.0; N]);
        for i in 0..n {
            phi[i][..n].copy_from_slice(&self.phi[i * n..(i + 1) * n]);
            g_now[i] = self.g_now[i];
            g_other[i] = self.g_other[i];
        }
        let d = self.delay_samples;
        let at = |k: usize| -> f64 {
            if k < d {
                0.0
            } else {
                v[k - d]
            }
        };
        let mut x = [0.0; N];
        for k in 0..len {
            emit(k, &x[..n]);
            if k + 1 == len {
                break;
            }
            let (w_now, w_other) = match self.hold {
                // u_{k−d} and u_{k−d−1}
                Hold::Zoh { .. } => (at(k), if k == 0 { 0.0 } else { at(k - 1) }),
                Hold::Foh => (v[k], v[k + 1] - v[k]),
            };
            let mut next = [0.0; N];
            for i in 0..N {
                let s = g_now[i] * w_now + g_other[i] * w_other;
                // accumulated onto s in index order, as the textbook recursion reads
                next[i] = phi[i].iter().zip(&x).fold(s, |acc, (r, xj)| acc + r * xj);
            }
            x = next;
        }
    }

    /// The top derivative `(s^n / A(s) · v)(kh) = v(kh) − Σ a_i (s^{n−i}/A · v)(kh)` at every
    /// sample, from a run of this filter on `v` (the delayed values for a delayed ZOH input).
    pub fn top_derivative(&self, states: &Columns, v: &[f64]) -> Vec<f64> {
        let n = self.n;
        let mut out = v.to_vec();
        for i in 1..=n {
            let a = self.den[i];
            for (o, x) in out.iter_mut().zip(states.col(n - i)) {
                *o -= a * x;
            }
        }
        out
    }
}

/// SVF states stored column by column (see [`Svf::run`]).
#[derive(Clone, Debug)]
pub(crate) struct Columns {
    len: usize,
    data: Vec<f64>,
}

impl Columns {
    /// `(s^j / A(s) · v)(kh)` for k = 0 … N−1.
    pub fn col(&self, j: usize) -> &[f64] {
        &self.data[j * self.len..(j + 1) * self.len]
    }

    /// The same states without their first `k` samples (sample 0 is then `k·h`).
    pub fn skip(&self, k: usize) -> Columns {
        let len = self.len.saturating_sub(k);
        let n = self.data.len() / self.len.max(1);
        let data = (0..n)
            .flat_map(|j| self.col(j)[k.min(self.len)..].to_vec())
            .collect();
        Columns { len, data }
    }

    /// `Σ_j b_j s^j/A · v`, `num` highest power first with degree < n.
    pub fn combine(&self, num: &[f64]) -> Vec<f64> {
        let m = num.len() - 1;
        let mut out = vec![0.0; self.len];
        for (i, b) in num.iter().enumerate() {
            for (o, x) in out.iter_mut().zip(self.col(m - i)) {
                *o += b * x;
            }
        }
        out
    }
}

/// Controllable canonical A-matrix (row-major) of `1/A(s)` with state `[ξ, ξ', …]`.
fn companion(den_monic: &[f64]) -> Vec<f64> {
    let n = den_monic.len() - 1;
    let mut a = vec![0.0; n * n];
    for i in 0..n.saturating_sub(1) {
        a[i * n + i + 1] = 1.0;
    }
    for i in 1..=n {
        a[(n - 1) * n + (n - i)] = -den_monic[i];
    }
    a
}

/// `expm(M t)` of the m × m block matrix `M = [[A, B, …], [0, …]]` (row-major), `A` the n × n companion
/// matrix and `B = e_n` in column n; `extra` sets the further blocks of `M t` (Van Loan 1978).
fn augmented_exponential(
    a: &[f64],
    n: usize,
    m: usize,
    t: f64,
    extra: impl FnOnce(&mut [f64]),
) -> Vec<f64> {
    let mut big = vec![0.0; m * m];
    for i in 0..n {
        for j in 0..n {
            big[i * m + j] = a[i * n + j] * t;
        }
    }
    big[(n - 1) * m + n] = t;
    extra(&mut big);
    expm_rows(&big, m)
}

/// `(e^{At}, ∫₀^t e^{Aσ}dσ B)` with `B = e_n`, from one exponential of `[[A, B],[0, 0]] t`
/// (Van Loan 1978, "Computing integrals involving the matrix exponential").
fn phi_gamma(a: &[f64], n: usize, t: f64) -> (Vec<f64>, Vec<f64>) {
    if t == 0.0 {
        return (identity(n), vec![0.0; n]);
    }
    let m = n + 1;
    let e = augmented_exponential(a, n, m, t, |_| {});
    let phi: Vec<f64> = (0..n * n).map(|k| e[(k / n) * m + k % n]).collect();
    let g: Vec<f64> = (0..n).map(|i| e[i * m + n]).collect();
    (phi, g)
}

/// Simulated output of `B(s)/A(s) · e^{−τs}` to a ZOH input, from rest; `num` highest power
/// first with degree < n, `den` monic.
pub(crate) fn simulate(
    num: &[f64],
    den_monic: &[f64],
    u: &[f64],
    dt_s: f64,
    delay_s: f64,
) -> Vec<f64> {
    Svf::new(den_monic, dt_s, Hold::Zoh { delay_s })
        .run(u)
        .combine(num)
}
