"""``python -m core bench scanlines``: the default estimate on clouds sampled the way
scanners sample them (:mod:`core.bench.scan_clouds`), against their exact geometry.

Scan lines far apart compared with the points along them, rings of a turntable or of a
rotating LiDAR, a terrestrial scanner's floor and the noise along its rays are where the
k nearest neighbours of a point stop being a disc of surface: they lie on one or two lines,
or spread along the view rays. The rules of :mod:`core.plane_spread` and
:mod:`core.initial_normals` were built on these clouds; this table is how a change to them
is judged. Per cloud: mean sign-blind |H| error (||H| - |H_true||: a scan's normals may
face either way without a viewpoint), median and 90th-percentile normal error (degrees,
sign-blind), the share of scored points estimated, and with a viewpoint the share of
normals facing the scanner. Clouds with a scanner position are estimated with
``orientation=view`` (``--no-view``: without it).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from ..estimate import estimate
from ..io.atomic import atomic_write
from ..passes import turn_angles
from ._table import fmt, text_table
from .scan_clouds import cases

HEADER = ("cloud", "points", "mean |H err|", "normal err p50", "p90", "valid", "facing", "s")


def score(cloud, res) -> dict:
    """The row's numbers for the estimate ``res`` of the :class:`ScanCloud` ``cloud``."""
    v = cloud.use & res.valid
    ang = turn_angles(res.normals, cloud.normals / np.linalg.norm(cloud.normals, axis=1, keepdims=True), v)
    h = np.abs(np.abs(res.mean[v]) - np.abs(cloud.mean[v]))
    out = {"points": len(cloud.points), "h_error": float(h.mean()) if len(h) else float("nan"),
           "normal_p50": float(np.median(ang)) if len(ang) else float("nan"),
           "normal_p90": float(np.percentile(ang, 90)) if len(ang) else float("nan"),
           "valid": float(v.sum() / max(int(cloud.use.sum()), 1)), "facing": None}
    if cloud.view is not None:
        toward = np.einsum("ij,ij->i", res.normals[v], np.asarray(cloud.view) - cloud.points[v])
        out["facing"] = float(np.mean(toward > 0)) if len(toward) else float("nan")
    return out


def run(only=None, use_view=True, out=print) -> dict:
    """{cloud: row} for the clouds whose name starts with ``only`` (all by default); prints the table."""
    rows, table = {}, []
    for name, make in cases().items():
        if only and not name.startswith(only):
            continue
        cloud = make()
        t = time.perf_counter()
        view = cloud.view if use_view else None
        res = estimate(cloud.points) if view is None else estimate(cloud.points, orientation=view)
        row = {**score(cloud if use_view else cloud._replace(view=None), res), "seconds": time.perf_counter() - t}
        rows[name] = row
        table.append((name, row["points"], fmt(row["h_error"]), fmt(row["normal_p50"]), fmt(row["normal_p90"]),
                      f"{row['valid']:.3f}", "" if row["facing"] is None else f"{row['facing']:.3f}",
                      f"{row['seconds']:.1f}"))
    out(text_table(HEADER, table, title="Scanner-sampled clouds, default estimate (k=\"auto\")"))
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m core bench scanlines", description=__doc__.split("\n\n")[0])
    p.add_argument("--only", default=None, help="run the clouds whose name starts with this (e.g. 'LiDAR')")
    p.add_argument("--no-view", action="store_true", help="estimate without the scanner's position")
    p.add_argument("--json", default=None, help="also write the rows to this JSON file")
    a = p.parse_args(argv)
    rows = run(a.only, not a.no_view)
    if not rows:
        raise SystemExit(f"scanlines: error: no cloud's name starts with {a.only!r}; names: "
                         + ", ".join(cases()))
    if a.json:
        with atomic_write(a.json) as fh:
            fh.write(json.dumps(rows, indent=1).encode("utf-8"))
    return 0
