#!/usr/bin/env bash
# Packs bin/nbep with the shared libraries it was linked against and their loader into DIR, for
# a node that lacks them (a compute node without the -dev packages, a borrowed machine):
#
#   scripts/pack-kit.sh DIR        then, there:  DIR/nbep run DECK ...
#
# DIR/nbep is a wrapper that starts the binary through the packed loader with the packed
# libraries only, so the node's own versions (if any) are not mixed in. Same processor
# architecture only (x86-64 here); about 30 MB with Open MPI's libraries. Not for MPI sweeps
# (`mpirun DIR/nbep sweep`): Open MPI loads its plugins from the build machine's install folder
# and its launcher is the node's own, so ranks need the same Open MPI installed where it was
# (README, Running on a cluster).
set -eu
[ $# = 1 ] || { echo "usage: scripts/pack-kit.sh DIR" >&2; exit 2; }
dir=$1
case $dir in /*) ;; *) dir=$PWD/$dir ;; esac   # relative to where it was called from
cd "$(dirname "$0")/.."
[ -x bin/nbep ] || { echo "pack-kit: bin/nbep missing: run make first" >&2; exit 1; }
mkdir -p "$dir/lib"
cp bin/nbep "$dir/nbep.bin"
# ldd's lines: "libx.so.N => /path (addr)" and the loader's "/lib64/ld-linux-x86-64.so.2 (addr)"
ldd bin/nbep | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' |
    while read -r f; do cp -L "$f" "$dir/lib/"; done
loader=""
for f in "$dir"/lib/ld-linux*; do [ -e "$f" ] && loader=${f##*/}; done
[ -n "$loader" ] || { echo "pack-kit: no loader in ldd's list" >&2; exit 1; }
cat >"$dir/nbep" <<W
#!/bin/sh
# nbep with the libraries it was built against (scripts/pack-kit.sh)
d=\$(cd "\$(dirname "\$0")" && pwd)
exec "\$d/lib/$loader" --library-path "\$d/lib" "\$d/nbep.bin" "\$@"
W
chmod +x "$dir/nbep"
libs=("$dir"/lib/*)
echo "packed ${#libs[@]} libraries: $dir/nbep ($("$dir/nbep" --version))"
