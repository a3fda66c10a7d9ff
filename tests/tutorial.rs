//! docs/tutorial.md, run as written: its files are the ones in examples/tutorial/, every shell
//! block marked ```` ```sh tutorial ```` runs (in that order, in a fresh directory holding those
//! files, with this build's signorini-mpi and scripts/ on PATH), and every ```` ```text output ````
//! block after a step lists lines that step must print: each expected line matches one printed
//! line, in order, with `…` standing for any text and every number within its tolerance (the
//! last printed digit of the document's number, plus 0.1 %). The numbers are read from the
//! document; none is repeated here.

mod common;

use common::*;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// A fenced block of the tutorial: its info string (after the backticks) and its text.
struct Block {
    info: String,
    text: String,
    line: usize,
}

fn blocks(doc: &str) -> Vec<Block> {
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in doc.lines().enumerate() {
        match (&mut open, line.strip_prefix("```")) {
            (None, Some(info)) => {
                open = Some(Block {
                    info: info.trim().to_string(),
                    text: String::new(),
                    line: i + 1,
                })
            }
            (Some(_), Some(rest)) if rest.trim().is_empty() => out.push(open.take().unwrap()),
            (Some(b), _) => {
                b.text.push_str(line);
                b.text.push('\n');
            }
            (None, None) => {}
        }
    }
    assert!(open.is_none(), "docs/tutorial.md: a fence is not closed");
    out
}

/// One piece of an expected line.
#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Text(String),
    /// A number and its absolute tolerance (half a unit of its last digit).
    Num(f64, f64),
    /// `…`: any text.
    Any,
}

/// The number starting at byte `i` of `s` (optional sign, digits, optional fraction and
/// exponent): its value, its rounding tolerance and its length in bytes.
fn number_at(s: &str, i: usize) -> Option<(f64, f64, usize)> {
    let b = s.as_bytes();
    let mut j = i;
    if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
        j += 1;
    }
    let int_start = j;
    while j < b.len() && b[j].is_ascii_digit() {
        j += 1;
    }
    if j == int_start {
        return None;
    }
    let mut decimals = 0i32;
    if j + 1 < b.len() && b[j] == b'.' && b[j + 1].is_ascii_digit() {
        j += 1;
        while j < b.len() && b[j].is_ascii_digit() {
            j += 1;
            decimals += 1;
        }
    }
    let mut exponent = 0i32;
    if j < b.len() && (b[j] == b'e' || b[j] == b'E') {
        let mut k = j + 1;
        if k < b.len() && (b[k] == b'-' || b[k] == b'+') {
            k += 1;
        }
        let digits = k;
        while k < b.len() && b[k].is_ascii_digit() {
            k += 1;
        }
        if k > digits {
            exponent = s[j + 1..k].parse().expect("exponent");
            j = k;
        }
    }
    let value: f64 = s[i..j].parse().ok()?;
    let tol = 0.5 * 10f64.powi(exponent - decimals);
    Some((value, tol, j - i))
}

/// Is byte `i` of `s` the start of a number (not a digit inside a word such as `2D` or `L4`)?
fn starts_number(s: &str, i: usize) -> bool {
    let b = s.as_bytes();
    let digit_at = |k: usize| k < b.len() && b[k].is_ascii_digit();
    let sign = b[i] == b'-' || b[i] == b'+';
    let first_digit = if sign { i + 1 } else { i };
    if !digit_at(first_digit) {
        return false;
    }
    // a sign only where a number may start: after a space, '[', '(', ',' or '=' or at the start
    let before = if i == 0 { b' ' } else { b[i - 1] };
    if sign {
        return matches!(before, b' ' | b'[' | b'(' | b',' | b'=');
    }
    !(before.is_ascii_alphabetic() || before == b'_' || before == b'.')
}

fn tokens(line: &str) -> Vec<Tok> {
    let mut out = Vec::new();
    let mut text = String::new();
    let mut i = 0;
    while i < line.len() {
        if line[i..].starts_with('…') {
            if !text.is_empty() {
                out.push(Tok::Text(std::mem::take(&mut text)));
            }
            out.push(Tok::Any);
            i += '…'.len_utf8();
            continue;
        }
        if starts_number(line, i) {
            if let Some((v, tol, len)) = number_at(line, i) {
                if !text.is_empty() {
                    out.push(Tok::Text(std::mem::take(&mut text)));
                }
                out.push(Tok::Num(v, tol));
                i += len;
                continue;
            }
        }
        let c = line[i..].chars().next().expect("char");
        text.push(c);
        i += c.len_utf8();
    }
    if !text.is_empty() {
        out.push(Tok::Text(text));
    }
    out
}

/// Relative tolerance of every number on top of its rounding.
const RTOL: f64 = 1e-3;

/// Does `line` (from byte `at`) match the expected tokens as a whole?
fn matches(expected: &[Tok], line: &str, at: usize) -> bool {
    let Some((first, rest)) = expected.split_first() else {
        return at == line.len();
    };
    match first {
        Tok::Text(t) => line[at..].starts_with(t.as_str()) && matches(rest, line, at + t.len()),
        Tok::Num(v, tol) => {
            if !starts_number(line, at) {
                return false;
            }
            match number_at(line, at) {
                Some((got, _, len)) => {
                    (got - v).abs() <= tol + RTOL * v.abs() && matches(rest, line, at + len)
                }
                None => false,
            }
        }
        Tok::Any => (at..=line.len())
            .filter(|&k| line.is_char_boundary(k))
            .any(|k| matches(rest, line, k)),
    }
}

/// Every expected line matches a printed line, in order; the lines that do not, with the
/// printed line of the same beginning where there is one.
fn check_output(expected: &str, printed: &str) -> Vec<String> {
    let printed: Vec<&str> = printed.lines().map(str::trim_end).collect();
    let mut from = 0;
    let mut problems = Vec::new();
    for want in expected
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.is_empty())
    {
        let toks = tokens(want);
        match (from..printed.len()).find(|&k| matches(&toks, printed[k], 0)) {
            Some(k) => from = k + 1,
            None => {
                let head: String = want.chars().take(12).collect();
                let near = printed
                    .iter()
                    .find(|l| l.starts_with(&head))
                    .map_or(String::new(), |l| format!("\n    printed: {l}"));
                problems.push(format!("  expected: {want}{near}"));
            }
        }
    }
    problems
}

#[test]
fn the_matcher_compares_numbers_within_their_digits() {
    let t = tokens("load step 8/8: p_max = 0.043191, gaps -1.25e-3 to 2D …");
    assert!(matches(
        &t,
        "load step 8/8: p_max = 0.0431912, gaps -1.2500e-3 to 2D (0.5 s)",
        0
    ));
    assert!(!matches(
        &t,
        "load step 8/8: p_max = 0.0433, gaps -1.25e-3 to 2D",
        0
    ));
    assert!(!matches(
        &t,
        "load step 7/8: p_max = 0.043191, gaps -1.25e-3 to 2D",
        0
    ));
    assert_eq!(
        check_output("a 1\nb 2\n", "x\na 1.0004\ny\nb 2\n"),
        Vec::<String>::new()
    );
    assert_eq!(check_output("b 2\na 1\n", "a 1\nb 2\n").len(), 1);
}

#[test]
fn the_tutorial_runs_as_written() {
    let doc_path = repo("docs/tutorial.md");
    let doc = std::fs::read_to_string(&doc_path).expect("docs/tutorial.md");
    let blocks = blocks(&doc);
    let work = tempfile::tempdir().expect("tempdir");

    // The files the tutorial shows are those of examples/tutorial/, and the run starts from them.
    let mut files = 0;
    for b in &blocks {
        let Some(name) = b
            .info
            .split_whitespace()
            .find_map(|w| w.strip_prefix("file="))
        else {
            continue;
        };
        let committed = std::fs::read_to_string(repo(name))
            .unwrap_or_else(|e| panic!("docs/tutorial.md:{}: {name}: {e}", b.line));
        assert_eq!(
            b.text, committed,
            "docs/tutorial.md:{}: the block differs from {name}",
            b.line
        );
        let base = Path::new(name).file_name().expect("file name");
        std::fs::write(work.path().join(base), committed).expect("copy");
        files += 1;
    }
    assert!(files >= 2, "the tutorial shows its .geo and its case file");

    let bin_dir = binary().parent().expect("binary's directory").to_path_buf();
    let path = format!(
        "{}:{}:{}",
        bin_dir.display(),
        repo("scripts").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut steps = 0;
    let mut last: Option<(usize, String)> = None;
    let mut problems = Vec::new();
    for b in &blocks {
        let words: Vec<&str> = b.info.split_whitespace().collect();
        if words.first() == Some(&"sh") && words.contains(&"tutorial") {
            let missing = words
                .iter()
                .filter_map(|w| w.strip_prefix("needs="))
                .find(|tool| {
                    !Command::new("sh")
                        .args(["-c", &format!("command -v {tool}")])
                        .output()
                        .is_ok_and(|o| o.status.success())
                });
            if let Some(tool) = missing {
                eprintln!(
                    "docs/tutorial.md:{}: step skipped, {tool} is not installed",
                    b.line
                );
                last = None;
                continue;
            }
            let mut cmd = Command::new("bash");
            cmd.args(["-euo", "pipefail", "-c", &b.text])
                .current_dir(work.path())
                .env("PATH", &path);
            mpi_env(&mut cmd);
            let run = run_with_timeout(cmd, Duration::from_secs(600));
            assert_eq!(
                run.code,
                Some(0),
                "docs/tutorial.md:{}: the step failed\n{}",
                b.line,
                run.output()
            );
            steps += 1;
            last = Some((b.line, format!("{}{}", run.stdout, run.stderr)));
        } else if words.first() == Some(&"text") && words.contains(&"output") {
            if let Some((line, printed)) = &last {
                let p = check_output(&b.text, printed);
                if !p.is_empty() {
                    problems.push(format!(
                        "docs/tutorial.md:{} (the output of the step at line {line}):\n{}\n--- printed\n{printed}",
                        b.line,
                        p.join("\n")
                    ));
                }
            }
        }
    }
    assert!(steps >= 4, "only {steps} tutorial steps ran");
    assert!(problems.is_empty(), "{}", problems.join("\n\n"));
}
