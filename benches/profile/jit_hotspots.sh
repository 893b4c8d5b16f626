#!/bin/bash
# Where a CPU driver (lavapipe, llvmpipe) spends a run's time inside its JIT-compiled
# kernels. perf sees the kernels only as anonymous addresses, and the driver frees their
# code when the pipelines go, so this script samples the run with perf while copying the
# anonymous executable mappings of it and its child processes every few seconds (gdb),
# then disassembles the hottest addresses from whichever copy holds them. Short runs need
# a short interval (-i 1): code freed between two copies cannot be shown, and an address
# that a later kernel reused shows that later kernel (each run of a benchmark case may
# compile its kernels anew at the same addresses).
#
#   benches/profile/jit_hotspots.sh [-n TOP] [-i SECONDS] -- COMMAND [ARGS...]
#   e.g. benches/profile/jit_hotspots.sh -i 1 -- target/release/splatter bench render --quick
#
# Needs perf, gdb and objdump, and permission to attach to one's own processes
# (kernel.yama.ptrace_scope 0, or root). Output: the top addresses with their share of the
# samples, each with the instructions around it. Work files go to $PROFILE_DIR (a new
# temporary directory by default).
set -euo pipefail
top=5
interval=2
while [[ $# -gt 0 && $1 != -- ]]; do
  case $1 in
    -n) top=$2; shift 2 ;;
    -i) interval=$2; shift 2 ;;
    *) echo "unknown option $1 (usage: $0 [-n TOP] [-i SECONDS] -- COMMAND...)" >&2; exit 2 ;;
  esac
done
[[ $# -gt 1 ]] || { echo "usage: $0 [-n TOP] [-i SECONDS] -- COMMAND..." >&2; exit 2; }
shift
for tool in perf gdb objdump; do
  command -v $tool > /dev/null || { echo "$0: $tool is not installed" >&2; exit 2; }
done
dir=${PROFILE_DIR:-$(mktemp -d)}
mkdir -p "$dir/code"

perf record -o "$dir/perf.data" -- "$@" > "$dir/run.log" 2>&1 &
recorder=$!

# The command and every process it starts (a benchmark may run each case in a child).
descendants() {
  local child
  for child in $(pgrep -P "$1"); do
    echo "$child"
    descendants "$child"
  done
}

# Copy one process's anonymous executable mappings to $dir/code/PID-SNAPSHOT-START.bin.
snapshot() {
  local pid=$1 range perms rest path dumps=()
  while read -r range perms _ _ _ path; do
    if [[ $perms == *x* && -z ${path:-} ]]; then
      dumps+=(-ex "dump binary memory $dir/code/$pid-$2-${range%-*}.bin 0x${range%-*} 0x${range#*-}")
    fi
  done < "/proc/$pid/maps" 2> /dev/null || true
  if [[ ${#dumps[@]} -gt 0 ]]; then
    gdb -batch -p "$pid" "${dumps[@]}" > /dev/null 2>&1 || true
  fi
}

round=0
while kill -0 $recorder 2> /dev/null; do
  sleep "$interval"
  round=$((round + 1))
  for pid in $(descendants $recorder); do
    snapshot "$pid" "$round"
  done
done
wait $recorder || true
echo "run log: $dir/run.log"

# perf's samples name threads, not processes, so a copy is found by address alone: the
# latest copy that holds the address with an instruction starting at it.
perf report -i "$dir/perf.data" --no-children --sort sym 2> /dev/null |
  awk '$2 == "[.]" && $3 ~ /^0x/ {print $1, $3}' | head -n "$top" |
  while read -r share address; do
    a=$((address))
    echo "== $address: $share of the samples"
    found=no
    for file in $(ls -t "$dir"/code/*.bin 2> /dev/null); do
      start=${file##*-}; start=$((16#${start%.bin}))
      size=$(stat -c %s "$file")
      (( a >= start && a < start + size )) || continue
      listing=$(objdump -D -b binary -m i386:x86-64 --adjust-vma=$start "$file" |
        grep -B 16 -A 6 "^ *$(printf '%x' $a):" | cut -f1,3 || true)
      if [[ -n $listing ]]; then
        echo "(from $file)"
        echo "$listing"
        found=yes
        break
      fi
    done
    [[ $found == yes ]] || echo "(in no copy: the code was freed or replaced before a snapshot; try a smaller -i)"
  done
