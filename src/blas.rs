//! OpenBLAS' kernels for this CPU. OpenBLAS built for many CPUs (DYNAMIC_ARCH, as Debian
//! ships it) picks its kernels by the CPU's model number, once, as the library loads. A
//! release older than the CPU does not know its model and falls back to a generic SSE3 core
//! ("Prescott"): Debian 12's OpenBLAS 0.3.21 does so on Intel Emerald Rapids, where MUMPS'
//! 3D factorisation of 113 k unknowns then takes 10.7 s instead of 3.9 s with the AVX-512
//! kernels (docs/numbers.md, "OpenBLAS' kernels"). OPENBLAS_CORETYPE overrides the choice,
//! but OpenBLAS reads it before `main` runs, so the process restarts itself once with it set
//! ([`restart_with_fitting_kernels`]). A user's own OPENBLAS_CORETYPE is left alone.

use crate::petsc::lapack::openblas_core;

/// Set in the restarted process: the core OpenBLAS had taken the CPU for.
const DETECTED: &str = "SIGNORINI_OPENBLAS_DETECTED";

/// The instruction sets that decide which of OpenBLAS' x86-64 kernel sets run here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Isa {
    /// AVX2 and FMA (OpenBLAS' "Haswell" kernels).
    pub avx2: bool,
    /// AVX-512 F, CD, BW, DQ and VL (its "SkylakeX" kernels).
    pub avx512: bool,
}

impl Isa {
    /// What this CPU (and the operating system, for the register state) supports.
    pub fn of_this_cpu() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            Isa {
                avx2: has!("avx2") && has!("fma"),
                avx512: has!("avx512f")
                    && has!("avx512cd")
                    && has!("avx512bw")
                    && has!("avx512dq")
                    && has!("avx512vl"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Isa {
            avx2: false,
            avx512: false,
        }
    }
}

/// OpenBLAS' kernel sets that use AVX2 or wider (the names of `openblas_get_corename`).
const WIDE: [&str; 5] = ["haswell", "zen", "skylakex", "cooperlake", "sapphirerapids"];

/// The kernel set to ask OpenBLAS for when it took a CPU with AVX2 or AVX-512 for an older
/// core (`detected`, OpenBLAS' name); `None` when its own choice uses AVX2 or better already,
/// or the CPU has neither.
pub fn better_core(detected: &str, isa: Isa) -> Option<&'static str> {
    if WIDE.contains(&detected.to_ascii_lowercase().as_str()) {
        return None;
    }
    if isa.avx512 {
        Some("SkylakeX")
    } else if isa.avx2 {
        Some("Haswell")
    } else {
        None
    }
}

/// Restarts this process (same arguments, same process id, before MPI is initialised) with
/// OPENBLAS_CORETYPE set when [`better_core`] finds OpenBLAS' own choice too old for the CPU.
/// Returns where no restart is needed, where the user set OPENBLAS_CORETYPE, where this is
/// the restarted process already, or where the restart failed (the run goes on as it is).
pub fn restart_with_fitting_kernels() {
    if std::env::var_os("OPENBLAS_CORETYPE").is_some() || std::env::var_os(DETECTED).is_some() {
        return;
    }
    let Some(detected) = openblas_core() else {
        return;
    };
    let Some(core) = better_core(&detected, Isa::of_this_cpu()) else {
        return;
    };
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    use std::os::unix::process::CommandExt;
    let mut args = std::env::args_os();
    let mut cmd = std::process::Command::new(exe);
    if let Some(arg0) = args.next() {
        cmd.arg0(arg0);
    }
    // `exec` returns only on failure; the run then goes on with OpenBLAS' own choice.
    let _ = cmd
        .args(args)
        .env("OPENBLAS_CORETYPE", core)
        .env(DETECTED, &detected)
        .exec();
}

/// The BLAS kernels this process runs, for the log and summary.json: OpenBLAS' kernel set,
/// with what OpenBLAS had taken the CPU for where [`restart_with_fitting_kernels`] restarted
/// the process. `None` when the BLAS is not OpenBLAS.
pub fn kernels() -> Option<String> {
    let core = openblas_core()?;
    Some(match std::env::var(DETECTED) {
        Ok(detected) => format!("OpenBLAS {core} (OpenBLAS had taken this CPU for {detected})"),
        Err(_) => format!("OpenBLAS {core}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const BOTH: Isa = Isa {
        avx2: true,
        avx512: true,
    };
    const AVX2: Isa = Isa {
        avx2: true,
        avx512: false,
    };
    const OLD: Isa = Isa {
        avx2: false,
        avx512: false,
    };

    #[test]
    fn a_generic_core_on_a_wide_cpu_gets_the_widest_kernels_it_can_run() {
        assert_eq!(better_core("Prescott", BOTH), Some("SkylakeX"));
        assert_eq!(better_core("Nehalem", AVX2), Some("Haswell"));
        assert_eq!(better_core("Sandybridge", BOTH), Some("SkylakeX"));
    }

    #[test]
    fn openblas_own_wide_choice_and_old_cpus_are_left_alone() {
        for core in ["Haswell", "Zen", "SkylakeX", "Cooperlake", "SapphireRapids"] {
            assert_eq!(better_core(core, BOTH), None, "{core}");
        }
        assert_eq!(better_core("Prescott", OLD), None);
    }

    #[test]
    fn this_process_names_its_blas() {
        // The test binary links the same BLAS as the solver (libblas.so.3), which
        // scripts/setup points to OpenBLAS: its kernel set has a name.
        let k = kernels().expect("OpenBLAS behind libblas.so.3 (scripts/setup)");
        assert!(
            k.starts_with("OpenBLAS ") && k.len() > "OpenBLAS ".len(),
            "{k}"
        );
    }
}
