"""The paper's claims checked against the numbers (the "Reading" of paper.md)."""

from __future__ import annotations

import numpy as np

from .._table import fmt
from .config import QUANTITIES
from .experiment import PaperRun


def _cases(run_, better, worse, *, exact=False, stat="mean"):
    """(wins, total, failures, ratios) of error(better) < error(worse) over surfaces, quantities, levels."""
    wins = total = 0
    fails, ratios = [], []
    for tab in run_.tables.values():
        if better not in tab.methods or worse not in tab.methods:
            continue
        for q, short, _ in QUANTITIES:
            for lv in [None] if exact else list(tab.levels):
                b = tab.value(q, better, lv, exact=exact, stat=stat)
                w = tab.value(q, worse, lv, exact=exact, stat=stat)
                total += 1
                ratios.append(b / w)
                if b < w:
                    wins += 1
                else:
                    fails.append(f"{short} on the {tab.surface}" + ("" if exact else f" at σ={lv:g}"))
    return wins, total, fails, ratios


def _list(fails, limit=4):
    if not fails:
        return ""
    more = f" and {len(fails) - limit} more" if len(fails) > limit else ""
    return " (not: " + ", ".join(fails[:limit]) + more + ")"


def _claim(run_, better, worse, **kw):
    """(verdict fraction, text) of error(better) < error(worse)."""
    w, t, f, r = _cases(run_, better, worse, **kw)
    if not t:
        return float("nan"), ""
    b, o = (better.upper(), worse.upper()) if not kw.get("exact") else (better.upper() + "E", worse.upper() + "E")
    return w / t, f"{b} < {o} in {w}/{t}{_list(f)}, median ratio {fmt(float(np.median(r)), 2)}"


def _verdict(fraction) -> str:
    if not np.isfinite(fraction):
        return "not tested"
    return "holds" if fraction == 1 else "mostly holds" if fraction >= 0.75 else "partly holds" if fraction >= 0.4 \
        else "does not hold"


def reading(run_: PaperRun) -> list[str]:
    """One sentence per ordering claimed by the paper, checked against these numbers.

    Counts run over all (surface, quantity, noise level) entries with PCA normals and
    compare mean errors unless said otherwise; "median ratio" is the median of the
    error ratios of the two methods.
    """
    out = []
    names = {m for t in run_.tables.values() for m in t.methods}
    top = max(max(t.levels) for t in run_.tables.values())
    low = min(min(t.levels) for t in run_.tables.values())
    has = lambda *ms: all(m in names for m in ms)  # noqa: E731
    if has("qp", "qn"):
        v, txt = _claim(run_, "qn", "qp")
        _, txt_med = _claim(run_, "qn", "qp", stat="median")
        _, txt_ex = _claim(run_, "qn", "qp", exact=True)
        out.append(f"*Fitting normals beats fitting points with the same surface (§3)* {_verdict(v)} for the "
                   f"quadric: {txt}; with median instead of mean errors {txt_med}; noise-free with exact normals "
                   f"{txt_ex}.")
    if has("cf", "cn"):
        w, t, _, r = _cases(run_, "cn", "cf")
        _, txt_ex = _claim(run_, "cn", "cf", exact=True)
        med = float(np.median(r)) if r else float("nan")
        out.append(f"*Fitting points and normals (CF) does not improve on fitting normals only (CN) (§3)* "
                   f"{'holds to within a few percent' if med <= 1.05 else 'does not hold'}: CN/CF median ratio {fmt(med, 2)} "
                   f"(CN < CF in {w}/{t}); but noise-free with exact normals {txt_ex}.")
    if has("nf", "cf", "ct"):
        v1, t1 = _claim(run_, "nf", "cf")
        v2, t2 = _claim(run_, "nf", "ct")
        out.append(f"*NF beats CF and CT with estimated normals (§5)* {_verdict(min(v1, v2))}: {t1}; {t2}.")
    if has("nr"):
        best_top = n_top = best_all = n_all = 0
        fails = []
        for tab in run_.tables.values():
            j = tab.methods.index("nr")
            for q, short, _ in QUANTITIES:
                is_best = np.nanargmin(tab.mean[q], axis=1) == j
                n_top += 1
                best_top += bool(is_best[-1])
                if not is_best[-1]:
                    win = tab.methods[int(np.nanargmin(tab.mean[q][-1]))].upper()
                    fails.append(f"{short} on the {tab.surface}, {win} best")
                n_all += len(is_best)
                best_all += int(is_best.sum())
        out.append(
            f"*NR is best at high noise (§5)* {_verdict(best_top / n_top)}: NR has the smallest error of the "
            f"PCA-normal methods at σ={top:g} in {best_top}/{n_top} (surface, quantity) cases{_list(fails)}, "
            f"and in {best_all}/{n_all} of all entries"
            + (" (so at every noise level, not only at high noise)." if best_all == n_all else ".")
        )
    bests, ratios = [], []
    for tab in run_.tables.values():
        i0 = tab.levels.index(min(tab.levels))
        for q, short, _ in QUANTITIES:
            ex = tab.exact_mean[q]
            j = int(np.nanargmin(ex))
            bests.append(f"{tab.methods[j].upper()}E for {short} on the {tab.surface}")
            ratios += list(ex / tab.mean[q][i0])
    if bests:
        worst = float(np.nanmax(ratios))
        out.append(
            f"*Given exact normals all methods have small errors (§5)* {'holds' if worst < 1 else 'does not hold'}: "
            f"exact instead of PCA normals on the σ={low:g} points scales the errors by "
            f"{fmt(float(np.nanmin(ratios)), 2)}–{fmt(worst, 2)} (median {fmt(float(np.nanmedian(ratios)), 2)}); "
            "the most accurate with exact normals is " + ", ".join(bests) + "."
        )
    tails = []
    for tab in run_.tables.values():
        for j, m in enumerate(tab.methods):
            mean, med = tab.mean["gaussian"][-1, j], tab.median["gaussian"][-1, j]
            if np.isfinite(mean) and np.isfinite(med) and med > 0 and mean > 5 * med:
                tails.append(f"{m.upper()} on the {tab.surface} (mean {fmt(mean)}, median {fmt(med)})")
    if tails:
        out.append(
            f"*Caveat*: at σ={top:g} a few points dominate the mean K error of " + ", ".join(tails)
            + ": the slopes −n_x/n_z, −n_y/n_z fitted by QN, CN and CF blow up where the PCA normal of a "
            "neighbour is nearly tangent to the centre's frame."
        )
    return out
