//! Generates the PETSc FFI bindings with bindgen against Debian's petsc-dev (PETSc 3.18),
//! plus the few PT-Scotch calls the partitioner makes directly (libptscotch-dev, the library
//! PETSc itself is built with). MPI types are blocklisted and taken from `mpi-sys`, so
//! PETSc's, PT-Scotch's and rsmpi's communicators are the same Rust type.

use std::env;
use std::path::PathBuf;

/// A cluster's own PETSc: PETSC_DIR (and PETSC_ARCH) put its pkg-config directory first.
fn use_petsc_dir() {
    for v in [
        "PETSC_DIR",
        "PETSC_ARCH",
        "MPI_INCLUDE_DIR",
        "SCOTCH_INCLUDE_DIR",
        "SCOTCH_LIB_DIR",
        "PKG_CONFIG_PATH",
    ] {
        println!("cargo:rerun-if-env-changed={v}");
    }
    let Ok(dir) = env::var("PETSC_DIR") else {
        return;
    };
    let mut dirs = vec![PathBuf::from(&dir).join("lib/pkgconfig")];
    if let Ok(arch) = env::var("PETSC_ARCH") {
        dirs.insert(0, PathBuf::from(&dir).join(arch).join("lib/pkgconfig"));
    }
    let mut path: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    if let Ok(old) = env::var("PKG_CONFIG_PATH") {
        path.push(old);
    }
    env::set_var("PKG_CONFIG_PATH", path.join(":"));
}

/// MPI's include directories: MPI_INCLUDE_DIR if given, else pkg-config ompi-c (Open MPI)
/// or mpich.
fn mpi_includes() -> Vec<PathBuf> {
    if let Ok(d) = env::var("MPI_INCLUDE_DIR") {
        return env::split_paths(&d).collect();
    }
    for name in ["ompi-c", "mpich"] {
        if let Ok(lib) = pkg_config::Config::new().cargo_metadata(false).probe(name) {
            return lib.include_paths;
        }
    }
    panic!(
        "no MPI headers found: install libopenmpi-dev (scripts/setup does), or set \
         MPI_INCLUDE_DIR to the directory of mpi.h"
    );
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    use_petsc_dir();
    let petsc = pkg_config::Config::new().probe("PETSc").expect(
        "pkg-config PETSc failed: install petsc-dev (scripts/setup does), or set PETSC_DIR \
         (and PETSC_ARCH) to a PETSc build",
    );
    let mpi_include = mpi_includes();
    for dir in &petsc.link_paths {
        println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display());
    }

    let header = r#"
#include <petscsys.h>
#include <petscvec.h>
#include <petscmat.h>
#include <petscksp.h>
#include <petscpc.h>
#include <petscis.h>
#include <petscsnes.h>
#include <stdio.h>
#include <ptscotch.h>
"#;
    let mut builder = bindgen::Builder::default()
        .header_contents("petsc_wrapper.h", header)
        .default_enum_style(bindgen::EnumVariation::Consts)
        .prepend_enum_name(false)
        .layout_tests(false)
        .generate_comments(false)
        .allowlist_function("PETSC_VIEWER_STDOUT_")
        .allowlist_function("Petsc(Initialize|Finalize|Initialized|ErrorMessage|Options.*|ObjectSetOptions|ObjectReference|MemoryGetCurrentUsage|MemoryGetMaximumUsage|MemorySetGetMaximumUsage|LogDefaultBegin|LogView|ViewerASCIIGetStdout|PopErrorHandler|MallocA|FreeA|PushErrorHandler|ReturnErrorHandler|GetVersion)")
        .allowlist_function("(Vec|Mat|KSP|PC|IS|MatPartitioning|MatNullSpace|PetscViewer)[A-Z].*")
        // SNES VI (src/snesvi.rs): only what the linear variational inequality needs.
        .allowlist_function("SNES(Create|Destroy|SetType|GetType|SetFunction|SetJacobian|SetFromOptions|SetTolerances|Solve|GetIterationNumber|GetLinearSolveIterations|GetConvergedReason|GetConvergedReasonString|GetNumberFunctionEvals|VISetVariableBounds|GetFunctionNorm|GetLineSearch|LineSearchSetType|GetKSP)")
        .allowlist_var("SNES(VINEWTON(RS|SS)LS|LINESEARCHBASIC|LINESEARCHBT)")
        .allowlist_var("PETSC_.*")
        .allowlist_var("(MAT|KSP|PC|VEC|IS)[A-Z_]+.*")
        .allowlist_var("(INSERT|ADD)_VALUES")
        .allowlist_var("NORM_.*")
        .allowlist_var("SCATTER_.*")
        .allowlist_type("Petsc.*")
        .allowlist_type("(Mat|Vec|KSP|PC|IS|InsertMode|NormType|MatAssemblyType|MatOption|MatReuse|MatInfo.*|ScatterMode|KSPConvergedReason|MatPartitioning|SNES|SNESConvergedReason)")
        // PT-Scotch: a distributed graph partitioned under an explicit context (threads,
        // determinism, seed); see petsc::scotch_partition.
        .allowlist_function(
            "SCOTCH_(context(Init|Exit|OptionSetNum|RandomClone|RandomSeed|ThreadSpawn|BindDgraph|BindGraph)|dgraph(Init|Exit|Build|Check|Part)|graph(Init|Exit|Build|Check|Order)|strat(Init|Exit|DgraphMapBuild|GraphOrderBuild))",
        )
        .allowlist_var("SCOTCH_(STRAT|OPTIONNUM)[A-Z]+")
        .allowlist_type("SCOTCH_(Num|Context|Dgraph|Graph|Strat)")
        .blocklist_type("MPI_.*")
        .blocklist_type("ompi_.*")
        .blocklist_item("FP_.*")
        .blocklist_function("Mat.*Device.*")
        .blocklist_function(".*(CUDA|Cuda|HIP|Hip|Kokkos|ViennaCL|SYCL|Sycl).*");
    for p in petsc.include_paths.iter().chain(mpi_include.iter()) {
        builder = builder.clang_arg(format!("-I{}", p.display()));
    }
    // Debian's default PT-Scotch (32-bit SCOTCH_Num, like PETSc's PetscInt), the one libpetsc
    // links; its headers live in their own directory.
    let scotch_include =
        env::var("SCOTCH_INCLUDE_DIR").unwrap_or_else(|_| "/usr/include/scotch".into());
    assert!(
        std::path::Path::new(&scotch_include)
            .join("ptscotch.h")
            .exists(),
        "{scotch_include}/ptscotch.h not found: install libptscotch-dev (petsc-dev pulls it in)"
    );
    builder = builder.clang_arg(format!("-I{scotch_include}"));
    if let Ok(d) = env::var("SCOTCH_LIB_DIR") {
        println!("cargo:rustc-link-search=native={d}");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{d}");
    }
    println!("cargo:rustc-link-lib=dylib=ptscotch");
    println!("cargo:rustc-link-lib=dylib=ptscotcherr");
    let bindings = builder
        .generate()
        .expect("bindgen failed on the PETSc headers");
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("petsc_bindings.rs");
    bindings
        .write_to_file(&out)
        .expect("writing PETSc bindings");
    mumps_bindings(&petsc.include_paths);
}

/// MUMPS' own C interface (src/petsc/mumps.rs: the Schur complement of a distributed matrix,
/// which PETSc's interface offers on one process only). The library PETSc links; its header
/// from libmumps-dev (or MUMPS_INCLUDE_DIR, or a PETSc build's include directory).
fn mumps_bindings(petsc_include: &[PathBuf]) {
    println!("cargo:rerun-if-env-changed=MUMPS_INCLUDE_DIR");
    println!("cargo:rerun-if-env-changed=MUMPS_LIB_DIR");
    let mut builder = bindgen::Builder::default()
        .header_contents("mumps_wrapper.h", "#include <dmumps_c.h>\n")
        .layout_tests(false)
        .generate_comments(false)
        .allowlist_function("dmumps_c")
        .allowlist_type("DMUMPS_STRUC_C");
    if let Ok(d) = env::var("MUMPS_INCLUDE_DIR") {
        builder = builder.clang_arg(format!("-I{d}"));
    }
    for p in petsc_include {
        builder = builder.clang_arg(format!("-I{}", p.display()));
    }
    if let Ok(d) = env::var("MUMPS_LIB_DIR") {
        println!("cargo:rustc-link-search=native={d}");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{d}");
    }
    println!("cargo:rustc-link-lib=dylib=dmumps");
    // dgetrf/dgetrs (src/petsc/lapack.rs): the LAPACK PETSc links as well
    println!("cargo:rustc-link-lib=dylib=lapack");
    let bindings = builder
        .generate()
        .expect("bindgen failed on dmumps_c.h: install libmumps-dev (petsc-dev pulls it in)");
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("mumps_bindings.rs");
    bindings
        .write_to_file(&out)
        .expect("writing MUMPS bindings");
}
