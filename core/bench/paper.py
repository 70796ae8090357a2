"""The paper's experiment: Cheng & Zhang (2009), §3 and §5, Figures 2–5.

Random points on a torus (R = 2, r = 1) and on a closed surface with saddles (standing in
for Goldfeather & Interrante's surface), k = 15 neighbours, isotropic Gaussian noise of
increasing standard deviation. For every method the mean absolute error of the Gaussian
curvature K, of the mean curvature H and of the principal direction e1 (degrees) is
averaged over ``repeats`` independent samples.

* Figures 2–4 (§3): the same surface fitted to points or to normals — QP, QN, CF, CN with
  normals estimated by weighted PCA, plus QPE, QNE, CFE, CNE: noise-free points with the
  exact normals.
* Figure 5 (§5): CF, CT, NF, NR with estimated normals, plus CFE, NFE, NRE.

``python -m core bench paper`` calls :func:`main`; :func:`run` returns the numbers.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import build_neighbours, estimate, metrics, noise, shapes
from ._args import levels as _levels
from ._args import positive as _positive
from ._table import error_panels, fmt, markdown_table, style, text_table

#: every method run with estimated normals (columns of the tables)
METHODS = ("qp", "qn", "cf", "cn", "ct", "nf", "nr")
FIG2_4 = ("qp", "qn", "cf", "cn")
FIG2_4_EXACT = ("qp", "qn", "cf", "cn")
FIG5 = ("cf", "ct", "nf", "nr")
FIG5_EXACT = ("cf", "nf", "nr")
#: (key of metrics.summary, short name, axis label)
QUANTITIES = (
    ("gaussian", "K", "mean |K − K_true|  (1/length²)"),
    ("mean", "H", "mean |H − H_true|  (1/length)"),
    ("direction_deg", "e1", "mean angle(e1, e1_true)  (degrees)"),
)
QUANTITY_TITLES = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H = (k1 + k2)/2",
                   "direction_deg": "principal direction e1"}
DEFAULT_LEVELS = (0.0, 0.05, 0.1, 0.15, 0.2, 0.3, 0.4)
QUICK = dict(points=1000, levels=(0.0, 0.4), repeats=1)
SURFACES = {
    "torus": ("torus (R = 2, r = 1)", lambda n, seed: shapes.torus(n, R=2.0, r=1.0, seed=seed)),
    "saddle": ("saddle surface (Goldfeather stand-in)", lambda n, seed: shapes.saddle(n, seed=seed)),
}
EXACT_ROW = "σ=0, exact n"
NOISE_UNIT = "σ of isotropic Gaussian noise, as a fraction of the mean point spacing"


@dataclass
class SurfaceTable:
    """Errors on one surface, averaged over the repeats.

    ``mean[q]``, ``median[q]``, ``std[q]`` : (levels, methods) arrays for quantity ``q``
    (a key of :data:`QUANTITIES`) with estimated normals: the mean absolute error (and the
    median absolute error), averaged over repeats, and the spread of the per-repeat means.
    ``exact_mean[q]``, ``exact_median[q]`` : (methods,) arrays, noise-free with exact normals.
    ``invalid`` : (levels, methods) mean fraction of points the method left invalid.
    """

    surface: str
    title: str
    n_points: int
    k: int
    repeats: int
    levels: tuple
    methods: tuple
    mean: dict = field(default_factory=dict)
    median: dict = field(default_factory=dict)
    std: dict = field(default_factory=dict)
    exact_mean: dict = field(default_factory=dict)
    exact_median: dict = field(default_factory=dict)
    invalid: np.ndarray | None = None
    spacing: float = float("nan")
    seconds: float = 0.0

    def value(self, quantity, method, level=None, *, exact=False, stat="mean") -> float:
        """One entry: ``level`` is a noise level (default the highest) unless ``exact``."""
        j = self.methods.index(method)
        if exact:
            return float((self.exact_mean if stat == "mean" else self.exact_median)[quantity][j])
        i = len(self.levels) - 1 if level is None else self.levels.index(level)
        return float((self.mean if stat == "mean" else self.median)[quantity][i, j])


@dataclass
class PaperRun:
    """What :func:`run` returns: one :class:`SurfaceTable` per surface plus the setup."""

    tables: dict
    setup: dict
    seconds: float


def _seed(*parts) -> int:
    return int(np.random.SeedSequence([int(p) for p in parts]).generate_state(1)[0])


def _errors(result, sample):
    """(mean, median) absolute error per quantity, over the points metrics.summary uses."""
    means = metrics.summary(result, sample)
    pe = metrics.point_errors(result, sample)
    medians = {}
    for q, _, _ in QUANTITIES:
        v = pe[q][sample.interior & np.isfinite(pe[q])]
        medians[q] = float(np.median(v)) if len(v) else float("nan")
    return {q: means[q] for q, _, _ in QUANTITIES}, medians, means["invalid_fraction"]


def run(points=5000, k=15, levels=DEFAULT_LEVELS, repeats=3, seed=0, surfaces=("torus", "saddle"),
        methods=METHODS, progress=None) -> PaperRun:
    """Run the experiment and return the table data.

    Parameters
    ----------
    points : number of random points per sample.
    k : neighbourhood size (the paper: 15).
    levels : noise levels, σ as a fraction of the mean point spacing of the clean sample.
    repeats : independent samples (surface and noise seeds) averaged per entry.
    seed : base seed; the same arguments give the same numbers.
    surfaces : names from :data:`SURFACES`.
    methods : names from :data:`core.METHODS`, run with PCA normals at every level and with
        the exact normals on the noise-free sample.
    progress : callable(message: str), optional.
    """
    levels = tuple(float(x) for x in levels)
    methods = tuple(methods)
    if not levels or any(not np.isfinite(x) or x < 0 for x in levels):
        raise ValueError(f"levels must be finite numbers >= 0, got {levels}")
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    unknown = [s for s in surfaces if s not in SURFACES]
    if unknown:
        raise ValueError(f"unknown surface(s) {unknown}; valid: {list(SURFACES)}")
    t_all = time.perf_counter()
    tables = {}
    nq, nl, nm = len(QUANTITIES), len(levels), len(methods)
    for s_i, name in enumerate(surfaces):
        title, make = SURFACES[name]
        t0 = time.perf_counter()
        est_mean = np.full((repeats, nq, nl, nm), np.nan)
        est_median = np.full_like(est_mean, np.nan)
        invalid = np.zeros((repeats, nl, nm))
        ex_mean = np.full((repeats, nq, nm), np.nan)
        ex_median = np.full_like(ex_mean, np.nan)
        spacing = []
        for r in range(repeats):
            sample = make(points, _seed(seed, s_i, r))
            spacing.append(noise.mean_spacing(sample.points))
            # noise-free points with the exact normals (the paper's "E" curves)
            nb = build_neighbours(sample.points, k)
            for j, m in enumerate(methods):
                res = estimate(sample.points, sample.normals, k=k, method=m, neighbours=nb)
                mean, median, _ = _errors(res, sample)
                for qi, (q, _, _) in enumerate(QUANTITIES):
                    ex_mean[r, qi, j], ex_median[r, qi, j] = mean[q], median[q]
            # estimated normals (weighted PCA) at every noise level, the same noisy cloud for all methods
            for li, sigma in enumerate(levels):
                pts = noise.add_noise(sample.points, sigma, relative=True, spacing=spacing[-1],
                                      seed=_seed(seed, s_i, r, li + 1))
                nb = build_neighbours(pts, k)
                for j, m in enumerate(methods):
                    res = estimate(pts, k=k, method=m, neighbours=nb)
                    mean, median, inv = _errors(res, sample)
                    invalid[r, li, j] = inv
                    for qi, (q, _, _) in enumerate(QUANTITIES):
                        est_mean[r, qi, li, j], est_median[r, qi, li, j] = mean[q], median[q]
            if progress is not None:
                progress(f"[{name}] repeat {r + 1}/{repeats} done, {time.perf_counter() - t0:.1f} s")
        tab = SurfaceTable(name, title, points, k, repeats, levels, methods, invalid=invalid.mean(0),
                           spacing=float(np.mean(spacing)))
        for qi, (q, _, _) in enumerate(QUANTITIES):
            tab.mean[q] = est_mean[:, qi].mean(0)
            tab.median[q] = est_median[:, qi].mean(0)
            tab.std[q] = est_mean[:, qi].std(0)
            tab.exact_mean[q] = ex_mean[:, qi].mean(0)
            tab.exact_median[q] = ex_median[:, qi].mean(0)
        tab.seconds = time.perf_counter() - t0
        tables[name] = tab
    setup = dict(points=points, k=k, levels=levels, repeats=repeats, seed=seed, surfaces=tuple(surfaces),
                 methods=methods)
    return PaperRun(tables, setup, time.perf_counter() - t_all)


# ----------------------------------------------------------------------------- tables
def table_rows(tab: SurfaceTable, quantity: str, stat: str = "mean"):
    """Header and rows of one quantity: rows = noise levels, then the exact-normal row."""
    header = ["σ/spacing"] + [m.upper() for m in tab.methods]
    est = (tab.mean if stat == "mean" else tab.median)[quantity]
    ex = (tab.exact_mean if stat == "mean" else tab.exact_median)[quantity]
    rows = [[f"{lv:g}"] + [fmt(v) for v in est[i]] for i, lv in enumerate(tab.levels)]
    rows.append([EXACT_ROW] + [fmt(v) for v in ex])
    return header, rows


def _caption(tab: SurfaceTable, quantity: str) -> str:
    return (f"{tab.title}, N = {tab.n_points}, k = {tab.k}, {tab.repeats} repeat(s): "
            f"mean absolute error of {QUANTITY_TITLES[quantity]}")


def text_tables(run_: PaperRun) -> str:
    out = [f"Noise: {NOISE_UNIT}. Rows: noise level with PCA-estimated normals; "
           f"last row '{EXACT_ROW}': noise-free points with the exact normals (QPE, QNE, ...)."]
    for tab in run_.tables.values():
        for q, _, _ in QUANTITIES:
            header, rows = table_rows(tab, q)
            out.append(text_table(header, rows, title=_caption(tab, q)))
    return "\n\n".join(out)


# ----------------------------------------------------------------------------- plots
def _ymax(tab: SurfaceTable, quantity: str, methods) -> float | None:
    """Top of the y axis: 4x the largest mean error that is not dominated by a few blown-up
    points (mean > 5x median); None (automatic) when nothing is blown up."""
    cols = [tab.methods.index(m) for m in methods if m in tab.methods]
    mean, median = tab.mean[quantity][:, cols], tab.median[quantity][:, cols]
    blown = mean > 5 * median
    if not blown.any() or blown.all():
        return None
    return float(4 * np.nanmax(np.where(blown, np.nan, mean)))


def plot(tab: SurfaceTable, out: Path) -> list[Path]:
    """The two figures of ``tab``: fig 2–4 (points vs normals) and fig 5 (CF/CT/NF/NR)."""
    x = list(tab.levels)
    xlabel = "noise σ  (fraction of mean point spacing)"
    paths = []
    for fname, est, exact, what in (
        (f"paper_fig2_4_{tab.surface}.png", FIG2_4, FIG2_4_EXACT, "fitting to points (dashed) vs normals (solid)"),
        (f"paper_fig5_{tab.surface}.png", FIG5, FIG5_EXACT, "CF, CT, NF, NR"),
    ):
        panels = []
        for q, _, ylabel in QUANTITIES:
            curves = [(m.upper(), tab.mean[q][:, tab.methods.index(m)], style(m))
                      for m in est if m in tab.methods]
            hlines = [(m.upper() + "E", tab.exact_mean[q][tab.methods.index(m)], style(m, exact=True))
                      for m in exact if m in tab.methods]
            panels.append(dict(ylabel=ylabel, title=QUANTITY_TITLES[q], curves=curves, hlines=hlines,
                               ymax=_ymax(tab, q, est)))
        title = (f"{tab.title[0].upper()}{tab.title[1:]}: {what} — N = {tab.n_points} points, k = {tab.k}, "
                 f"{tab.repeats} repeat(s); dotted: noise-free, exact normals (…E)")
        paths.append(error_panels(out / fname, x, panels, title=title, xlabel=xlabel, logy=True,
                                  ncol=len(est) + len(exact)))
    return paths


# ----------------------------------------------------------------------------- reading
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


# ----------------------------------------------------------------------------- markdown
def markdown(run_: PaperRun, *, command: str, images: dict) -> str:
    s = run_.setup
    lines = [
        "# Cheng & Zhang (2009), Figures 2–5: curvature error vs noise",
        "",
        f"Generated by `{command}` on {_dt.date.today().isoformat()} in {run_.seconds:.1f} s "
        f"(`core.bench.paper`). Do not edit by hand: rerun the command.",
        "",
        "## Setup",
        "",
        f"- Surfaces: {', '.join(run_.tables[n].title for n in run_.tables)}; {s['points']} area-uniform random "
        f"points each, k = {s['k']} nearest neighbours (the point itself included).",
        f"- Noise: {NOISE_UNIT} of the clean sample (the paper only says \"random noise with different "
        f"variance\"). Levels: {', '.join(f'{x:g}' for x in s['levels'])}. "
        + "Mean spacing: " + ", ".join(f"{fmt(t.spacing)} on the {n}" for n, t in run_.tables.items()) + ".",
        "- Estimated normals: weighted PCA (eqs. 13–14), oriented outward, then the fit (`core.estimate` defaults; "
        "NR = NF + 1 refinement pass). Errors are measured against the exact values at the clean point.",
        f"- `{EXACT_ROW}` rows (the paper's QPE, QNE, CFE, CNE, NFE, NRE): noise-free points with the exact "
        "normals as input.",
        f"- Entries: mean absolute error over all points, averaged over {s['repeats']} independent sample(s) "
        f"(base seed {s['seed']}). H = (k1 + k2)/2 (the paper prints k1 + k2: its errors in H would be twice "
        "ours); direction = angle between estimated and true e1 (sign-free), in degrees, skipping "
        f"near-umbilic points (|k1 − k2| ≤ {metrics.UMBILIC} max|k|).",
        "- Methods: QP/QN quadric fitted to points/normals, CF cubic fitted to points + normals (Goldfeather & "
        "Interrante), CN cubic fitted to normals, CT curvature tensor (Batagelo & Wu), NF normal fitting, "
        "NR normal fitting with one normal refinement.",
        "",
        "## Reading of these numbers",
        "",
        "Generated from the tables below (mean absolute errors, PCA normals, all surfaces, quantities and "
        "noise levels unless said otherwise; 'median ratio' is the median over entries of the ratio of the "
        "two methods' errors):",
        "",
        *[f"- {sentence}" for sentence in reading(run_)],
        "",
    ]
    for name, tab in run_.tables.items():
        lines += [f"## {tab.title[0].upper()}{tab.title[1:]}", ""]
        for q, _, _ in QUANTITIES:
            header, rows = table_rows(tab, q)
            lines += [f"**{_caption(tab, q)}**", "", markdown_table(header, rows), ""]
        i = len(tab.levels) - 1
        header = ["quantity"] + [m.upper() for m in tab.methods]
        rows = [[QUANTITY_TITLES[q]] + [fmt(v) for v in tab.median[q][i]] for q, _, _ in QUANTITIES]
        lines += [f"**Median absolute error at σ={tab.levels[i]:g} (PCA normals), for comparison with the "
                  "means above: robust to a few blown-up points**", "", markdown_table(header, rows), ""]
        inv = tab.invalid
        if np.nanmax(inv) > 0:
            j = np.unravel_index(np.nanargmax(inv), inv.shape)
            lines += [f"Invalid (degenerate) points: at most {100 * inv[j]:.2f}% "
                      f"({tab.methods[j[1]].upper()} at σ={tab.levels[j[0]]:g}); they are left out of the means.", ""]
        for p in images.get(name, ()):
            lines += [f"![{p.stem}]({p.name})", ""]
    return "\n".join(lines)


# ----------------------------------------------------------------------------- CLI
def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m core bench paper",
        description="Reproduce Cheng & Zhang (2009) Figures 2–5: mean absolute error of K, H and the "
                    "principal direction vs noise on a torus and a saddle surface.",
    )
    p.add_argument("--points", type=_positive, default=None, help="points per sample (default 5000; --quick 1000)")
    p.add_argument("--k", type=_positive, default=15, help="neighbourhood size (default 15)")
    p.add_argument("--levels", type=_levels, default=None,
                   help="noise σ as fractions of the mean spacing, comma-separated "
                        "(default 0,0.05,0.1,0.15,0.2,0.3,0.4; --quick 0,0.4)")
    p.add_argument("--repeats", type=_positive, default=None, help="samples averaged per entry (default 3; --quick 1)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    p.add_argument("--surface", choices=("torus", "saddle", "both"), default="both", help="default both")
    p.add_argument("--out", default="docs/bench", help="directory for paper.md and the PNGs (default docs/bench)")
    p.add_argument("--quick", action="store_true", help="1000 points, 2 noise levels, 1 repeat (seconds)")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    quick = QUICK if args.quick else dict(points=5000, levels=DEFAULT_LEVELS, repeats=3)
    points = args.points or quick["points"]
    levels = args.levels or quick["levels"]
    repeats = args.repeats or quick["repeats"]
    surfaces = ("torus", "saddle") if args.surface == "both" else (args.surface,)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    def report(msg):
        print(msg, file=sys.stderr, flush=True)

    result = run(points=points, k=args.k, levels=levels, repeats=repeats, seed=args.seed,
                 surfaces=surfaces, progress=report)
    print(text_tables(result))
    print()
    for sentence in reading(result):
        print(sentence)
    images = {name: plot(tab, out) for name, tab in result.tables.items()}
    cmd = (f"python -m core bench paper --points {points} --k {args.k} "
           f"--levels {','.join(f'{x:g}' for x in levels)} --repeats {repeats} --seed {args.seed} "
           f"--surface {args.surface} --out {args.out}")
    md = out / "paper.md"
    md.write_text(markdown(result, command=cmd, images=images) + "\n", encoding="utf-8")
    print(f"\nwrote {md} and {', '.join(str(p) for ps in images.values() for p in ps)} "
          f"({result.seconds:.1f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
