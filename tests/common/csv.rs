//! contact_nodes.csv (header + rows, no quoting), one row per contact node, by column name.

use std::collections::BTreeMap;
use std::path::Path;

/// One row of a CSV file, by column name.
#[derive(Debug, Clone)]
pub struct Row(pub BTreeMap<String, String>);

impl Row {
    pub fn s(&self, key: &str) -> &str {
        self.0
            .get(key)
            .unwrap_or_else(|| panic!("CSV has no column {key:?}: {:?}", self.0))
    }

    pub fn f(&self, key: &str) -> f64 {
        let s = self.s(key);
        s.parse()
            .unwrap_or_else(|e| panic!("CSV {key} = {s:?} is not a number: {e}"))
    }

    pub fn node_id(&self) -> u64 {
        self.s("node_id").parse().expect("node_id")
    }

    pub fn active(&self) -> bool {
        match self.s("state") {
            "active" => true,
            "inactive" => false,
            other => panic!("unknown contact state {other:?}"),
        }
    }

    /// "stick", "slip" or "-".
    pub fn tangential(&self) -> &str {
        self.s("tangential")
    }

    /// (u_t1[, u_t2]) of a CSV with `dim` spatial columns.
    pub fn u_t(&self, dim: usize) -> Vec<f64> {
        (1..dim).map(|i| self.f(&format!("u_t{i}"))).collect()
    }

    /// (λ_t1[, λ_t2]).
    pub fn lambda_t(&self, dim: usize) -> Vec<f64> {
        (1..dim).map(|i| self.f(&format!("lambda_t{i}"))).collect()
    }

    pub fn bound(&self) -> f64 {
        self.f("bound")
    }
}

/// Reads a header + rows CSV file without quoting; the rows in file order.
pub fn read_csv(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("CSV header")
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "CSV row {l:?} vs {header:?}");
            Row(header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.trim().to_string()))
                .collect())
        })
        .collect()
}

/// The rows by node id.
pub fn by_node_id(rows: Vec<Row>) -> BTreeMap<u64, Row> {
    rows.into_iter().map(|r| (r.node_id(), r)).collect()
}

/// Spatial dimension of a contact_nodes.csv (2 without a z column).
pub fn csv_dim(rows: &BTreeMap<u64, Row>) -> usize {
    let r = rows.values().next().expect("contact rows");
    if r.0.contains_key("z") {
        3
    } else {
        2
    }
}

/// Selected numeric CSV columns of each contact node, by node id.
pub fn columns(rows: &BTreeMap<u64, Row>, keys: &[&str]) -> BTreeMap<u64, Vec<f64>> {
    rows.iter()
        .map(|(k, r)| (*k, keys.iter().map(|c| r.f(c)).collect()))
        .collect()
}
