"""Captions and status lines of a result: the views' titles, the status bar, the parameters
of an export (text only, no Qt; :mod:`app.presenter` draws them).
"""

from __future__ import annotations

import textwrap

import numpy as np

import core

__all__ = ["method_title", "uses_passes", "summary_line", "status_line", "preview_line", "result_parameters",
           "orientation_text", "title", "degenerate"]


def method_title(name: str | None) -> str:
    method = core.METHODS.get(name) if name else None
    return getattr(method, "title", name or "")


def uses_passes(name: str | None) -> bool:
    return bool(getattr(core.METHODS.get(name), "uses_passes", False)) if name else False


def degenerate(result) -> str | None:
    """Why core made no estimate for the whole cloud, or None."""
    return (getattr(result, "params", None) or {}).get("degenerate")


def _passes_text(result) -> str:
    """Refinement passes kept, with the maximum when fewer were (k="auto" stops early)."""
    run = getattr(result, "params", {}).get("passes_run", result.passes)
    return f"{run}" if run == result.passes else f"{run} of max {result.passes}"


def orientation_text(orientation) -> str:
    """How the normals were oriented, for captions ("oriented toward (1, 2, 3)"); "" for the default."""
    if isinstance(orientation, tuple):
        return "oriented toward (" + ", ".join(f"{v:.3g}" for v in orientation) + ")"
    return {"propagate": "oriented up (+z)", "keep": "file's normals kept",
            "viewpoints": "oriented toward the scanners"}.get(orientation, "")


def _oriented(out) -> str:
    """:func:`orientation_text` of how a result was oriented: the request's mode, or its
    scanners' positions where "auto" faced them (an E57 file's, ``params["orientation"]``)."""
    params = getattr(out.result, "params", None) or {}
    return orientation_text("viewpoints" if params.get("orientation") == "viewpoints" else out.request.orientation)


def title(out, method: str, result, summary: dict | None) -> str:
    """Top-left caption of a view: method and parameters (or why there is no estimate), cloud, errors."""
    req = out.request
    why = degenerate(result)
    text = f"{method_title(method)}\n" + ("no estimate: " + "\n  ".join(textwrap.wrap(why, 48)) if why
                                           else f"k = {result.k}")
    if not why and getattr(result, "passes", None) is not None and uses_passes(method):
        text += f",  passes = {_passes_text(result)}"
    if req.noise > 0:
        text += f"{chr(10) if why else ',  '}noise {req.noise:g}%"
    if _oriented(out):
        text += f"\n{_oriented(out)}"
    text += f"\n{req.source.name}"
    if summary:
        text += "\n" + summary_line(summary, None, short=True)
    return text


def result_parameters(out) -> str:
    """Method and parameters of a result: "NR k=auto (median 14) passes=4  ·  noise 5%"."""
    res, req = out.result, out.request
    why = degenerate(res)  # nothing ran: the k asked for, no median of the -1 placeholders, no passes
    k = f"auto (median {int(np.median(res.k_point))})" if res.k == "auto" and not why else res.k
    text = f"{req.method.upper()} k={k}"
    if not why and getattr(res, "passes", None) is not None and uses_passes(req.method):
        text += f" passes={_passes_text(res)}"
    text += f"  ·  noise {req.noise:g}%" if req.noise > 0 else ""
    return text + (f"  ·  {_oriented(out)}" if _oriented(out) else "")


def status_line(out) -> str:
    """The status bar's description of a result."""
    res, req = out.result, out.request
    why = degenerate(res)
    invalid = int(getattr(res, "n_invalid", int(np.count_nonzero(~np.asarray(res.valid)))))
    if why:  # nothing was estimated: the reason first (a narrow window cuts the line off), no passes
        return (f"{req.source.name}: {len(out.points):,} points  ·  {result_parameters(out)} — no estimate: {why}"
                f"  ·  {invalid:,} invalid (grey)  ·  {out.elapsed:.2f} s")
    text = f"{req.source.name}: {len(out.points):,} points  ·  {result_parameters(out)}"
    text += f"  ·  {invalid:,} invalid (grey)" if invalid else "  ·  all valid"
    border = getattr(res, "border", None)
    n_border = 0 if border is None else int(np.count_nonzero(border))
    text += f"  ·  {n_border:,} on a border (grey)" if n_border else ""
    text += _params_text(getattr(res, "params", None) or {})
    text += f"  ·  {out.elapsed:.2f} s" + _reused_text(out)
    return text


def _params_text(params) -> str:
    """What the estimate did to the cloud it was given: file normals repaired or used for
    their signs only (core.given_normals_check), points in a volume (core.volumetric),
    duplicates merged."""
    repaired = params.get("normals_repaired") or {}
    fixed = repaired.get("unusable", 0) + repaired.get("renormalised", 0)
    text = f"  ·  {fixed:,} file normals repaired" if fixed else ""
    text += "  ·  file normals rough: used for their signs only" if repaired.get("use") == "signs" else ""
    volume = params.get("volumetric", 0)
    text += f"  ·  {volume:,} on no surface (a volume)" if volume else ""
    copies = params.get("duplicates", 0)
    return text + (f"  ·  {copies:,} duplicates merged" if copies else "")


#: How the status line names the stages re-used from the previous estimate (core.stage_cache).
_STAGE_NAMES = {"initial": "initial normals", "orientation": "orientation", "scale": "chosen k"}


def _reused_text(out) -> str:
    """" (neighbours, initial normals, orientation, chosen k re-used)", or what of it was."""
    names = (["neighbours"] if out.reused_neighbours else []) + [
        text for stage, text in _STAGE_NAMES.items() if stage in getattr(out, "reused_stages", ())]
    return f" ({', '.join(names)} re-used)" if names else ""


def preview_line(out) -> str:
    """The status bar while a preview is shown."""
    req = out.request
    k = req.k if not req.k_auto else f"{out.result.k} (paper's pipeline)"
    oriented = f", {_oriented(out)}" if _oriented(out) else ""
    return (f"{req.source.name}: PREVIEW ({req.method.upper()} k={k}{oriented} on {out.preview:,} of "
            f"{len(out.points):,} points, {out.elapsed:.2f} s) — computing the full result…")


def summary_line(summary: dict | None, method: str | None, *, short: bool = False) -> str:
    """One line of mean absolute errors against the truth."""
    if not summary:
        return ""
    parts = []
    for key, label, unit in (("mean", "H", ""), ("gaussian", "K", ""), ("k1", "k1", ""), ("k2", "k2", ""),
                             ("normal_deg", "n", "°"), ("direction_deg", "dir", "°")):
        value = summary.get(key)
        if value is not None and np.isfinite(value):
            parts.append(f"{label} {value:.3g}{unit}")
    if short:
        keep = [p for p in parts if p.split()[0] in ("H", "K", "dir")]
        return "mean abs. error:  " + "   ".join(keep)
    return f"{(method or '').upper()} mean abs. error: " + ", ".join(parts)
