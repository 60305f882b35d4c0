#!/usr/bin/env python3
"""Independent check of an OpenCAMLib reference CSV: brute-force drop-cutter in numpy.

For every point, over ALL triangles (no spatial index), the tool-tip z is the maximum of
  * facet contacts: the cutter's lowest point along the facet normal, closed form
    (contact at horizontal distance a + r*sin(slope) uphill of the axis, h = r*(1 - cos));
  * edge contacts (vertices included): along each edge, the tip height
    z(t) - h(rho(t)) is concave in t (h convex increasing, rho convex), so its maximum over
    the chord inside the cutter's disc is found by golden-section search to ~1e-15 in t.
Independent of OpenCAMLib's code and of cam-offset's closed forms.

  python brute_check.py PART.stl REF.csv --cutter bull -D 6 -r 1.5 [--sample N]
prints max |dz| over points where both see contact, and disagreements in hit.
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import sys

import numpy as np
import trimesh


def profile(kind, D, r):
    R = D / 2.0
    if kind == "ball":
        r = R
    elif kind == "flat":
        r = 0.0
    return R, r, R - r


def h_of(rho, R, r, a):
    u = np.clip(rho - a, 0.0, None)
    return r - np.sqrt(np.clip(r * r - u * u, 0.0, None)) if r > 0 else np.zeros_like(rho)


def drop_point(x, y, tris, R, r, a):
    # Candidates: triangles whose XY bbox meets the disc's bbox.
    lo = tris.min(axis=1)
    hi = tris.max(axis=1)
    m = (lo[:, 0] <= x + R) & (hi[:, 0] >= x - R) & (lo[:, 1] <= y + R) & (hi[:, 1] >= y - R)
    T = tris[m]
    if len(T) == 0:
        return None
    best = -np.inf
    # Facets.
    n = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
    nl = np.linalg.norm(n, axis=1)
    ok = nl > 0
    n = n[ok] / nl[ok, None]
    Tf = T[ok]
    n = n * np.where(n[:, 2] < 0, -1.0, 1.0)[:, None]
    nz = n[:, 2]
    ok = nz > 1e-12
    n, Tf, nz = n[ok], Tf[ok], nz[ok]
    if len(Tf):
        s = np.hypot(n[:, 0], n[:, 1])
        rho = a + r * s
        dirx = np.where(s > 0, -n[:, 0] / np.where(s > 0, s, 1), 0.0)
        diry = np.where(s > 0, -n[:, 1] / np.where(s > 0, s, 1), 0.0)
        cx = x + rho * dirx
        cy = y + rho * diry
        # Flat bottom on a horizontal facet: any point of the disc; use the axis (and the
        # edges cover the rest).
        p0 = Tf[:, 0]
        zc = p0[:, 2] - (n[:, 0] * (cx - p0[:, 0]) + n[:, 1] * (cy - p0[:, 1])) / nz
        # Inside test (barycentric in XY).
        v0 = Tf[:, 1, :2] - Tf[:, 0, :2]
        v1 = Tf[:, 2, :2] - Tf[:, 0, :2]
        v2 = np.column_stack([cx, cy]) - Tf[:, 0, :2]
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            b1 = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
            b2 = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        inside = (b1 >= 0) & (b2 >= 0) & (b1 + b2 <= 1) & (den != 0)
        hz = r * (1.0 - nz)
        if inside.any():
            best = max(best, float(np.max(zc[inside] - hz[inside])))
    # Edges (with their end points).
    E0 = np.concatenate([T[:, 0], T[:, 1], T[:, 2]])
    E1 = np.concatenate([T[:, 1], T[:, 2], T[:, 0]])
    d = E1 - E0
    # Chord of the segment within the disc: |E0 + t d - (x,y)|_xy <= R.
    px = E0[:, 0] - x
    py = E0[:, 1] - y
    A = d[:, 0] ** 2 + d[:, 1] ** 2
    B = 2 * (px * d[:, 0] + py * d[:, 1])
    C = px * px + py * py - R * R
    disc = B * B - 4 * A * C
    vert = A == 0  # vertical edge: only its top point matters (when within the disc)
    with np.errstate(divide="ignore", invalid="ignore"):
        sq = np.sqrt(np.clip(disc, 0, None))
        t0 = np.where(vert, 0.0, (-B - sq) / (2 * A))
        t1 = np.where(vert, 1.0, (-B + sq) / (2 * A))
    ok = np.where(vert, C <= 0, disc >= 0) & (t1 >= 0) & (t0 <= 1)
    t0 = np.clip(t0, 0, 1)
    t1 = np.clip(t1, 0, 1)
    ok &= t0 <= t1
    E0, d, t0, t1 = E0[ok], d[ok], t0[ok], t1[ok]
    if len(E0):
        def f(t):
            px_ = E0[:, 0] + t * d[:, 0] - x
            py_ = E0[:, 1] + t * d[:, 1] - y
            rho = np.minimum(np.hypot(px_, py_), R)
            return E0[:, 2] + t * d[:, 2] - h_of(rho, R, r, a)
        g = (math.sqrt(5) - 1) / 2
        lo_, hi_ = t0.copy(), t1.copy()
        c = hi_ - g * (hi_ - lo_)
        e = lo_ + g * (hi_ - lo_)
        fc, fe = f(c), f(e)
        for _ in range(80):
            left = fc >= fe
            hi_ = np.where(left, e, hi_)
            lo_ = np.where(left, lo_, c)
            c_new = hi_ - g * (hi_ - lo_)
            e_new = lo_ + g * (hi_ - lo_)
            c, e = c_new, e_new
            fc, fe = f(c), f(e)
        vals = np.maximum.reduce([f(t0), f(t1), fc, fe])
        best = max(best, float(vals.max()))
    return None if best == -np.inf else best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("ref")
    ap.add_argument("--cutter", required=True)
    ap.add_argument("-D", type=float, required=True)
    ap.add_argument("-r", type=float, default=0.0)
    ap.add_argument("--sample", type=int, default=0, help="check every k-th point only")
    ap.add_argument("--misses", action="store_true", help="check only the points with hit = 0")
    args = ap.parse_args()
    m = trimesh.load(args.mesh, force="mesh", process=False)
    tris = np.asarray(m.vertices, dtype=np.float64)[np.asarray(m.faces)]
    R, r, a = profile(args.cutter, args.D, args.r)
    rows = list(csv.reader(open(args.ref)))[1:]
    if args.misses:
        rows = [r for r in rows if r[3] == "0"]
    step = max(args.sample, 1)
    worst = (0.0, None)
    hit_mismatch = []
    n = 0
    for row in rows[::step]:
        x, y, z = float(row[0]), float(row[1]), float(row[2])
        hit = row[3] == "1"
        zb = drop_point(x, y, tris, R, r, a)
        n += 1
        if (zb is not None) != hit:
            hit_mismatch.append((x, y, z, zb))
            continue
        if zb is not None:
            dz = abs(zb - z)
            if dz > worst[0]:
                worst = (dz, (x, y, z, zb))
    print(json.dumps({"ref": args.ref, "checked": n, "max_abs_dz": worst[0], "worst": worst[1],
                      "hit_mismatch": len(hit_mismatch), "hit_mismatch_first": hit_mismatch[:3]}))


if __name__ == "__main__":
    main()
