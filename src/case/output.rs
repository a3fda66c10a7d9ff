//! `[output]`.

use std::path::{Path, PathBuf};

use super::keys;
use super::reader::{list, Reader, Res, Tab};
use super::tree::join_index;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum OutputField {
    Displacement,
    Stress,
    VonMises,
    VonMisesThesis,
    Rank,
    Body,
    Contact,
}

impl OutputField {
    pub const ALL: [OutputField; 7] = [
        OutputField::Displacement,
        OutputField::Stress,
        OutputField::VonMises,
        OutputField::VonMisesThesis,
        OutputField::Rank,
        OutputField::Body,
        OutputField::Contact,
    ];

    /// The spelling used in the case file.
    pub fn name(self) -> &'static str {
        match self {
            OutputField::Displacement => "displacement",
            OutputField::Stress => "stress",
            OutputField::VonMises => "von_mises",
            OutputField::VonMisesThesis => "von_mises_thesis",
            OutputField::Rank => "rank",
            OutputField::Body => "body",
            OutputField::Contact => "contact",
        }
    }

    fn from_name(s: &str) -> Option<OutputField> {
        OutputField::ALL.into_iter().find(|f| f.name() == s)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct OutputSection {
    /// Relative to the working directory.
    pub dir: PathBuf,
    /// Requested fields, in file order, without duplicates.
    pub fields: Vec<OutputField>,
}

impl OutputSection {
    pub fn wants(&self, f: OutputField) -> bool {
        self.fields.contains(&f)
    }
}

/// The default `output.fields`.
pub const DEFAULT_FIELDS: [OutputField; 3] = [
    OutputField::Displacement,
    OutputField::VonMises,
    OutputField::Contact,
];

impl Reader<'_> {
    pub(super) fn output(&self, top: &Tab, output_dir: Option<&Path>) -> Res<OutputSection> {
        let stem = self
            .file
            .file_stem()
            .map_or_else(|| "case".into(), |s| s.to_string_lossy().into_owned());
        let mut out = OutputSection {
            dir: Path::new("out").join(stem),
            fields: DEFAULT_FIELDS.to_vec(),
        };
        if let Some((k, n)) = top.get("output") {
            let t = self.table(&k, n, keys::OUTPUT)?;
            if let Some((dk, d)) = t.get("dir") {
                out.dir = PathBuf::from(self.name(&dk, d)?);
            }
            if let Some((fk, f)) = t.get("fields") {
                let elems = self.array(&fk, f, "an array of field names")?;
                let mut fields = Vec::new();
                for (i, e) in elems.iter().enumerate() {
                    let ek = join_index(&fk, i);
                    let s = self.string(&ek, e)?;
                    let Some(field) = OutputField::from_name(s) else {
                        let names: Vec<&str> = OutputField::ALL.iter().map(|f| f.name()).collect();
                        return Err(self.err(
                            &ek,
                            e.loc,
                            format!("unknown field \"{s}\"; allowed: {}", list(&names)),
                        ));
                    };
                    if !fields.contains(&field) {
                        fields.push(field);
                    }
                }
                out.fields = fields;
            }
        }
        if let Some(d) = output_dir {
            out.dir = d.to_path_buf();
        }
        Ok(out)
    }
}
