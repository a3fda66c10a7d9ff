//! Case-file reader: the bytes before a first NUL are the TOML text, the lines after it are
//! `--set` overrides. Any input must give a case or an `InputError`, never a panic, a stack
//! overflow or a hang.
#![no_main]

use libfuzzer_sys::fuzz_target;
use signorini_mpi_fuzz::case::Case;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let (text, rest) = match data.iter().position(|&b| b == 0) {
        Some(p) => (&data[..p], &data[p + 1..]),
        None => (data, &data[..0]),
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let overrides: Vec<String> = String::from_utf8_lossy(rest)
        .lines()
        .filter(|l| !l.is_empty())
        .map(str::to_string)
        .collect();
    if let Ok(case) = Case::parse(text, Path::new("fuzz/case.toml"), &overrides, None) {
        for d in [2, 3] {
            let _ = case.model(d);
            let groups = [("left".to_string(), d - 1), ("body".to_string(), d)];
            let _ = case.check_against_mesh(d, &groups);
        }
    }
});
