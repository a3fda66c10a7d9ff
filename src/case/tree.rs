//! A small owned TOML value tree that remembers where every key came from (a line of the
//! case file, or a `--set` override), so validation errors can point at the right place.

use std::collections::BTreeMap;
use std::ops::Range;

use toml_edit::{ImDocument, Item, Table, Value};

/// Where a key or value came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Loc {
    /// 1-based line in the case file.
    Line(usize),
    /// Given on the command line with `--set`.
    Set,
    /// Not known (e.g. a table that only exists implicitly).
    Unknown,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Kind {
    Str(String),
    Int(i64),
    Float(f64),
    Bool(bool),
    Datetime,
    Array(Vec<Node>),
    Table(Vec<(String, Node)>),
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Node {
    pub kind: Kind,
    pub loc: Loc,
}

impl Node {
    fn new(kind: Kind, loc: Loc) -> Self {
        Node { kind, loc }
    }

    pub fn empty_table(loc: Loc) -> Self {
        Node::new(Kind::Table(Vec::new()), loc)
    }

    /// "a string", "an integer", ... for type errors.
    pub fn type_name(&self) -> &'static str {
        match self.kind {
            Kind::Str(_) => "a string",
            Kind::Int(_) => "an integer",
            Kind::Float(_) => "a float",
            Kind::Bool(_) => "a boolean",
            Kind::Datetime => "a datetime",
            Kind::Array(_) => "an array",
            Kind::Table(_) => "a table",
        }
    }

    fn set_loc_recursive(&mut self, loc: Loc) {
        self.loc = loc;
        match &mut self.kind {
            Kind::Array(v) => v.iter_mut().for_each(|n| n.set_loc_recursive(loc)),
            Kind::Table(v) => v.iter_mut().for_each(|(_, n)| n.set_loc_recursive(loc)),
            _ => {}
        }
    }
}

/// Byte offset → 1-based line number.
pub(crate) struct LineIndex {
    starts: Vec<usize>,
}

impl LineIndex {
    pub fn new(text: &str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { starts }
    }

    pub fn line(&self, offset: usize) -> usize {
        match self.starts.binary_search(&offset) {
            Ok(i) => i + 1,
            Err(i) => i,
        }
    }

    fn loc(&self, span: Option<Range<usize>>, fallback: Loc) -> Loc {
        span.map_or(fallback, |s| Loc::Line(self.line(s.start)))
    }
}

/// Parses TOML text into a tree; on a syntax error returns (line, one-line message).
pub(crate) fn parse(text: &str) -> Result<Node, (Option<usize>, String)> {
    let lines = LineIndex::new(text);
    let doc = ImDocument::parse(text).map_err(|e| {
        let line = e.span().map(|s| lines.line(s.start));
        let msg = e
            .message()
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join("; ");
        (line, format!("TOML syntax error: {msg}"))
    })?;
    Ok(from_table(doc.as_table(), Loc::Unknown, &lines))
}

fn from_table(t: &Table, fallback: Loc, lines: &LineIndex) -> Node {
    let loc = lines.loc(t.span(), fallback);
    let mut entries = Vec::new();
    for (k, item) in t.iter() {
        let key_loc = t
            .get_key_value(k)
            .and_then(|(key, _)| key.span())
            .map_or(loc, |s| Loc::Line(lines.line(s.start)));
        if let Some(node) = from_item(item, key_loc, lines) {
            entries.push((k.to_string(), node));
        }
    }
    Node::new(Kind::Table(entries), loc)
}

fn from_item(item: &Item, key_loc: Loc, lines: &LineIndex) -> Option<Node> {
    match item {
        Item::None => None,
        Item::Value(v) => {
            let mut n = from_value(v, key_loc, lines);
            // A key = value pair is reported at the key's line.
            if key_loc != Loc::Unknown {
                n.loc = key_loc;
            }
            Some(n)
        }
        Item::Table(t) => Some(from_table(t, key_loc, lines)),
        Item::ArrayOfTables(a) => {
            let elems = a.iter().map(|t| from_table(t, key_loc, lines)).collect();
            Some(Node::new(Kind::Array(elems), lines.loc(a.span(), key_loc)))
        }
    }
}

fn from_value(v: &Value, fallback: Loc, lines: &LineIndex) -> Node {
    let loc = lines.loc(v.span(), fallback);
    let kind = match v {
        Value::String(s) => Kind::Str(s.value().clone()),
        Value::Integer(i) => Kind::Int(*i.value()),
        Value::Float(f) => Kind::Float(*f.value()),
        Value::Boolean(b) => Kind::Bool(*b.value()),
        Value::Datetime(_) => Kind::Datetime,
        Value::Array(a) => Kind::Array(a.iter().map(|x| from_value(x, loc, lines)).collect()),
        Value::InlineTable(t) => {
            let mut entries = Vec::new();
            for (k, x) in t.iter() {
                let key_loc = t
                    .get_key_value(k)
                    .and_then(|(key, _)| key.span())
                    .map_or(loc, |s| Loc::Line(lines.line(s.start)));
                let mut n = from_value(x, key_loc, lines);
                n.loc = key_loc;
                entries.push((k.to_string(), n));
            }
            Kind::Table(entries)
        }
    };
    Node::new(kind, loc)
}

/// Human-readable key path: `a.b`, `a[0].b`.
pub(crate) fn join_key(parent: &str, key: &str) -> String {
    if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    }
}

pub(crate) fn join_index(parent: &str, i: usize) -> String {
    format!("{parent}[{i}]")
}

/// Parses the value part of a `--set key=value`: a TOML value if it parses as one,
/// otherwise the plain string.
fn parse_override_value(raw: &str) -> Node {
    let raw = raw.trim();
    let wrapped = format!("v = {raw}");
    let parsed = ImDocument::parse(wrapped.as_str()).ok().and_then(|doc| {
        let t = doc.as_table();
        if t.len() != 1 {
            return None;
        }
        match t.get("v") {
            Some(Item::Value(v)) => Some(from_value(v, Loc::Set, &LineIndex::new(""))),
            _ => None,
        }
    });
    let mut node = parsed.unwrap_or_else(|| Node::new(Kind::Str(raw.to_string()), Loc::Set));
    node.set_loc_recursive(Loc::Set);
    node
}

/// The most components a `--set` key path may have (the deepest key of the schema has 3;
/// the tree is walked recursively, so an unbounded path could overflow the stack).
pub(crate) const MAX_KEY_DEPTH: usize = 16;

/// Applies one `key.path=value` override to the tree. Missing tables (or arrays, when the
/// next component is an index) are created; a numeric component indexes an array, one past
/// the end appends a new entry.
/// Errors return (key path as far as understood, message).
pub(crate) fn apply_override(root: &mut Node, spec: &str) -> Result<(), (String, String)> {
    let Some((path, raw)) = spec.split_once('=') else {
        return Err((
            spec.trim().to_string(),
            format!("--set '{spec}': expected key.path=value"),
        ));
    };
    let path = bracket_indices(path.trim());
    let path = path.as_str();
    let segs: Vec<&str> = path.split('.').map(str::trim).collect();
    if segs.len() > MAX_KEY_DEPTH {
        let head: String = path.chars().take(40).collect();
        return Err((
            format!("{head}..."),
            format!(
                "--set key path has {} components; a case file key has at most {MAX_KEY_DEPTH}",
                segs.len()
            ),
        ));
    }
    if segs.iter().any(|s| s.is_empty()) {
        return Err((
            path.to_string(),
            format!("--set '{spec}': empty component in key path"),
        ));
    }
    let value = parse_override_value(raw);
    let mut cur = root;
    let mut shown = String::new();
    for i in 0..segs.len() {
        cur = override_slot(cur, &segs, i, &mut shown)?;
        if i == segs.len() - 1 {
            *cur = value;
            return Ok(());
        }
    }
    Ok(())
}

/// A key path with its array indices written as the messages write them, `contact[0].group`,
/// in the dotted form `contact.0.group` (only digits between the brackets). Pure.
fn bracket_indices(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    let mut rest = path;
    while let Some(open) = rest.find('[') {
        let Some(len) = rest[open..].find(']') else {
            break;
        };
        let inner = &rest[open + 1..open + len];
        if inner.is_empty() || !inner.bytes().all(|b| b.is_ascii_digit()) {
            break;
        }
        out.push_str(&rest[..open]);
        out.push('.');
        out.push_str(inner);
        rest = &rest[open + len + 1..];
    }
    out.push_str(rest);
    out
}

/// The slot that component `i` of the `--set` key path `segs` names inside `cur`, created
/// where missing (a container created on the way is an array if the next component is an
/// index); `shown`, the key path as far as understood, takes the component. Errors return
/// (key path as far as understood, message).
fn override_slot<'n>(
    cur: &'n mut Node,
    segs: &[&str],
    i: usize,
    shown: &mut String,
) -> Result<&'n mut Node, (String, String)> {
    let seg = segs[i];
    let type_name = cur.type_name();
    let fresh = || match segs.get(i + 1).map(|s| s.parse::<usize>()) {
        Some(Ok(_)) => Node::new(Kind::Array(Vec::new()), Loc::Set),
        _ => Node::empty_table(Loc::Set),
    };
    match &mut cur.kind {
        Kind::Table(entries) => {
            *shown = join_key(shown, seg);
            let pos = match entries.iter().position(|(k, _)| k == seg) {
                Some(p) => p,
                None => {
                    entries.push((seg.to_string(), fresh()));
                    entries.len() - 1
                }
            };
            Ok(&mut entries[pos].1)
        }
        Kind::Array(elems) => {
            let Ok(idx) = seg.parse::<usize>() else {
                return Err((
                    shown.clone(),
                    format!("is an array; --set needs a numeric index after it, got '{seg}'"),
                ));
            };
            *shown = join_index(shown, idx);
            if idx > elems.len() {
                return Err((
                    shown.clone(),
                    format!(
                        "index out of range (the array has {} entries; use index {} to append)",
                        elems.len(),
                        elems.len()
                    ),
                ));
            }
            if idx == elems.len() {
                elems.push(fresh());
            }
            Ok(&mut elems[idx])
        }
        _ => Err((
            shown.clone(),
            format!(
                "is {}, so --set cannot set '{}' inside it",
                type_name,
                segs[i..].join(".")
            ),
        )),
    }
}

/// Records the location of every key path in the tree.
pub(crate) fn collect_locs(node: &Node, path: &str, out: &mut BTreeMap<String, Loc>) {
    if !path.is_empty() {
        out.insert(path.to_string(), node.loc);
    }
    match &node.kind {
        Kind::Table(entries) => {
            for (k, n) in entries {
                collect_locs(n, &join_key(path, k), out);
            }
        }
        Kind::Array(elems) => {
            for (i, n) in elems.iter().enumerate() {
                collect_locs(n, &join_index(path, i), out);
            }
        }
        _ => {}
    }
}
