"""Darboux in a pyvista (or Open3D / trimesh / laspy) script.

Estimates the curvature of a point cloud held by another library, gets the result back
as a ``pyvista.PolyData`` with every per-point field, saves it for ParaView, and (with
``--show``) plots the mean curvature.

    python docs/examples/pyvista_roundtrip.py [cloud.ply|.las|...] [--out curvature.vtp] [--show]

Without a file the bundled Stanford bunny is used. The same ``core.estimate`` call takes an
Open3D ``PointCloud`` (``o3d.io.read_point_cloud(...)``), a ``trimesh.PointCloud`` or a
``laspy.LasData`` (``laspy.read(...)``) directly.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pyvista as pv

import core

BUNNY = Path(__file__).resolve().parents[2] / "resources" / "bunny.ply"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cloud", nargs="?", default=str(BUNNY))
    parser.add_argument("--out", default="curvature.vtp", help="where to save the result (VTK XML PolyData)")
    parser.add_argument("--show", action="store_true", help="plot the mean curvature")
    args = parser.parse_args(argv)

    cloud = pv.read(args.cloud)  # any pyvista data set: its points, and normals if it has some
    result = core.estimate(cloud, k="auto")  # NR with k chosen per point
    print(f"{result.n_invalid} of {len(result)} points invalid; median H = {np.median(result.mean[result.valid]):.4g}")

    out = result.to_pyvista()  # point data: k1, k2, e1, e2, mean, gaussian, ..., valid; normals
    out.save(args.out)
    print(f"wrote {args.out} with point data {', '.join(out.point_data.keys())}")
    if args.show:
        limit = np.nanpercentile(np.abs(result.mean), 98)
        out.plot(scalars="mean", cmap="RdBu_r", clim=(-limit, limit), point_size=4, render_points_as_spheres=True)


if __name__ == "__main__":
    main()
