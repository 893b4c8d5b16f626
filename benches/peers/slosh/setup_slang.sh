#!/usr/bin/env bash
# Lays out the Slang library (headers + libslang.so) that slosh3d needs, taken from the
# `slangpy` wheel on PyPI (Slang's own Python package ships the same library as Slang's
# GitHub releases). slangpy 0.36.0 carries Slang 2025.18, the series slosh's CI pins
# (2025.18.2). Prints the SLANG_DIR to export.
#
#   bash benches/peers/slosh/setup_slang.sh [DIR]   # DIR defaults to $CARGO_TARGET_DIR/slang-2025.18
set -euo pipefail
SLANGPY=0.36.0
dir=${1:-${CARGO_TARGET_DIR:-$(dirname "$0")/target}/slang-2025.18}
if [[ -f "$dir/lib/libslang.so" && -f "$dir/include/slang.h" ]]; then
  mkdir -p "$dir/bin"
  echo "SLANG_DIR=$(cd "$dir" && pwd)"
  exit 0
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 -m pip download --quiet --no-deps --only-binary=:all: \
  --platform manylinux_2_34_x86_64 --python-version 3.11 \
  "slangpy==$SLANGPY" -d "$tmp" >&2
# bin/ stays empty (no slangc is needed), but slang-hal's build script copies from it.
mkdir -p "$dir/include" "$dir/lib" "$dir/bin"
python3 - "$tmp"/slangpy-*.whl "$dir" <<'PY'
import sys, zipfile, os
whl, out = sys.argv[1], sys.argv[2]
with zipfile.ZipFile(whl) as z:
    for name in z.namelist():
        base = os.path.basename(name)
        if name.count("/") == 2 and name.startswith("slangpy/include/slang") and not base.startswith("slang-rhi") and base.endswith(".h"):
            dest = os.path.join(out, "include", base)
        elif name.startswith("slangpy/libslang") and base.endswith(".so"):
            dest = os.path.join(out, "lib", base)
        else:
            continue
        with z.open(name) as src, open(dest, "wb") as dst:
            dst.write(src.read())
PY
echo "2025.18 (slangpy $SLANGPY wheel)" > "$dir/VERSION"
echo "SLANG_DIR=$(cd "$dir" && pwd)"
