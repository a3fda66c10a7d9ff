# Shared shell code for scripts/*: source it, do not run it.
# shellcheck shell=bash

# The repository root, whatever the caller's working directory.
SIGNORINI_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

die() {
    echo "$(basename "$0"): error: $*" >&2
    exit 1
}

# Put cargo on PATH (rustup installs it under ~/.cargo/bin, which a
# non-login shell such as CI's may not have).
ensure_cargo() {
    if ! command -v cargo >/dev/null 2>&1 && [ -f "${CARGO_HOME:-$HOME/.cargo}/env" ]; then
        # shellcheck disable=SC1091
        . "${CARGO_HOME:-$HOME/.cargo}/env"
    fi
    command -v cargo >/dev/null 2>&1 ||
        die "cargo not found (install Rust >= 1.85 with rustup; Debian 12's cargo is too old)"
}

# The environment every MPI run of this project needs.
mpi_env() {
    # mpirun refuses to run as root unless told so.
    if [ "$(id -u)" -eq 0 ]; then
        export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    fi
    # One BLAS thread per MPI rank: MUMPS under MPI would otherwise oversubscribe the cores.
    export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
    export OMP_NUM_THREADS="${OMP_NUM_THREADS:-1}"
}

# Number of cores (for --oversubscribe decisions).
ncores() {
    nproc 2>/dev/null || getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1
}

# Packages (given as arguments) that are not installed, space-separated on stdout.
missing_packages() {
    local p missing=()
    for p in "$@"; do
        if [ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" != "install ok installed" ]; then
            missing+=("$p")
        fi
    done
    echo "${missing[*]}"
}

# Install Debian packages that are missing (apt-get update only when needed).
# Prints nothing when everything is present.
apt_install_missing() {
    local missing
    missing=$(missing_packages "$@")
    [ -z "$missing" ] && return 0
    [ "$(id -u)" -eq 0 ] || die "missing packages: $missing (run as root, or: sudo apt-get install $missing)"
    echo "setup: installing $missing" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null || die "apt-get update failed"
    # shellcheck disable=SC2086
    apt-get install -y -qq --no-install-recommends $missing >/dev/null ||
        die "apt-get install $missing failed"
    missing=$(missing_packages "$@")
    [ -z "$missing" ] || die "still missing after apt-get install: $missing"
}
