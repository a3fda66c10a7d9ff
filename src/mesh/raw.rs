//! Low-level scanning of the raw bytes of a `.msh` file for what `mshio` does not give us:
//! the format version (for a clear error on MSH 2.2), the `$PhysicalNames` section, the
//! presence of `$PartitionedEntities`, and the node tags that `mshio` drops when gmsh
//! numbers the nodes densely.

use std::collections::HashMap;

/// What the header scan found before the `$Nodes` section.
#[derive(Debug, Default)]
pub(crate) struct HeaderInfo {
    /// Version number as written in `$MeshFormat` (e.g. "4.1", "2.2").
    pub version: String,
    /// 0 = ASCII, 1 = binary.
    pub file_type: i32,
    /// Size of `size_t` in bytes (binary files).
    pub size_t_size: usize,
    /// Binary files: little endian (gmsh writes its native byte order).
    pub little_endian: bool,
    /// Physical names keyed by (dimension, physical tag).
    pub physical_names: HashMap<(usize, i32), String>,
    /// A `$PartitionedEntities` section was seen (gmsh -part).
    pub partitioned: bool,
    /// Byte offset of the `$Nodes` line, if found.
    pub nodes_offset: Option<usize>,
    /// Byte offset of the body of `$Entities`, if found.
    pub entities_offset: Option<usize>,
}

/// Smallest number of bytes one item of a section can take in the file, ASCII and binary
/// (`st` = size of `size_t`). A count announced in a section header times this must fit in
/// the rest of the file, else the count is corrupt (and must not size an allocation).
struct MinBytes {
    ascii: u64,
    binary_fixed: u64,
    binary_st: u64,
}

impl MinBytes {
    fn get(&self, binary: bool, st: usize) -> u64 {
        if binary {
            self.binary_fixed + self.binary_st * st as u64
        } else {
            self.ascii
        }
    }
}

/// An entity of `$Entities`: at least `tag x y z nphys` (a point; ASCII `1 0 0 0 0\n`).
const ENTITY: MinBytes = MinBytes {
    ascii: 10,
    binary_fixed: 28,
    binary_st: 1,
};
/// A block header of `$Nodes` / `$Elements`: `dim tag parametric|type count`.
const BLOCK: MinBytes = MinBytes {
    ascii: 8,
    binary_fixed: 12,
    binary_st: 1,
};
/// A node: its tag and three coordinates (ASCII `1\n0 0 0\n`).
const NODE: MinBytes = MinBytes {
    ascii: 8,
    binary_fixed: 24,
    binary_st: 1,
};
/// An element: its tag and at least one node tag (ASCII `1 1\n`).
const ELEMENT: MinBytes = MinBytes {
    ascii: 4,
    binary_fixed: 0,
    binary_st: 2,
};

/// Reads `n` unsigned header numbers at `pos` (ASCII tokens, or binary `size_t`s).
fn header_numbers(bytes: &[u8], pos: usize, n: usize, info: &HeaderInfo) -> Option<Vec<u64>> {
    let mut out = Vec::with_capacity(n);
    if info.file_type == 1 {
        let st = info.size_t_size;
        for k in 0..n {
            out.push(read_uint(bytes, pos + k * st, st, info.little_endian)?);
        }
    } else {
        let mut p = pos;
        for _ in 0..n {
            let s = skip_ws(bytes, p);
            let mut e = s;
            while e < bytes.len() && !bytes[e].is_ascii_whitespace() {
                e += 1;
            }
            out.push(std::str::from_utf8(&bytes[s..e]).ok()?.parse().ok()?);
            p = e;
        }
    }
    Some(out)
}

/// Checks that `counts` items (one `MinBytes` each) fit in the `available` bytes.
fn check_fits(
    section: &str,
    what: &[(&str, u64, &MinBytes)],
    available: usize,
    info: &HeaderInfo,
) -> Result<(), String> {
    let binary = info.file_type == 1;
    let mut need: u128 = 0;
    for (_, n, m) in what {
        need += u128::from(*n) * u128::from(m.get(binary, info.size_t_size));
    }
    if need > available as u128 {
        let list: Vec<String> = what.iter().map(|(w, n, _)| format!("{n} {w}")).collect();
        return Err(format!(
            "${section} announces {}, more than the {available} bytes after its header can \
             hold: the file is truncated or corrupt",
            list.join(" and ")
        ));
    }
    Ok(())
}

/// The unsigned integer of `size` (4 or 8) bytes at `p`.
fn read_uint(bytes: &[u8], p: usize, size: usize, le: bool) -> Option<u64> {
    let b = bytes.get(p..p.checked_add(size)?)?;
    Some(match size {
        4 => {
            let a = [b[0], b[1], b[2], b[3]];
            u64::from(if le {
                u32::from_le_bytes(a)
            } else {
                u32::from_be_bytes(a)
            })
        }
        8 => {
            let a: [u8; 8] = b.try_into().ok()?;
            if le {
                u64::from_le_bytes(a)
            } else {
                u64::from_be_bytes(a)
            }
        }
        _ => return None,
    })
}

/// Bounds the counts in the headers of `$Entities`, `$Nodes` and `$Elements` by the size of the file, before anything is allocated from
/// them. A header that cannot be read is left to the parser (which reports it).
pub(crate) fn check_section_counts(bytes: &[u8], info: &HeaderInfo) -> Result<(), String> {
    if let Some(pos) = info.entities_offset {
        if let Some(n) = header_numbers(bytes, pos, 4, info) {
            let body = pos
                + if info.file_type == 1 {
                    4 * info.size_t_size
                } else {
                    0
                };
            let total = n.iter().fold(0u64, |a, &x| a.saturating_add(x));
            check_fits(
                "Entities",
                &[("entities", total, &ENTITY)],
                bytes.len().saturating_sub(body),
                info,
            )?;
        }
    }
    // Every place the parser could take for the start of a $Nodes or $Elements section (it
    // reads all of them, and only then refuses a second one).
    let mut sections = Vec::new();
    for (name, items, min) in [
        ("Nodes", "nodes", &NODE),
        ("Elements", "elements", &ELEMENT),
    ] {
        let tag = format!("${name}");
        let mut from = 0;
        while let Some(p) = find_section(bytes, tag.as_bytes(), from) {
            sections.push((name, p, items, min));
            from = p + 1;
        }
    }
    for (name, at, items, min) in sections {
        let pos = next_line(bytes, at);
        let Some(n) = header_numbers(bytes, pos, 4, info) else {
            continue;
        };
        // (The MSH parser computes `count - 1`: a zero count must not reach it.)
        if n[1] == 0 {
            return Err(format!("${name} holds no {items}"));
        }
        let body = if info.file_type == 1 {
            pos + 4 * info.size_t_size
        } else {
            pos
        };
        check_fits(
            name,
            &[("entity blocks", n[0], &BLOCK), (items, n[1], min)],
            bytes.len().saturating_sub(body),
            info,
        )?;
    }
    Ok(())
}

/// Offset of the next `name` followed by an end of line (as the parser accepts a section
/// start: after any whitespace, or none), at or after `from`.
fn find_section(bytes: &[u8], name: &[u8], from: usize) -> Option<usize> {
    let mut i = from;
    while let Some(p) = find(bytes, name, i) {
        let after = bytes.get(p + name.len()).copied();
        if matches!(after, Some(b'\n' | b'\r')) {
            return Some(p);
        }
        i = p + 1;
    }
    None
}

/// Position of `needle` in `hay` at or after `from`.
fn find(hay: &[u8], needle: &[u8], from: usize) -> Option<usize> {
    if from >= hay.len() || needle.is_empty() {
        return None;
    }
    let first = needle[0];
    let mut i = from;
    while i + needle.len() <= hay.len() {
        match hay[i..].iter().position(|&b| b == first) {
            None => return None,
            Some(p) => {
                let s = i + p;
                if s + needle.len() > hay.len() {
                    return None;
                }
                if &hay[s..s + needle.len()] == needle {
                    return Some(s);
                }
                i = s + 1;
            }
        }
    }
    None
}

/// Offset just past the next newline at or after `from` (or the end).
fn next_line(bytes: &[u8], from: usize) -> usize {
    match bytes[from.min(bytes.len())..]
        .iter()
        .position(|&b| b == b'\n')
    {
        Some(p) => from + p + 1,
        None => bytes.len(),
    }
}

fn skip_ws(bytes: &[u8], mut i: usize) -> usize {
    while i < bytes.len() && bytes[i].is_ascii_whitespace() {
        i += 1;
    }
    i
}

/// Scans `$MeshFormat` and every section up to `$Nodes`. Errors are plain messages (the
/// caller adds the file name and a hint).
pub(crate) fn scan_header(bytes: &[u8]) -> Result<HeaderInfo, String> {
    let mut info = HeaderInfo::default();
    let start = skip_ws(bytes, 0);
    if !bytes[start..].starts_with(b"$MeshFormat") {
        return Err(format!(
            "not a Gmsh .msh file (it does not start with $MeshFormat); {}",
            super::HINT_MSH41
        ));
    }
    let line_start = next_line(bytes, start);
    let line_end = next_line(bytes, line_start);
    read_format_line(&bytes[line_start..line_end], &mut info)?;
    if info.file_type == 1 {
        info.little_endian = binary_little_endian(bytes, line_end)?;
    }
    let end_fmt = find(bytes, b"$EndMeshFormat", line_end).ok_or("no $EndMeshFormat")?;
    scan_sections(bytes, next_line(bytes, end_fmt), &mut info)?;
    Ok(info)
}

/// The version line of `$MeshFormat` (`line`): version, file type and data size, each
/// checked.
fn read_format_line(line: &[u8], info: &mut HeaderInfo) -> Result<(), String> {
    let line = String::from_utf8_lossy(line);
    let mut tok = line.split_whitespace();
    info.version = tok.next().unwrap_or("").to_string();
    info.file_type = tok.next().and_then(|t| t.parse().ok()).unwrap_or(-1);
    info.size_t_size = tok.next().and_then(|t| t.parse().ok()).unwrap_or(0);
    if info.version != "4.1" {
        return Err(format!(
            "unsupported MSH format version '{}' (only MSH 4.1 is read); {}",
            info.version,
            super::HINT_MSH41
        ));
    }
    // The MSH parser panics on a data size it has no reader for (or one that overflows), so
    // the header is checked here first. gmsh writes sizeof(size_t) = 8.
    if info.file_type != 0 && info.file_type != 1 {
        return Err(format!(
            "$MeshFormat: file type '{}' is neither 0 (ASCII) nor 1 (binary)",
            line.split_whitespace().nth(1).unwrap_or("")
        ));
    }
    if info.size_t_size != 4 && info.size_t_size != 8 {
        return Err(format!(
            "$MeshFormat: data size '{}' is not supported (gmsh writes 8)",
            line.split_whitespace().nth(2).unwrap_or("")
        ));
    }
    Ok(())
}

/// A binary file's byte order, from the endianness check value (int 1) at `at`, right after
/// the version line.
fn binary_little_endian(bytes: &[u8], at: usize) -> Result<bool, String> {
    let b = bytes
        .get(at..at + 4)
        .ok_or("truncated $MeshFormat section")?;
    let le = i32::from_le_bytes([b[0], b[1], b[2], b[3]]);
    let be = i32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    if le != 1 && be != 1 {
        return Err("$MeshFormat: binary file without the endianness check value 1".into());
    }
    Ok(be != 1)
}

/// Walks the sections from `pos` to `$Nodes` (or `$Elements`): they are small
/// ($PhysicalNames, $Entities, $PartitionedEntities, ...); records what `info` keeps of them.
fn scan_sections(bytes: &[u8], mut pos: usize, info: &mut HeaderInfo) -> Result<(), String> {
    let mut entities = None;
    loop {
        pos = skip_ws(bytes, pos);
        if pos >= bytes.len() {
            break;
        }
        if bytes[pos] != b'$' {
            return Err(format!(
                "unexpected content at byte {pos} (expected a $Section)"
            ));
        }
        let name_end = bytes[pos..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .map_or(bytes.len(), |p| pos + p);
        let name = &bytes[pos + 1..name_end];
        if name == b"Nodes" || name == b"Elements" {
            if name == b"Nodes" {
                info.nodes_offset = Some(pos);
            }
            break;
        }
        let mut end_tag = b"$End".to_vec();
        end_tag.extend_from_slice(name);
        let body_start = next_line(bytes, pos);
        let end = find(bytes, &end_tag, body_start).ok_or_else(|| {
            format!(
                "section ${} has no {}",
                String::from_utf8_lossy(name),
                String::from_utf8_lossy(&end_tag)
            )
        })?;
        match name {
            b"PhysicalNames" => {
                info.physical_names = parse_physical_names(&bytes[body_start..end])?;
            }
            b"PartitionedEntities" => info.partitioned = true,
            b"Entities" => entities = Some(body_start),
            _ => {}
        }
        pos = next_line(bytes, end);
    }
    info.entities_offset = entities;
    Ok(())
}

/// Parses the body of `$PhysicalNames` (always text): a count, then `dim tag "name"` lines.
fn parse_physical_names(body: &[u8]) -> Result<HashMap<(usize, i32), String>, String> {
    let text = std::str::from_utf8(body).map_err(|_| "$PhysicalNames is not valid UTF-8")?;
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let count = lines.next().ok_or("$PhysicalNames: missing count")?;
    let n: u64 = count
        .parse()
        .map_err(|_| format!("$PhysicalNames: cannot read the count '{count}'"))?;
    let lines: Vec<&str> = lines.collect();
    if n > lines.len() as u64 {
        return Err(format!(
            "$PhysicalNames announces {n} names, but the section has {} lines: the file \
             is corrupt",
            lines.len()
        ));
    }
    let mut names = HashMap::with_capacity(n as usize);
    for l in lines.into_iter().take(n as usize) {
        let bad = || format!("$PhysicalNames: cannot read line '{l}'");
        let mut parts = l.splitn(3, char::is_whitespace);
        let dim: usize = parts.next().and_then(|t| t.parse().ok()).ok_or_else(bad)?;
        let tag: i32 = parts.next().and_then(|t| t.parse().ok()).ok_or_else(bad)?;
        let rest = parts.next().ok_or_else(bad)?.trim();
        let name = rest
            .strip_prefix('"')
            .and_then(|r| r.strip_suffix('"'))
            .unwrap_or(rest);
        names.insert((dim, tag), name.to_string());
    }
    Ok(names)
}

/// Reads the node tags of the `$Nodes` section in file order (both ASCII and binary).
/// Used only when `mshio` dropped them (dense numbering), to avoid assuming that the
/// nodes are stored in tag order. Returns `None` if the layout is not as expected.
pub(crate) fn scan_node_tags(bytes: &[u8], info: &HeaderInfo) -> Option<Vec<u64>> {
    let start = next_line(bytes, info.nodes_offset?);
    if info.file_type == 1 {
        scan_node_tags_binary(bytes, start, info)
    } else {
        scan_node_tags_ascii(bytes, start)
    }
}

fn scan_node_tags_ascii(bytes: &[u8], start: usize) -> Option<Vec<u64>> {
    let mut pos = start;
    let mut token = || -> Option<&[u8]> {
        let s = skip_ws(bytes, pos);
        let mut e = s;
        while e < bytes.len() && !bytes[e].is_ascii_whitespace() {
            e += 1;
        }
        pos = e;
        (e > s).then(|| &bytes[s..e])
    };
    fn int(t: &[u8]) -> Option<u64> {
        std::str::from_utf8(t).ok()?.parse().ok()
    }
    let n_blocks = int(token()?)?;
    let n_nodes = int(token()?)?;
    token()?;
    token()?;
    // Each node takes at least 6 bytes ("1\n0 0 0"): a larger count is corrupt.
    if n_nodes > (bytes.len() / 6) as u64 {
        return None;
    }
    let mut tags = Vec::with_capacity(n_nodes as usize);
    for _ in 0..n_blocks {
        token()?; // entity dim
        token()?; // entity tag
        let parametric = int(token()?)?;
        if parametric != 0 {
            return None;
        }
        let n = int(token()?)?;
        for _ in 0..n {
            tags.push(int(token()?)?);
        }
        for _ in 0..n.checked_mul(3)? {
            token()?;
        }
    }
    (tags.len() as u64 == n_nodes).then_some(tags)
}

fn scan_node_tags_binary(bytes: &[u8], start: usize, info: &HeaderInfo) -> Option<Vec<u64>> {
    let le = info.little_endian;
    let st = info.size_t_size;
    let read_u = |p: usize, size: usize| read_uint(bytes, p, size, le);
    let mut p = start;
    let n_blocks = read_u(p, st)?;
    let n_nodes = read_u(p + st, st)?;
    p += 4 * st;
    // Each node takes st + 24 bytes: a larger count is corrupt.
    if n_nodes > (bytes.len() / (st + 24)) as u64 {
        return None;
    }
    let mut tags = Vec::with_capacity(n_nodes as usize);
    for _ in 0..n_blocks {
        let parametric = read_u(p.checked_add(8)?, 4)?;
        if parametric != 0 {
            return None;
        }
        let n = usize::try_from(read_u(p + 12, st)?).ok()?;
        p += 12 + st;
        if p.checked_add(n.checked_mul(st + 24)?)? > bytes.len() {
            return None;
        }
        for i in 0..n {
            tags.push(read_u(p + i * st, st)?);
        }
        p += n * st + n * 24;
    }
    (tags.len() as u64 == n_nodes).then_some(tags)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn physical_names_with_spaces_and_repeated_tags() {
        let body = b"3\n1 1 \"left side\"\n2 1 \"body\"\n1 2 right\n";
        let names = parse_physical_names(body).unwrap();
        assert_eq!(names[&(1, 1)], "left side");
        assert_eq!(names[&(2, 1)], "body");
        assert_eq!(names[&(1, 2)], "right");
    }

    #[test]
    fn find_substring() {
        assert_eq!(find(b"ab$End$EndX", b"$EndX", 0), Some(6));
        assert_eq!(find(b"ab$End", b"$EndX", 0), None);
    }
}
