//! MSH reader (ASCII and binary): any input must give a mesh or an `InputError`, never a
//! panic, an abort, an allocation beyond what the file size justifies, or a hang. The parser
//! panics that the reader normally catches are NOT caught here, so that they show as crashes.
#![no_main]

use libfuzzer_sys::fuzz_target;
use signorini_mpi_fuzz::mesh;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    mesh::set_catch_parser_panics(false);
    let path = Path::new("fuzz.msh");
    if let Ok(m) = mesh::read_msh_bytes(data, path) {
        // Exercise the boundary-group check on every facet group.
        for g in &m.groups {
            if g.dim + 1 == m.dim {
                let _ = m.check_boundary_group(path, &g.name, "fuzz");
            }
        }
        let _ = m.extent();
    }
});
