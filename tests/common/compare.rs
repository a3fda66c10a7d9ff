//! Comparing numbers, vectors and fields given by node id.

use std::collections::BTreeMap;

use serde_json::Value;

/// Relative difference |a − b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// A JSON array of numbers as a vector.
pub fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("{v} is not an array"))
        .iter()
        .map(|x| x.as_f64().unwrap_or_else(|| panic!("{x} is not a number")))
        .collect()
}

/// max_k |a_k − b_k| over the common node ids (both maps must hold the same ids) and
/// max_k |b_k|, i.e. (absolute difference, scale).
pub fn max_diff(a: &BTreeMap<u64, Vec<f64>>, b: &BTreeMap<u64, Vec<f64>>) -> (f64, f64) {
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the two runs have different node ids"
    );
    let mut diff = 0.0f64;
    let mut scale = 0.0f64;
    for (k, va) in a {
        let vb = &b[k];
        assert_eq!(va.len(), vb.len());
        for (x, y) in va.iter().zip(vb) {
            diff = diff.max((x - y).abs());
            scale = scale.max(y.abs());
        }
    }
    (diff, scale)
}
