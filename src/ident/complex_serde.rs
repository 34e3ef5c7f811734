//! Serde adapters for complex numbers as `[re, im]` pairs (num-complex's serde feature is off).

use num_complex::Complex64;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// `Vec<Complex64>` as `[[re, im], …]`.
pub(crate) mod many {
    use super::*;

    /// Serialises as a list of `[re, im]` pairs.
    pub fn serialize<S: Serializer>(v: &[Complex64], s: S) -> Result<S::Ok, S::Error> {
        let pairs: Vec<[f64; 2]> = v.iter().map(|c| [c.re, c.im]).collect();
        pairs.serialize(s)
    }

    /// Reads a list of `[re, im]` pairs.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Complex64>, D::Error> {
        let pairs = Vec::<[f64; 2]>::deserialize(d)?;
        Ok(pairs
            .into_iter()
            .map(|[re, im]| Complex64::new(re, im))
            .collect())
    }
}
