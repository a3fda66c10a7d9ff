//! The validation context: typed reading of the value tree, errors naming the key.

use std::path::Path;

use super::tree::{join_index, join_key, Kind, Loc, Node};
use crate::error::InputError;

/// Validation context: builds errors that name the file.
pub(super) struct Reader<'a> {
    pub(super) file: &'a Path,
}

pub(super) type Res<T> = Result<T, InputError>;

/// A table node being read, with its key path.
pub(super) struct Tab<'n> {
    pub(super) key: String,
    pub(super) loc: Loc,
    pub(super) entries: &'n [(String, Node)],
}

impl<'n> Tab<'n> {
    pub(super) fn get(&self, k: &str) -> Option<(String, &'n Node)> {
        self.entries
            .iter()
            .find(|(name, _)| name == k)
            .map(|(name, n)| (join_key(&self.key, name), n))
    }
}

pub(super) fn list(xs: &[&str]) -> String {
    xs.join(", ")
}

impl Reader<'_> {
    pub(super) fn err(&self, key: &str, loc: Loc, msg: impl Into<String>) -> InputError {
        let mut msg = msg.into();
        let line = match loc {
            Loc::Line(l) => Some(l),
            Loc::Set => {
                msg.push_str(" (from --set)");
                None
            }
            Loc::Unknown => None,
        };
        let e = InputError::new(self.file, msg).with_line(line);
        if key.is_empty() {
            e
        } else {
            e.with_key(key)
        }
    }

    pub(super) fn type_err(&self, key: &str, n: &Node, expected: &str) -> InputError {
        let mut msg = format!("expected {expected}, found {}", n.type_name());
        if let (Loc::Set, Kind::Str(s)) = (n.loc, &n.kind) {
            if s.starts_with('[') || s.starts_with('{') {
                msg.push_str(
                    " (the value is not valid TOML, so it was taken as a string; \
                     quote the strings inside arrays and tables)",
                );
            }
        }
        self.err(key, n.loc, msg)
    }

    /// The node as a table, keys not checked.
    pub(super) fn table_any<'n>(&self, key: &str, n: &'n Node) -> Res<Tab<'n>> {
        match &n.kind {
            Kind::Table(entries) => Ok(Tab {
                key: key.to_string(),
                loc: n.loc,
                entries,
            }),
            _ => Err(self.type_err(key, n, "a table")),
        }
    }

    /// The node as a table whose keys are all in `allowed`.
    pub(super) fn table<'n>(&self, key: &str, n: &'n Node, allowed: &[&str]) -> Res<Tab<'n>> {
        let Kind::Table(entries) = &n.kind else {
            return Err(self.type_err(key, n, "a table"));
        };
        for (k, v) in entries {
            if !allowed.contains(&k.as_str()) {
                let where_ = if key.is_empty() {
                    "at the top level".to_string()
                } else {
                    format!("in [{key}]")
                };
                return Err(self.err(
                    &join_key(key, k),
                    v.loc,
                    format!("unknown key {where_}; allowed keys: {}", list(allowed)),
                ));
            }
        }
        Ok(Tab {
            key: key.to_string(),
            loc: n.loc,
            entries,
        })
    }

    pub(super) fn required<'n>(&self, t: &Tab<'n>, k: &str) -> Res<(String, &'n Node)> {
        t.get(k).ok_or_else(|| {
            let what = if t.key.is_empty() {
                format!("missing required section [{k}]")
            } else {
                "missing required key".to_string()
            };
            let loc = if t.key.is_empty() {
                Loc::Unknown
            } else {
                t.loc
            };
            self.err(&join_key(&t.key, k), loc, what)
        })
    }

    pub(super) fn num(&self, key: &str, n: &Node) -> Res<f64> {
        let x = match n.kind {
            Kind::Float(x) => x,
            Kind::Int(i) => i as f64,
            _ => return Err(self.type_err(key, n, "a number")),
        };
        if !x.is_finite() {
            return Err(self.err(key, n.loc, format!("must be a finite number, got {x}")));
        }
        Ok(x)
    }

    pub(super) fn positive(&self, key: &str, n: &Node) -> Res<f64> {
        let x = self.num(key, n)?;
        if x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, n.loc, format!("must be > 0, got {x}")))
        }
    }

    pub(super) fn boolean(&self, key: &str, n: &Node) -> Res<bool> {
        match n.kind {
            Kind::Bool(b) => Ok(b),
            _ => Err(self.type_err(key, n, "a boolean (true or false)")),
        }
    }

    pub(super) fn string<'n>(&self, key: &str, n: &'n Node) -> Res<&'n str> {
        match &n.kind {
            Kind::Str(s) => Ok(s),
            _ => Err(self.type_err(key, n, "a string")),
        }
    }

    pub(super) fn name(&self, key: &str, n: &Node) -> Res<String> {
        let s = self.string(key, n)?;
        if s.trim().is_empty() {
            Err(self.err(key, n.loc, "must not be empty"))
        } else {
            Ok(s.to_string())
        }
    }

    pub(super) fn choice<T: Copy>(&self, key: &str, n: &Node, options: &[(&str, T)]) -> Res<T> {
        let s = self.string(key, n)?;
        options
            .iter()
            .find(|(name, _)| *name == s)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let names: Vec<String> = options.iter().map(|(o, _)| format!("\"{o}\"")).collect();
                self.err(
                    key,
                    n.loc,
                    format!("unknown value \"{s}\"; allowed: {}", names.join(", ")),
                )
            })
    }

    pub(super) fn array<'n>(&self, key: &str, n: &'n Node, expected: &str) -> Res<&'n [Node]> {
        match &n.kind {
            Kind::Array(v) => Ok(v),
            _ => Err(self.type_err(key, n, expected)),
        }
    }

    pub(super) fn check_len(&self, key: &str, n: &Node, len: usize) -> Res<()> {
        if len == 2 || len == 3 {
            Ok(())
        } else {
            Err(self.err(
                key,
                n.loc,
                format!("expected 2 or 3 components (one per dimension), got {len}"),
            ))
        }
    }

    /// A vector of 2 or 3 numbers.
    pub(super) fn vector(&self, key: &str, n: &Node) -> Res<Vec<f64>> {
        let elems = self.array(key, n, "an array of numbers")?;
        self.check_len(key, n, elems.len())?;
        elems
            .iter()
            .enumerate()
            .map(|(i, e)| self.num(&join_index(key, i), e))
            .collect()
    }
}
