"""Teaching maths against the truth: Gauss-Bonnet, lines of curvature, point types.

``python -m core bench teach`` prints a table per quantity (5000 points, the default
estimate, noise 0 and 0.1 of the mean spacing).
"""

from __future__ import annotations

import argparse
from types import SimpleNamespace

import numpy as np

import core

from ._table import fmt, text_table

_CHI = {"sphere": 2, "ellipsoid": 2, "torus": 0}
_AREA = {"sphere": 4 * np.pi, "torus": 8 * np.pi**2}


def _estimate(name, n, sigma, seed):
    s = core.shapes.SHAPES[name](n, seed=seed)
    pts = core.noise.add_noise(s.points, sigma, seed=seed + 1) if sigma else s.points
    return s, core.estimate(pts)


def gauss_bonnet_rows(n, sigmas, seed):
    rows = []
    for name, chi in _CHI.items():
        for sigma in sigmas:
            _, res = _estimate(name, n, sigma, seed)
            gb = core.gauss_bonnet(res)
            area = _AREA.get(name)
            rows.append([name, fmt(sigma), fmt(gb.chi, 4), fmt(abs(gb.chi - chi), 2),
                         fmt(100 * (gb.area / area - 1), 2) if area else "-", str(gb.closed)])
    return rows


def _torus_angles(lines, direction):
    """Per line: drift of its phi (meridians) or theta (parallels) in degrees; per chord: the
    angle to the true direction, in the true tangent plane."""
    drift, chords = [], []
    for line in lines:
        rho = np.hypot(line[:, 0], line[:, 1])
        a = np.arctan2(line[:, 1], line[:, 0]) if direction == "e1" else np.arctan2(line[:, 2], rho - 2.0)
        drift.append(np.degrees(np.ptp(np.unwrap(a))))
        mid = 0.5 * (line[1:] + line[:-1])
        t = np.diff(line, axis=0)
        phi = np.arctan2(mid[:, 1], mid[:, 0])
        ring = np.column_stack([2 * np.cos(phi), 2 * np.sin(phi), np.zeros(len(mid))])
        nrm = (mid - ring) / np.linalg.norm(mid - ring, axis=1, keepdims=True)
        t -= nrm * (t * nrm).sum(1, keepdims=True)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        if direction == "e1":
            true = np.cross(nrm, np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(len(mid))]))
        else:
            true = np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(len(mid))])
        chords.append(np.degrees(np.arccos(np.clip(np.abs((t * true).sum(1)), 0, 1))))
    return np.array(drift), np.concatenate(chords)


def lines_rows(n, sigmas, seed):
    rows = []
    for sigma in sigmas:
        _, res = _estimate("torus", n, sigma, seed)
        for direction, what in (("e1", "meridians"), ("e2", "parallels")):
            lines = core.curvature_lines(res, direction=direction)
            drift, chords = _torus_angles(lines, direction)
            rows.append([f"torus {what}", fmt(sigma), str(len(lines)), fmt(np.median(chords), 2),
                         fmt(np.percentile(chords, 95), 2), fmt(np.percentile(drift, 95), 2), fmt(drift.max(), 2)])
    return rows


def types_rows(n, sigmas, seed):
    rows = []
    for name in ("sphere", "cylinder", "plane", "torus", "ellipsoid", "saddle"):
        for sigma in sigmas:
            s, res = _estimate(name, n, sigma, seed)
            truth = SimpleNamespace(k1=s.k1, k2=s.k2, points=s.points, valid=np.ones(len(s.k1), bool),
                                    curvedness=np.sqrt(0.5 * (s.k1**2 + s.k2**2)))
            agree = core.point_types(res)[s.interior] == core.point_types(truth)[s.interior]
            rows.append([name, fmt(sigma), fmt(100 * agree.mean(), 3)])
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m core bench teach", description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=5000)
    p.add_argument("--sigmas", default="0,0.1", help="noise levels in mean spacings")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    sigmas = tuple(float(x) for x in a.sigmas.split(","))
    print(text_table(["shape", "sigma", "chi", "|chi error|", "area error %", "closed"],
                     gauss_bonnet_rows(a.n, sigmas, a.seed), title="Gauss-Bonnet (chi: sphere 2, torus 0)"))
    print()
    print(text_table(["lines", "sigma", "count", "chord err median deg", "p95 deg", "drift p95 deg", "drift max deg"],
                     lines_rows(a.n, sigmas, a.seed), title="Lines of curvature on the torus"))
    print()
    print(text_table(["shape", "sigma", "types agree with truth %"], types_rows(a.n, sigmas, a.seed),
                     title="Point types (interior points)"))
    return 0
