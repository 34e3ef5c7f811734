//! The nuisance terms' projection: an orthonormal basis of their residual directions, and the residual with
//! them estimated (projected off).

/// r ← (1 − Q Qᵀ) r for an orthonormal basis Q: the least-squares residual once the nuisance terms, linear in
/// their effect on the output, are estimated jointly (variable projection, Golub & Pereyra 1973).
pub fn project_off(r: &mut [f64], basis: &[Vec<f64>]) {
    for q in basis {
        let c: f64 = q.iter().zip(r.iter()).map(|(a, b)| a * b).sum();
        r.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
    }
}

/// An orthonormal basis of the span of `columns` by modified Gram–Schmidt; a column that is (nearly) in the
/// span of the ones before it (norm left below 10⁻⁹ of its own) is dropped.
pub fn orthonormal_basis(columns: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for col in columns {
        let mut u = col.clone();
        let norm0 = dot(&u, &u).sqrt();
        for b in &basis {
            let c = dot(&u, b);
            u.iter_mut().zip(b).for_each(|(x, y)| *x -= c * y);
        }
        let norm = dot(&u, &u).sqrt();
        if norm > 1e-9 * norm0.max(1e-300) && norm.is_finite() {
            u.iter_mut().for_each(|x| *x /= norm);
            basis.push(u);
        }
    }
    basis
}
