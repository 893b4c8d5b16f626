#!/usr/bin/env python3
"""Compare decoded PLYs (e.g. splat-transform X -> .ply) with the source PLY.

Usage: compare.py [--order MORTON.ply] SOURCE.ply DECODED.ply [more DECODED.ply ...]
Needs numpy and scipy (this analysis script only; make_subset.py needs neither).

For each decoded file it prints: the count; which axis map (identity or a flip of one
or two axes) puts the decoded positions onto the source; whether row order is kept
(row i within the quantisation of source row i), or follows the order of MORTON.ply
(a lossless reordering of SOURCE, e.g. `splat-transform SOURCE.ply -m MORTON.ply`),
or else a one-to-one matching by position (min-weight bipartite matching over 8
nearest neighbours; plain nearest neighbour above 20,000 rows); then, after
matching, max / mean abs difference per field.  For fields a format clips (opacity,
f_dc, log-scale) it also prints the max difference over the rows whose source value
lies inside the decoded range ("in range").  Quaternions are compared after
normalising both and choosing the sign (q ~ -q).
"""
import sys
import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import min_weight_full_bipartite_matching
from scipy.spatial import cKDTree

TYPES = {"float": "<f4", "float32": "<f4", "double": "<f8", "uchar": "u1", "uint8": "u1",
         "int": "<i4", "uint": "<u4", "short": "<i2", "ushort": "<u2", "char": "i1"}
FLIPS = {"identity": (1, 1, 1), "flip y,z": (1, -1, -1), "flip x,y": (-1, -1, 1),
         "flip x,z": (-1, 1, -1), "flip x": (-1, 1, 1), "flip y": (1, -1, 1),
         "flip z": (1, 1, -1)}


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    fields, n = [], None
    for ln in data[:end].decode("ascii").splitlines():
        p = ln.split()
        if p[:2] == ["element", "vertex"]:
            n = int(p[2])
        elif p and p[0] == "element":
            raise SystemExit("%s: only plain (single-element) PLY" % path)
        elif p and p[0] == "property":
            fields.append((p[2], TYPES[p[1]]))
    arr = np.frombuffer(data, dtype=np.dtype(fields), count=n, offset=end)
    return {k: arr[k].astype(np.float64) for k, _ in fields}, n


def positions(d):
    return np.stack([d["x"], d["y"], d["z"]], 1)


def quats(d):
    return np.stack([d["rot_0"], d["rot_1"], d["rot_2"], d["rot_3"]], 1)


def match(P, Q, tree):
    """Permutation idx with Q[j] ~ P[idx[j]] (one-to-one when counts agree)."""
    k = min(8, len(P))
    dist, nn = tree.query(Q, k=k)
    if len(P) != len(Q):
        return nn[:, 0]
    if len(np.unique(nn[:, 0])) == len(P) or len(P) > 20000:
        return nn[:, 0]
    rows = np.repeat(np.arange(len(Q)), k)
    w = csr_matrix((dist.ravel() + 1e-12, (rows, nn.ravel())), shape=(len(Q), len(P)))
    _, col = min_weight_full_bipartite_matching(w)
    return col


def sigmoid(x):
    with np.errstate(over="ignore"):
        return 1.0 / (1.0 + np.exp(-x))


def exact_perm(src, ref):
    """idx with ref row j == src row idx[j] (ref is a lossless reordering of src)."""
    keys = sorted(src)
    a = np.stack([src[k] for k in keys], 1)
    b = np.stack([ref[k] for k in keys], 1)
    ia = np.lexsort(a.T[::-1])
    ib = np.lexsort(b.T[::-1])
    if not np.array_equal(a[ia], b[ib]):
        raise SystemExit("--order file is not a reordering of the source")
    idx = np.empty(len(b), dtype=np.int64)
    idx[ib] = ia
    return idx


def report(src, n, tree, path, order=None):
    dec, m = read_ply(path)
    print("== %s" % path)
    print("  count: source %d, decoded %d%s" % (n, m, "" if n == m else "  (CHANGED)"))
    P, Q = positions(src), positions(dec)
    extent = np.ptp(P, 0).max()
    fits = {}
    for name, s in FLIPS.items():
        d, _ = tree.query(Q * np.array(s))
        fits[name] = np.median(d)
    name = min(fits, key=fits.get)
    s = np.array(FLIPS[name])
    others = sorted(v for k, v in fits.items() if k != name)
    print("  axis map: %s (median nearest distance %.3g; next best %.3g; extent %.3g)"
          % (name, fits[name], others[0], extent))
    Qs = Q * s
    kept = False
    if m == n:
        ident = np.abs(Qs - P).max()
        kept = ident < 1e-3 * extent
    follows = False
    if not kept and order is not None and m == n:
        oidx = order[1]
        dev = np.abs(Qs - positions(order[0])).max()
        follows = dev < 1e-3 * extent
    if kept:
        idx = np.arange(n)
        print("  order: KEPT (row i -> source row i; max position diff in place %.3g)" % ident)
    elif follows:
        idx = oidx
        print("  order: REORDERED, exactly as the --order (Morton) file (max position diff"
              " against it in place %.3g); rows left in place: %d of %d"
              % (dev, np.sum(idx == np.arange(n)), n))
    else:
        idx = match(P, Qs, tree)
        print("  order: REORDERED (rows left in place: %d of %d); matched one-to-one by position"
              % (np.sum(idx == np.arange(m)) if m == n else -1, m))
    ref = {k: v[idx] for k, v in src.items()}
    for i, k in enumerate("xyz"):
        d = np.abs(dec[k] * s[i] - ref[k])
        print("  %-8s max %.3g  mean %.3g" % (k, d.max(), d.mean()))
    for k in ("scale_0", "scale_1", "scale_2", "opacity", "f_dc_0", "f_dc_1", "f_dc_2"):
        a, b = dec[k], ref[k]
        fin = np.isfinite(a)
        d = np.abs(a[fin] - b[fin])
        lo, hi = a[fin].min(), a[fin].max()
        inr = fin & (b >= lo) & (b <= hi)
        di = np.abs(a[inr] - b[inr])
        line = "  %-8s max %.3g  mean %.3g | in range [%.4g, %.4g]: %d rows, max %.3g" % (
            k, d.max(), d.mean(), lo, hi, inr.sum(), di.max() if inr.any() else float("nan"))
        if not fin.all():
            line += "  | %d non-finite decoded: %s" % ((~fin).sum(), np.unique(a[~fin]))
        print(line)
        if k == "opacity":
            da = np.abs(sigmoid(a) - sigmoid(b))
            print("  %-8s as sigmoid(opacity): max %.3g  mean %.3g" % ("", da.max(), da.mean()))
    qs = quats(ref)
    qs = qs / np.linalg.norm(qs, axis=1, keepdims=True)
    qd = quats(dec)
    nd = np.linalg.norm(qd, axis=1)
    if name != "identity":
        # conjugating a rotation by an axis flip diag(s) (det +1 for a two-axis flip)
        # maps quaternion (w, x, y, z) to (w, s_y s_z x, s_x s_z y, s_x s_y z)
        qd = qd * np.array([1, s[1] * s[2], s[0] * s[2], s[0] * s[1]])
    qdn = qd / nd[:, None]
    dp, dm = np.abs(qdn - qs).max(1), np.abs(qdn + qs).max(1)
    dq = np.minimum(dp, dm)
    big = np.abs(qd).argmax(1)
    print("  rot      (normalised, sign-matched) max %.3g  mean %.3g" % (dq.max(), dq.mean()))
    print("  rot      decoded |q| in [%.4f, %.4f]; sign differs from source in %d rows;"
          " decoded w<0 in %d rows (source: %d); largest |component| negative in %d rows"
          % (nd.min(), nd.max(), (dm < dp).sum(), (qd[:, 0] < 0).sum(),
             (qs[:, 0] < 0).sum(), (qd[np.arange(m), big] < 0).sum()))


def main():
    args = sys.argv[1:]
    order_path = None
    if args and args[0] == "--order":
        order_path, args = args[1], args[2:]
    src, n = read_ply(args[0])
    tree = cKDTree(positions(src))
    order = None
    if order_path:
        ref, _ = read_ply(order_path)
        order = (ref, exact_perm(src, ref))
    for path in args[1:]:
        report(src, n, tree, path, order)


if __name__ == "__main__":
    main()
