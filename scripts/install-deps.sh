#!/usr/bin/env bash
# Installs every Debian/Ubuntu package nbep needs to build, test, benchmark and plot.
# Idempotent (apt-get skips what is installed); fails loudly on the first error.
# Works as root without sudo, or as a user (through sudo, asked only when something is missing).
set -euo pipefail

packages=(
    build-essential pkg-config make gcc         # compiler with OpenMP (libgomp ships with gcc)
    libgsl-dev                                  # polynomial roots (quartic contact times)
    libhdf5-dev hdf5-tools                      # output (serial HDF5) and h5dump/h5ls
    libconfig-dev                               # input decks
    libjansson-dev                              # the JSON summary (written and read back)
    libcmocka-dev                               # unit tests
    libopenmpi-dev openmpi-bin                  # parameter sweeps across ranks
    valgrind                                    # make valgrind (and make check VALGRIND=1): memcheck
    clang libomp-dev                            # make tsan: ThreadSanitizer with an OpenMP it can see
    python3 python3-numpy python3-matplotlib python3-h5py   # benchmark plots and renderer
    python3-mpmath                              # make accuracy: 60-digit reference check
    procps                                      # pgrep in the sweep tests (a minimal image lacks it)
)

export DEBIAN_FRONTEND=noninteractive
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ "${#missing[@]}" -eq 0 ]; then
    echo "install-deps.sh: all ${#packages[@]} packages already installed"
    exit 0
fi
# Root only now that something is missing: a user whose machine has everything needs no sudo.
if [ "$(id -u)" -eq 0 ]; then
    as_root=()
elif command -v sudo >/dev/null 2>&1; then
    as_root=(sudo)
else
    echo "install-deps.sh: must run as root or with sudo available to install ${missing[*]}" >&2
    exit 1
fi
echo "install-deps.sh: installing ${missing[*]}"
"${as_root[@]}" apt-get update -q
"${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "install-deps.sh: done"
