//! OpenBLAS' kernels for this CPU. OpenBLAS built for many CPUs (DYNAMIC_ARCH, as Debian
//! ships it) picks its kernels by the CPU's model number, once, as the library loads. A
//! release older than the CPU does not know its model and falls back to a generic SSE3 core
//! ("Prescott"): Debian 12's OpenBLAS 0.3.21 does so on Intel Emerald Rapids, where MUMPS'
//! 3D factorisation of 113 k unknowns then takes 10.7 s instead of 3.9 s with the AVX-512
//! kernels (docs/numbers.md, "OpenBLAS' kernels"). OPENBLAS_CORETYPE overrides the choice,
//! but OpenBLAS reads it before `main` runs, so the process restarts itself once with it set
//! ([`restart_with_fitting_kernels`]). A user's own OPENBLAS_CORETYPE is left alone.

use crate::petsc::lapack::{openblas_core, openblas_threads, set_openblas_threads};
use crate::tuning::WIDE_MIN_DIM;
use mpi::collective::SystemOperation;
use mpi::topology::SimpleCommunicator;
use mpi::traits::*;
use rustix::thread::{sched_getaffinity, sched_setaffinity, CpuSet, Pid};

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

/// 64-bit words of a CPU set (CpuSet::MAX_CPU bits).
const CPU_WORDS: usize = CpuSet::MAX_CPU.div_ceil(64);

/// Rank 0's dense work on the cores of its node. The condensed path's dense phases (the inverse
/// of the Schur complement, the dense Newton steps, the half-space model) run on rank 0 alone;
/// the other ranks of its node wait for them without spinning ([`crate::par::Ctx::on_root_wide`]),
/// and rank 0 lets its threads run on every CPU those ranks may use (the union of their
/// affinity masks: an MPI launcher that binds each rank to a core leaves rank 0 one core) with
/// as many OpenBLAS threads, restoring both afterwards. MUMPS and everything else keep the
/// process' own setting (OPENBLAS_NUM_THREADS). `solver.dense_threads = N` fixes the count
/// whatever the binding ([`NodeCores::with`]).
#[derive(Clone, Copy)]
pub struct NodeCores {
    /// Rank 0 with OpenBLAS: the CPUs of the ranks on its node; `None` elsewhere.
    wide: Option<CpuSet>,
    /// The thread count asked for by the case (`None`: one per CPU of `wide`).
    fixed: Option<usize>,
}

impl NodeCores {
    /// The CPUs of the ranks that share world rank 0's node (MPI_Comm_split_type shared;
    /// one OR-reduction of the affinity masks). Collective.
    pub fn of_root_node(world: &SimpleCommunicator) -> NodeCores {
        let node = world.split_shared(0);
        let own = sched_getaffinity(None).ok();
        let mut words = [0u64; CPU_WORDS];
        for c in (0..CpuSet::MAX_CPU).filter(|&c| own.is_some_and(|s| s.is_set(c))) {
            words[c / 64] |= 1 << (c % 64);
        }
        let mut union = [0u64; CPU_WORDS];
        node.all_reduce_into(&words[..], &mut union[..], SystemOperation::bitwise_or());
        if world.rank() != 0 || own.is_none() || openblas_threads().is_none() {
            return NodeCores::none();
        }
        let mut wide = CpuSet::new();
        for c in (0..CpuSet::MAX_CPU).filter(|&c| union[c / 64] >> (c % 64) & 1 == 1) {
            wide.set(c);
        }
        NodeCores {
            wide: Some(wide),
            fixed: None,
        }
    }

    /// Nothing widened (a process that is not rank 0, or a test).
    pub fn none() -> NodeCores {
        NodeCores {
            wide: None,
            fixed: None,
        }
    }

    /// These cores with the case's `solver.dense_threads`: "auto" one thread per CPU of the
    /// node's ranks (as the launcher bound them), `N` exactly N threads on rank 0 (with
    /// OpenBLAS; on those CPUs) whatever the binding. Local.
    pub fn with(self, threads: crate::case::DenseThreads) -> NodeCores {
        let fixed = match threads {
            crate::case::DenseThreads::Auto => None,
            crate::case::DenseThreads::Fixed(n) => Some(n.max(1)),
        };
        NodeCores { fixed, ..self }
    }

    /// The OpenBLAS threads rank 0's dense work runs with: one per CPU of its node's ranks,
    /// at least the process' own count, or the case's fixed count (1 without OpenBLAS or off
    /// rank 0).
    pub fn threads(&self) -> usize {
        self.threads_over(openblas_threads().unwrap_or(1))
    }

    /// [`NodeCores::threads`] for the process' own count `own`.
    fn threads_over(&self, own: usize) -> usize {
        match (self.wide, self.fixed) {
            (None, _) => own,
            (Some(_), Some(n)) => n,
            (Some(w), None) => own.max(w.count() as usize),
        }
    }

    /// `work`, whose dense matrices are of dimension `dim` at most, with every thread of this
    /// process allowed on the node's CPUs and OpenBLAS on [`NodeCores::threads`] threads; both
    /// restored afterwards (also when `work` panics). Where that is no more than the process
    /// has, or `dim` is below [`WIDE_MIN_DIM`], `work` runs as it is. Local.
    pub fn run<T>(&self, dim: usize, work: impl FnOnce() -> T) -> T {
        if dim < WIDE_MIN_DIM {
            return work();
        }
        let (Some(wide), Some(own)) = (self.wide, openblas_threads()) else {
            return work();
        };
        let threads = self.threads_over(own);
        if threads == own {
            return work();
        }
        let _widened = Widened::new(&wide, own, threads);
        work()
    }
}

/// The threads of this process (/proc/self/task; empty where it cannot be read).
fn own_threads() -> Vec<Pid> {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return Vec::new();
    };
    dir.filter_map(|e| e.ok()?.file_name().to_str()?.parse().ok())
        .filter_map(Pid::from_raw)
        .collect()
}

/// Widened affinity and OpenBLAS threads, restored on drop ([`NodeCores::run`]).
struct Widened {
    saved: Vec<(Pid, CpuSet)>,
    caller: Option<CpuSet>,
    threads: usize,
}

impl Widened {
    fn new(wide: &CpuSet, own: usize, threads: usize) -> Widened {
        let saved: Vec<(Pid, CpuSet)> = own_threads()
            .into_iter()
            .filter_map(|t| Some((t, sched_getaffinity(Some(t)).ok()?)))
            .collect();
        let caller = sched_getaffinity(None).ok();
        for (t, _) in &saved {
            // a thread that ended meanwhile, or a set the system refuses: left as it is
            let _ = sched_setaffinity(Some(*t), wide);
        }
        // threads OpenBLAS starts now inherit the caller's widened set
        set_openblas_threads(threads);
        Widened {
            saved,
            caller,
            threads: own,
        }
    }
}

impl Drop for Widened {
    fn drop(&mut self) {
        set_openblas_threads(self.threads);
        for t in own_threads() {
            let back = (self.saved.iter().find(|(s, _)| *s == t).map(|(_, m)| *m)).or(self.caller);
            if let Some(m) = back {
                let _ = sched_setaffinity(Some(t), &m);
            }
        }
    }
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
