//! Every relative link of the README and of docs/*.md resolves: `](path)` names a file of the
//! repository and `](path#anchor)` a heading of that Markdown file (GitHub's anchors: lower
//! case, code ticks and punctuation dropped, spaces as '-', "-1", "-2"… for repeated headings).

mod common;
use common::*;
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The text outside fenced code blocks.
fn prose(text: &str) -> String {
    let mut fence = false;
    let mut out = String::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fence = !fence;
            continue;
        }
        if !fence {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

/// GitHub's anchor of a heading's text.
fn slug(heading: &str) -> String {
    // a link inside the heading counts by its text
    let mut text = String::new();
    let mut rest = heading.trim();
    while let Some(open) = rest.find('[') {
        text.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        match (after.find("]("), after.find(')')) {
            (Some(close), Some(end)) if close < end => {
                text.push_str(&after[..close]);
                rest = &after[end + 1..];
            }
            _ => {
                text.push('[');
                rest = after;
            }
        }
    }
    text.push_str(rest);
    text.to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

fn anchors(path: &Path) -> HashSet<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    let mut out = HashSet::new();
    for line in prose(&text).lines() {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let s = slug(&line[hashes + 1..]);
            let n = seen.entry(s.clone()).or_insert(0);
            out.insert(if *n == 0 {
                s.clone()
            } else {
                format!("{s}-{n}")
            });
            *n += 1;
        }
    }
    out
}

/// The targets of `](target)` in `text`.
fn link_targets(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        let after = &rest[i + 2..];
        let end = after
            .find(|c: char| c == ')' || c.is_whitespace())
            .unwrap_or(after.len());
        out.push(after[..end].to_string());
        rest = &after[end..];
    }
    out
}

fn documents() -> Vec<PathBuf> {
    let mut files = vec![repo("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

#[test]
fn every_link_of_the_readme_and_the_docs_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in documents() {
        let text = prose(&std::fs::read_to_string(&file).unwrap());
        for target in link_targets(&text) {
            let scheme = target.split(':').next().unwrap_or("");
            if target.contains(':') && scheme.chars().all(|c| c.is_ascii_lowercase()) {
                continue; // https:, mailto:
            }
            checked += 1;
            let (path, anchor) = target.split_once('#').unwrap_or((target.as_str(), ""));
            let dest = if path.is_empty() {
                file.clone()
            } else {
                file.parent().unwrap().join(path)
            };
            if !dest.exists() {
                broken.push(format!("{}: no file {target}", file.display()));
            } else if !anchor.is_empty()
                && dest.extension().is_some_and(|x| x == "md")
                && !anchors(&dest).contains(anchor)
            {
                broken.push(format!("{}: no heading for {target}", file.display()));
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} links found: the scan is broken"
    );
    assert!(
        broken.is_empty(),
        "{} broken link(s):\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn anchors_follow_githubs_rule() {
    assert_eq!(slug("The `reuse` path (2D, 3D)"), "the-reuse-path-2d-3d");
    assert_eq!(slug("See [method](method.md) here"), "see-method-here");
    assert_eq!(
        link_targets("a [x](b.md#c) and [y](d.md)"),
        vec!["b.md#c", "d.md"]
    );
}

#[test]
fn every_document_is_in_the_index() {
    let index = std::fs::read_to_string(repo("docs/README.md")).unwrap();
    let listed: HashSet<String> = link_targets(&index).into_iter().collect();
    for file in documents().iter().skip(1) {
        let name = file.file_name().unwrap().to_str().unwrap().to_string();
        if name != "README.md" {
            assert!(
                listed
                    .iter()
                    .any(|t| t.split('#').next() == Some(name.as_str())),
                "docs/README.md does not list {name}"
            );
        }
    }
}
