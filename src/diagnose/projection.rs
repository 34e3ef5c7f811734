//! The nuisance terms' projection: an orthonormal basis of their residual directions, and the residual with
//! them estimated (projected off).

use crate::ident::linalg::dot;

/// r ← (1 − Q Qᵀ) r for an orthonormal basis Q: the least-squares residual once the nuisance terms, linear in
/// their effect on the output, are estimated jointly (variable projection, Golub & Pereyra 1973).
pub fn project_off(r: &mut [f64], basis: &[Vec<f64>]) {
    for q in basis {
        let c = dot(q, r);
        r.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
    }
}

/// An orthonormal basis of the span of `columns` by modified Gram–Schmidt; a column that is (nearly) in the
/// span of the ones before it (norm left below 10⁻⁹ of its own) is dropped. Each pass that takes one basis
/// vector's component off also forms the inner product with the next one ([`axpy_dot`]): one sweep over the
/// column per basis vector instead of two.
pub fn orthonormal_basis(columns: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for col in columns {
        let mut u = col.clone();
        let norm0 = dot(&u, &u).sqrt();
        if let Some(first) = basis.first() {
            let mut c = dot(&u, first);
            for (i, b) in basis.iter().enumerate() {
                c = axpy_dot(&mut u, c, b, basis.get(i + 1).unwrap_or(b));
            }
        }
        let norm = dot(&u, &u).sqrt();
        if norm > 1e-9 * norm0.max(1e-300) && norm.is_finite() {
            u.iter_mut().for_each(|x| *x /= norm);
            basis.push(u);
        }
    }
    basis
}

/// u ← u − c b, and the inner product of the new u with `next`, summed as [`dot`] sums.
fn axpy_dot(u: &mut [f64], c: f64, b: &[f64], next: &[f64]) -> f64 {
    let mut acc = [0.0; 8];
    let split = u.len() - u.len() % 8;
    let (head, tail) = u.split_at_mut(split);
    for ((uc, bc), nc) in head
        .chunks_exact_mut(8)
        .zip(b.chunks_exact(8))
        .zip(next.chunks_exact(8))
    {
        for k in 0..8 {
            uc[k] -= c * bc[k];
            acc[k] += uc[k] * nc[k];
        }
    }
    let mut rest = 0.0;
    for ((x, y), z) in tail.iter_mut().zip(&b[split..]).zip(&next[split..]) {
        *x -= c * y;
        rest += *x * z;
    }
    acc.iter().sum::<f64>() + rest
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Modified Gram–Schmidt as the textbook writes it: each basis vector's component taken off in turn.
    fn textbook(columns: &[Vec<f64>]) -> Vec<Vec<f64>> {
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

    #[test]
    fn the_fused_sweep_is_modified_gram_schmidt_to_the_last_bit() {
        let cols: Vec<Vec<f64>> = (0..6)
            .map(|j| {
                (0..37)
                    .map(|t| ((t * (j + 3)) as f64 * 0.37).sin() + j as f64 * 0.01)
                    .collect()
            })
            .chain(std::iter::once(vec![0.0; 37]))
            .collect();
        let mut dependent = cols[0].clone();
        dependent
            .iter_mut()
            .zip(&cols[1])
            .for_each(|(a, b)| *a = 2.0 * *a - b);
        let mut all = cols.clone();
        all.push(dependent);
        let basis = orthonormal_basis(&all);
        assert_eq!(basis, textbook(&all));
        // the zero column and the combination of the first two are dropped
        assert_eq!(basis.len(), 6);
        for (i, a) in basis.iter().enumerate() {
            for (j, b) in basis.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((dot(a, b) - want).abs() < 1e-12);
            }
        }
    }
}
