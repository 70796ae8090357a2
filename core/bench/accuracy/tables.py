"""Text and markdown tables of an :class:`~.cases.AccuracyRun`."""

from __future__ import annotations

import numpy as np

from .._table import fmt, text_table
from .cases import AccuracyRun, ShapeTable
from .config import APSS, APSSE, LABELS, NFE, NOISE_UNIT, NR15, ORACLES, OUTLIER_FRACTION, QUANTITIES, QUANTITY_TITLES
from .verdicts import targets


def _cand_label(col, c, grid=None) -> str:
    """A chosen k (or APSS scale/nPCA-k), with an arrow when it is at an end of its grid."""
    if c is None:
        return "–"
    value = c[1] if col in (APSS, APSSE) else c
    edge = ""
    if grid and len(grid) > 1:
        edge = "↑" if value == max(grid) else "↓" if value == min(grid) else ""
    if col in (APSS, APSSE):
        pk, sc = c
        return (f"{sc:g}" if pk is None else f"{sc:g}/n{pk}") + edge
    return f"{c}{edge}"


def race_rows(tab: ShapeTable, q: str):
    header = ["σ/spacing"] + [LABELS[c] for c in tab.columns]
    rows = []
    for li, lv in enumerate(tab.levels):
        vals = [tab.err[c][q][li] for c in tab.columns]
        rows.append([f"{lv:g}"] + [fmt(v) for v in vals])
    ref = [f"σ=0, exact n"] + [fmt(tab.ref[NFE][q]) if c == NR15 else
                              (fmt(tab.ref[APSSE][q]) if c == APSS and APSSE in tab.ref else "")
                              for c in tab.columns]
    rows.append(ref)
    return header, rows


def _bold_min(cells, values):
    """Markdown: bold the smallest finite value of a row."""
    finite = [v for v in values if v is not None and np.isfinite(v)]
    if not finite:
        return cells
    lo = min(finite)
    return [f"**{c}**" if v is not None and np.isfinite(v) and v == lo else c for c, v in zip(cells, values)]


def race_md_rows(tab: ShapeTable, q: str):
    header, rows = race_rows(tab, q)
    out = []
    for li, row in enumerate(rows[:-1]):
        vals = [tab.err[c][q][li] for c in tab.columns]
        out.append([row[0]] + _bold_min(row[1:], vals))
    out.append(rows[-1])
    header = list(header)
    header[header.index(LABELS[NR15])] = "NR k=15 (ref: NFE)"
    if APSS in tab.columns:
        header[header.index(LABELS[APSS])] = "APSS best (ref: exact n)"
    return header, out


def chosen_rows(tab: ShapeTable):
    """Which k / scale the oracles chose, per level (K/H/e1)."""
    header = ["σ/spacing"] + [LABELS[c] for c in tab.columns if c in ORACLES]
    if tab.auto_k:
        header.append("NR auto: median k (p10–p90)")
    rows = []
    for li, lv in enumerate(tab.levels):
        row = [f"{lv:g}"]
        for c in tab.columns:
            if c not in ORACLES:
                continue
            grid = tab.grids.get(c)
            row.append(" / ".join(_cand_label(c, tab.chosen[c][q][li], grid) for q, _, _ in QUANTITIES))
        if tab.auto_k:
            lo, hi = tab.auto_k_range[li]
            row.append(f"{tab.auto_k[li]:g} ({lo:g}–{hi:g})")
        rows.append(row)
    return header, rows


def robust_table(run_: AccuracyRun):
    header = ["shape", "σ", "method", "K", "H", "e1 (°)", "K growth", "H growth", "e1 growth", "invalid"]
    rows = []
    for r in run_.robust:
        d, c = r["dirty"], r["clean"]
        g = [(d[q] / c[q] - 1) * 100 if c[q] > 0 else float("nan") for q, _, _ in QUANTITIES]
        rows.append([r["shape"], f"{r['level']:g}", r["method"]] + [fmt(d[q]) for q, _, _ in QUANTITIES]
                    + [f"{x:+.0f}%" if np.isfinite(x) else "nan" for x in g] + [f"{100 * d['invalid']:.1f}%"])
    return header, rows


def options_table(run_: AccuracyRun, name, kmode, *, markdown_=False):
    rows_d = run_.options[(name, kmode)]
    levels = sorted({lv for r in rows_d.values() for lv in r})
    header = ["weights", "constraint", "passes"] + [f"{s} σ={lv:g}" for lv in levels for _, s, _ in QUANTITIES]
    keys = list(rows_d)
    cols = [(lv, q) for lv in levels for q, _, _ in QUANTITIES]
    vals = {key: [rows_d[key].get(lv, {}).get(q, float("nan")) for lv, q in cols] for key in keys}
    rows = []
    for key in keys:
        cells = [fmt(v) for v in vals[key]]
        if markdown_:
            col_min = [min(vals[k2][j] for k2 in keys if np.isfinite(vals[k2][j])) for j in range(len(cols))]
            cells = [f"**{c}**" if np.isfinite(v) and v == m else c for c, v, m in zip(cells, vals[key], col_min)]
        rows.append(list(key) + cells)
    return header, rows


def text_tables(run_: AccuracyRun) -> str:
    out = [f"Noise: {NOISE_UNIT}. Oracle columns (best k / best scale) pick, per shape, level and quantity, "
           "the grid value with the smallest error against the truth. Last row: σ=0 with exact normals "
           "(NF k=15 under 'NR k=15', APSS under 'APSS best')."]
    out += [f"NOTE: {n}" for n in run_.notes]
    for tab in run_.tables.values():
        for q, _, _ in QUANTITIES:
            header, rows = race_rows(tab, q)
            out.append(text_table(header, rows, title=f"{tab.title}: mean absolute error of {QUANTITY_TITLES[q]}"))
        header, rows = chosen_rows(tab)
        out.append(text_table(header, rows, title=f"{tab.title}: chosen k / APSS scale/nPCA-k (for K / H / e1)"))
    if run_.robust:
        header, rows = robust_table(run_)
        out.append(text_table(header, rows, title=f"Robustness: {100 * OUTLIER_FRACTION:g}% outliers, error on "
                                                  "the inliers; growth vs the same cloud without outliers"))
    for (name, kmode) in run_.options:
        header, rows = options_table(run_, name, kmode)
        out.append(text_table(header, rows, title=f"NR options on the {name}, k={kmode}"))
    tg = targets(run_)
    if tg:
        out.append("Targets of issue 4\n" + "\n".join(f"- [{v}] {t}: {d}" for t, v, d in tg))
    return "\n\n".join(out)
