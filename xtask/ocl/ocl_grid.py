#!/usr/bin/env python3
"""OpenCAMLib reference CL grids with full precision, for `cargo xtask ocl-ref`.

Calls OpenCAMLib exactly as ../shared/tools/ocl/ocl_dropcutter.py does (it imports that
script's `make_surface`, `make_cutter`, `drop` and `grid_xy`: STLSurf built from trimesh's
triangles, BatchDropCutter over CLPoints starting at zmin), but writes

  * x, y with Python's repr (shortest text that round-trips the float64 exactly), so a point
    can be matched to another program's grid point by exact equality;
  * z (TOOL TIP, mm) with %.10f;
  * hit (1 = the cutter touched a triangle, 0 = it stayed at zmin) and cc_type (OpenCAMLib
    CCType code of the contact);

in raster order (row j = 0..ny-1, x increasing along every row), the order of cam-offset's
`Grid::xy(k)`.  zmin defaults to (mesh min z - D - 1): every possible tool-tip contact height
is >= mesh min z - D/2, so hit = (z > zmin) exactly, and no contact is clipped at zmin.

The last stdout line is a JSON object with the grid parameters and timings.

  python ocl_grid.py PART.stl --cutter bull -D 6 -r 1.5 --step 1 -o out.csv [--threads N]
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("--shared-ocl", default=os.environ.get("CAM_OCL_TOOLS"),
                    help="directory of the shared ocl_dropcutter.py / cam_common.py")
    ap.add_argument("--cutter", required=True, choices=["ball", "flat", "bull"])
    ap.add_argument("-D", "--diameter", type=float, required=True)
    ap.add_argument("-r", "--corner-radius", type=float, default=None)
    ap.add_argument("--length", type=float, default=50.0)
    ap.add_argument("--step", type=float, required=True)
    ap.add_argument("--zmin", type=float, default=None)
    ap.add_argument("--threads", type=int, default=0)
    ap.add_argument("-o", "--output", required=True)
    args = ap.parse_args(argv)

    if not args.shared_ocl:
        raise SystemExit("--shared-ocl (or CAM_OCL_TOOLS) is required")
    sys.path.insert(0, os.path.abspath(args.shared_ocl))
    from cam_common import Cutter, mesh_triangles  # noqa: E402
    from ocl_dropcutter import drop, grid_xy, make_cutter, make_surface  # noqa: E402
    from opencamlib import ocl  # noqa: E402

    if args.cutter == "bull" and args.corner_radius is None:
        raise SystemExit("-r is required for bull")
    cutter = Cutter(args.cutter, args.diameter, args.corner_radius or 0.0, args.length)

    tris = mesh_triangles(args.mesh)
    lo = tris.reshape(-1, 3).min(axis=0)
    hi = tris.reshape(-1, 3).max(axis=0)
    zmin = float(lo[2] - args.diameter - 1.0) if args.zmin is None else args.zmin
    surf = make_surface(tris)
    x0, x1, y0, y1 = float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])
    xy, nx, ny = grid_xy(x0, x1, y0, y1, args.step, "raster")

    t0 = time.perf_counter()
    z, hit, cc = drop(surf, make_cutter(cutter), xy, zmin, args.threads)
    dt = time.perf_counter() - t0
    # hit as the shared script defines it (z > zmin + 1e-9) must agree with the CC type.
    cc_none = int(ocl.CCType.NONE) if hasattr(ocl, "CCType") else 0
    mismatch = int(np.sum(hit != (cc != cc_none)))

    with open(args.output, "w") as f:
        f.write("x,y,z,hit,cc_type\n")
        for (x, y), zz, h, c in zip(xy.tolist(), z.tolist(), hit.tolist(), cc.tolist()):
            f.write(f"{x!r},{y!r},{zz:.10f},{int(h)},{int(c)}\n")

    info = {
        "mesh": os.path.basename(args.mesh), "triangles": int(len(tris)),
        "cutter": cutter.kind, "diameter": args.diameter, "corner_radius": cutter.r,
        "length": args.length, "step": args.step, "x0": x0, "y0": y0, "nx": int(nx), "ny": int(ny),
        "x1": x1, "y1": y1, "zmin": zmin, "points": int(len(xy)),
        "no_contact": int((~hit).sum()), "hit_cc_mismatch": mismatch,
        "seconds": dt, "points_per_s": len(xy) / max(dt, 1e-9),
        "threads": args.threads or int(ocl.max_threads()), "ocl_version": str(ocl.version()),
        "order": "raster",
    }
    print(json.dumps(info))


if __name__ == "__main__":
    main()
