"""The targets of issue 4, read off the numbers, and a short factual summary."""

from __future__ import annotations

import numpy as np

from .._table import fmt
from .cases import AccuracyRun
from .config import APSS, AUTO, LABELS, NFE, NR15, OUTLIER_FRACTION, QUANTITIES, QUANTITY_TITLES


def _ratio_text(r):
    return f"{fmt(r, 2)}×"


def reading(run_: AccuracyRun) -> list[str]:
    """A short factual summary: per column, in how many (shape, noise level, quantity)
    entries it has the smallest error, and the k the automatic choice settled on."""
    tabs = run_.tables
    if not tabs:
        return []
    cols = next(iter(tabs.values())).columns
    wins = {c: 0 for c in cols}
    total = 0
    for tab in tabs.values():
        for q, _, _ in QUANTITIES:
            for li in range(len(tab.levels)):
                fin = {c: tab.err[c][q][li] for c in cols if np.isfinite(tab.err[c][q][li])}
                if fin:
                    wins[min(fin, key=fin.get)] += 1
                    total += 1
    out = [f"Smallest error in {total} (shape, σ, quantity) entries: "
           + ", ".join(f"{LABELS[c]} {wins[c]}" for c in cols) + "."]
    for tab in tabs.values():
        if tab.auto_k:
            out.append(f"{tab.title}: NR auto's median k per σ " + ", ".join(
                f"{lv:g}: {k:g}" for lv, k in zip(tab.levels, tab.auto_k)) + ".")
    for q, _, _ in QUANTITIES:
        best = [(tab.value(NR15, q, lv) / tab.ref[NFE][q], tab.title) for tab in tabs.values()
                for lv in tab.levels if lv == 0.0 and NFE in tab.ref and tab.ref[NFE][q] > 0]
        if best:
            out.append(f"{QUANTITY_TITLES[q]} at σ=0, NR k=15 / NF with exact normals: "
                       + ", ".join(f"{t} {_ratio_text(r)}" for r, t in best) + ".")
    return out


def targets(run_: AccuracyRun) -> list[tuple[str, str, str]]:
    """The measurable targets of issue 4: (target, verdict, numbers) rows."""
    tabs = run_.tables
    cols = next(iter(tabs.values())).columns if tabs else ()
    default = AUTO if AUTO in cols else NR15
    dname = "NR auto" if default == AUTO else "NR k=15"
    tg = []
    if APSS in cols:
        fails, n, ratios = [], 0, []
        for name in ("torus", "saddle"):
            tab = tabs.get(name)
            if tab is None:
                continue
            for lv in (0.1, 0.2):
                if lv not in tab.levels:
                    continue
                for q, s, _ in QUANTITIES:
                    n += 1
                    a, b = tab.value(default, q, lv), tab.value(APSS, q, lv)
                    ratios.append(a / b)
                    if not a < b:
                        fails.append(f"{s} on the {name} at σ={lv:g} ({_ratio_text(a / b)})")
        if n:
            tg.append((f"{dname} (no parameter set) beats APSS at its best scale on K, H and e1, torus and saddle, "
                       "σ = 0.1 and 0.2", "met" if not fails else "NOT met",
                       f"wins {n - len(fails)}/{n}; error ratio ours/APSS {fmt(min(ratios), 2)}–{fmt(max(ratios), 2)}"
                       + (f"; loses {', '.join(fails)}" if fails else "")))
    r0 = []
    for tab in tabs.values():
        if 0.0 in tab.levels and NFE in tab.ref:
            for q, s, _ in QUANTITIES:
                r0.append((tab.value(default, q, 0.0) / tab.ref[NFE][q], f"{s} on the {tab.shape}"))
    if r0:
        worst = max(r0)
        over = [w for r, w in r0 if r > 1.5]
        tg.append((f"{dname} within 1.5× of NF with exact normals (k=15) at σ = 0", "met" if not over else "NOT met",
                   f"ratio {fmt(min(r for r, _ in r0), 2)}–{fmt(worst[0], 2)} (worst: {worst[1]}); above 1.5× in "
                   f"{len(over)}/{len(r0)}"))
    tab = tabs.get("torus")
    if tab is not None and 0.2 in tab.levels:
        v = tab.value(default, "direction_deg", 0.2)
        tg.append((f"{dname}: principal directions under 5° at σ = 0.2 on the torus", "met" if v < 5 else "NOT met",
                   f"{fmt(v)}°"))
    if run_.robust:
        for label in ("NR auto", "NR auto, Tukey", "NR k=15", "NR k=15, Tukey"):
            rows = [r for r in run_.robust if r["method"] == label]
            if not rows:
                continue
            g = [(r["dirty"][q] / r["clean"][q] - 1) for r in rows for q, _, _ in QUANTITIES]
            tg.append((f"{label}: with {100 * OUTLIER_FRACTION:g}% outliers the inlier error grows by < 25%",
                       "met" if max(g) < 0.25 else "NOT met",
                       f"{100 * min(g):+.0f}% to {100 * max(g):+.0f}% over K, H, e1 on "
                       + ", ".join(dict.fromkeys(r["shape"] for r in rows))
                       + f" at σ={', '.join(f'{lv:g}' for lv in dict.fromkeys(r['level'] for r in rows))}"))
    return tg
