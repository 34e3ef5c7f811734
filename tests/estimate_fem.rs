//! The filter error method's numerics against an independent oracle: the steady-state Riccati
//! solution against `scipy.linalg.solve_continuous_are` (scripts/oracle_care.py) on systems with
//! unstable, oscillatory and integrating modes.

use std::io::Write;
use std::process::{Command, Stdio};

use faer::Mat;
use flightid::estimate::riccati::care_filter;

fn mat(rows: &[&[f64]]) -> Mat<f64> {
    Mat::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn to_json(m: &Mat<f64>) -> serde_json::Value {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect::<Vec<f64>>())
        .collect()
}

/// P from scipy for the filter-form equation.
fn oracle(a: &Mat<f64>, c: &Mat<f64>, q: &Mat<f64>, r_c: &Mat<f64>) -> Vec<Vec<f64>> {
    let python = flightid::sim::env::python().expect("provisioned Python");
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/oracle_care.py");
    let mut child = Command::new(python)
        .arg(script)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run oracle");
    let input =
        serde_json::json!({"a": to_json(a), "c": to_json(c), "q": to_json(q), "r_c": to_json(r_c)});
    child
        .stdin
        .take()
        .unwrap()
        .write_all(input.to_string().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    serde_json::from_value(v["p"].clone()).unwrap()
}

#[test]
fn riccati_solution_matches_scipy() {
    let diag = |d: &[f64]| Mat::from_fn(d.len(), d.len(), |i, j| if i == j { d[i] } else { 0.0 });
    let cases = [
        // 4-state longitudinal (phugoid, short period), α and q measured, turbulence on u, α, q
        (
            mat(&[
                &[-0.04, 4.0, 0.0, -9.81],
                &[-0.003, -1.1, 1.0, 0.0],
                &[0.002, -7.5, -2.2, 0.0],
                &[0.0, 0.0, 1.0, 0.0],
            ]),
            mat(&[
                &[0.0, 1.0, 0.0, 0.0],
                &[0.0, 0.0, 1.0, 0.0],
                &[0.0, 0.0, 0.0, 1.0],
            ]),
            diag(&[0.05, 2e-4, 4e-3, 0.0]),
            diag(&[0.02 * 4e-6, 0.02 * 2.5e-5, 0.02 * 4e-6]),
        ),
        // statically unstable short period, one output
        (
            mat(&[&[-0.8, 1.0], &[3.0, -1.5]]),
            mat(&[&[0.0, 1.0]]),
            diag(&[1e-3, 1e-2]),
            diag(&[1e-5]),
        ),
        // a pure integrator (heading) observed with a lag state
        (
            mat(&[&[0.0, 1.0, 0.0], &[0.0, -2.0, 1.0], &[0.0, 0.0, -5.0]]),
            mat(&[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]]),
            diag(&[0.0, 0.0, 0.3]),
            diag(&[1e-4, 1e-3]),
        ),
    ];
    for (a, c, q, r_c) in cases {
        let p = care_filter(&a, &c, &q, &r_c).expect("stabilising solution");
        let want = oracle(&a, &c, &q, &r_c);
        let scale = want.iter().flatten().fold(0.0_f64, |s, v| s.max(v.abs()));
        for i in 0..a.nrows() {
            for j in 0..a.nrows() {
                assert!(
                    (p[(i, j)] - want[i][j]).abs() <= 1e-8 * scale,
                    "P[{i}][{j}] {} vs scipy {}",
                    p[(i, j)],
                    want[i][j]
                );
            }
        }
    }
}
