"""Text tables of a :class:`~.experiment.PaperRun`."""

from __future__ import annotations

from .._table import fmt, text_table
from .config import EXACT_ROW, NOISE_UNIT, QUANTITIES, QUANTITY_TITLES
from .experiment import PaperRun, SurfaceTable


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
