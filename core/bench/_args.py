"""argparse types shared by the benchmarks' command lines."""

from __future__ import annotations

import argparse

import numpy as np


def levels(text: str):
    try:
        vals = tuple(float(x) for x in text.split(",") if x.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"levels must be comma-separated numbers, got {text!r}") from None
    if not vals or any(not np.isfinite(v) or v < 0 for v in vals):
        raise argparse.ArgumentTypeError(f"levels must be numbers >= 0, got {text!r}")
    return vals


def positive(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {v}")
    return v
