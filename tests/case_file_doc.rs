//! docs/case-file.md documents every table of the case file: each heading whose first code
//! span names a table of `case::keys::SECTIONS` is followed by a table whose first column
//! (`| key | type | default | meaning |`) lists that table's keys. The keys in the document
//! and the keys the reader accepts agree both ways, and every table of the reader has its
//! section in the document.

use signorini_mpi::case::keys::SECTIONS;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The first `code span` of a line.
fn first_code_span(line: &str) -> Option<&str> {
    let start = line.find('`')? + 1;
    let len = line[start..].find('`')?;
    Some(&line[start..start + len])
}

/// The cells of a table row: split at every `|` that is not escaped (`\|` stays in its cell).
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut out = vec![String::new()];
    let mut escaped = false;
    for c in inner.chars() {
        match c {
            '|' if !escaped => out.push(String::new()),
            _ => out.last_mut().expect("a cell").push(c),
        }
        escaped = c == '\\';
    }
    out.iter().map(|c| c.trim().to_string()).collect()
}

/// Section name → the keys of its `| key | …` tables, in document order; every key table
/// belongs to the last heading above it, which must name a section.
fn documented_keys(doc: &str) -> BTreeMap<String, Vec<String>> {
    let mut out: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut section: Option<String> = None;
    let mut in_table = false;
    let mut in_fence = false;
    for (i, line) in doc.lines().enumerate() {
        let line_no = i + 1;
        if line.starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        if line.starts_with('#') {
            section = first_code_span(line).map(str::to_string);
            in_table = false;
            continue;
        }
        if !line.starts_with('|') {
            in_table = false;
            continue;
        }
        let cells = cells(line);
        let cells: Vec<&str> = cells.iter().map(String::as_str).collect();
        if cells.first() == Some(&"key") {
            let name = section.clone().unwrap_or_else(|| {
                panic!("docs/case-file.md:{line_no}: a key table under a heading without a section name in a code span")
            });
            assert!(
                !out.contains_key(&name),
                "docs/case-file.md:{line_no}: a second key table for {name}"
            );
            out.insert(name, Vec::new());
            in_table = true;
            continue;
        }
        if !in_table || cells.iter().all(|c| c.chars().all(|ch| ch == '-')) {
            continue;
        }
        let name = section.clone().expect("in a key table");
        let key = first_code_span(cells[0]).unwrap_or_else(|| {
            panic!("docs/case-file.md:{line_no}: the key column holds no `key`: {line}")
        });
        assert!(
            cells.len() == 4 && cells[1..].iter().all(|c| !c.is_empty()),
            "docs/case-file.md:{line_no}: a row needs key, type, default and meaning: {line}"
        );
        out.get_mut(&name)
            .expect("table started")
            .push(key.to_string());
    }
    out
}

#[test]
fn the_case_file_reference_lists_exactly_the_accepted_keys() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/case-file.md");
    let doc = std::fs::read_to_string(&path).expect("docs/case-file.md");
    let documented = documented_keys(&doc);
    let mut problems = Vec::new();
    for (section, keys) in SECTIONS {
        let Some(doc_keys) = documented.get(*section) else {
            problems.push(format!("{section}: no key table in the document"));
            continue;
        };
        let accepted: BTreeSet<&str> = keys.iter().copied().collect();
        let listed: BTreeSet<&str> = doc_keys.iter().map(String::as_str).collect();
        if listed.len() != doc_keys.len() {
            problems.push(format!("{section}: a key listed twice: {doc_keys:?}"));
        }
        for k in accepted.difference(&listed) {
            problems.push(format!("{section}: `{k}` is accepted but not documented"));
        }
        for k in listed.difference(&accepted) {
            problems.push(format!("{section}: `{k}` is documented but not accepted"));
        }
    }
    let known: BTreeSet<&str> = SECTIONS.iter().map(|(s, _)| *s).collect();
    for section in documented.keys() {
        if !known.contains(section.as_str()) {
            problems.push(format!(
                "{section}: a key table in the document for no table of the reader"
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "docs/case-file.md against src/case/keys.rs:\n{}",
        problems.join("\n")
    );
}

/// The parser itself: a key table under a named heading, fences and other tables ignored.
#[test]
fn the_parser_reads_key_tables_by_heading() {
    let doc = "# Title\n\n## `[a]`\n\n| key | type | default | meaning |\n|---|---|---|---|\n\
               | `x` | number | 1 | the x, \\|x\\| |\n| `y` | string | — | the y, with `code` |\n\n\
               ```toml\n| key | not | a | table |\n```\n\n| other | table |\n|---|---|\n| `z` | no |\n";
    let got = documented_keys(doc);
    assert_eq!(got.len(), 1, "{got:?}");
    assert_eq!(got["[a]"], vec!["x", "y"]);
}
