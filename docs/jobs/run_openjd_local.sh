#!/usr/bin/env bash
# Runs docs/jobs/splatter.openjd.yaml on this machine with the Open Job Description CLI
# (`openjd check`, then `openjd run` of both steps, tasks one after another), and checks
# that the job's frames are exactly the listed ones and byte-identical to one process
# rendering the same frames from the same states; then compares them with one process
# simulating and rendering the whole scene. See docs/farm.md.
#
#   cargo build --release
#   pip install openjd-cli            # into a virtual environment; not needed by CI
#   docs/jobs/run_openjd_local.sh [WORK_DIR]
#
# Environment: SPLATTER (the program, default target/release/splatter), FRAMES (default
# 0-3,5,7-11: a list with gaps), CHUNK (frames a render task, default 3), OPENJD (default
# openjd). Exits non-zero when a check fails.
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
splatter="$(realpath "${SPLATTER:-$repo/target/release/splatter}")"
openjd="${OPENJD:-openjd}"
frames="${FRAMES:-0-3,5,7-11}"
chunk="${CHUNK:-3}"
template="$repo/docs/jobs/splatter.openjd.yaml"

[ -x "$splatter" ] || { echo "no splatter program at $splatter (cargo build --release)" >&2; exit 2; }
command -v "$openjd" >/dev/null || { echo "no openjd on the PATH (pip install openjd-cli)" >&2; exit 2; }

work="$(realpath -m "${1:-$(mktemp -d)}")"
mkdir -p "$work"
cp "$repo/docs/jobs/jelly_12.json" "$work/scene.json"
echo "work dir: $work; frames $frames in chunks of $chunk"
"$openjd" --version

"$openjd" check "$template"
"$openjd" run "$template" --step Render --run-dependencies \
    -p Splatter="$splatter" -p Scene="$work/scene.json" -p WorkDir="$work/job" \
    -p Frames="$frames" -p ChunkSize="$chunk" >"$work/openjd.log" 2>&1 \
    || { tail -n 40 "$work/openjd.log"; exit 1; }
# The frame lists openjd gave the render tasks.
grep -o "Frame(CHUNK\[INT\]) = .*" "$work/openjd.log" | sed 's/^/  render task: /' || true

# One process, the same states, every listed frame: the reference.
"$splatter" render "$work/scene.json" --from-states "$work/job/states" --frames "$frames" \
    --out "$work/single" 2>"$work/single.log"

list() { (cd "$1" && ls frame_*.png); }
if [ "$(list "$work/job/frames")" != "$(list "$work/single")" ]; then
    echo "FAIL: the job wrote other frames than the single run:" >&2
    diff <(list "$work/job/frames") <(list "$work/single") >&2 || true
    exit 1
fi
n=0
for f in "$work"/single/frame_*.png; do
    cmp "$f" "$work/job/frames/$(basename "$f")"
    n=$((n + 1))
done
echo "OK: $n frames ($(list "$work/single" | tr '\n' ' ')) byte-identical to the single run"

# One process simulating and rendering every frame of the scene, no states: the listed
# frames compared. The export rounds the states a little (covariance to scale and
# rotation), so this is reported rather than required; on this scene they are identical.
"$splatter" render "$work/scene.json" --deterministic --out "$work/full" 2>"$work/full.log"
same=0
for f in "$work"/single/frame_*.png; do
    cmp -s "$f" "$work/full/$(basename "$f")" && same=$((same + 1))
done
echo "and $same of $n byte-identical to a single simulated run of the whole scene (--deterministic, no states)"
