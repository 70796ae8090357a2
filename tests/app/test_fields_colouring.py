"""Colour maps that fit the field (pure numpy)."""

from __future__ import annotations

import numpy as np

from app.fields import FIELDS, colouring


def test_signed_fields_are_diverging_and_centred():
    values = np.linspace(0.2, 1.0, 100)  # H on a convex shape: still centred on 0
    look = colouring(FIELDS["mean"], values)
    assert look.cmap == "RdBu_r" and look.clim[0] == -look.clim[1]
    assert colouring(FIELDS["shape_index"], values).cmap == "RdBu_r"


def test_k1_is_sequential_on_a_convex_shape_and_diverging_on_a_saddle():
    rng = np.random.default_rng(0)
    convex = rng.uniform(0.7, 2.4, 1000)
    look = colouring(FIELDS["k1"], convex, clip=0)
    assert look.cmap == "viridis" and look.clim[0] > 0.6 and look.clim[1] < 2.5  # its own range
    mixed = rng.uniform(-1.0, 1.0, 1000)
    look = colouring(FIELDS["k2"], mixed)
    assert look.cmap == "RdBu_r" and look.clim[0] == -look.clim[1]
    # a few negative values (noise on a convex shape) do not make it diverging
    noisy = np.concatenate([convex, -0.01 * np.ones(20)])
    assert colouring(FIELDS["k1"], noisy, floor=0.001).cmap == "viridis"


def test_outlier_score_is_scaled_around_its_threshold():
    look = colouring(FIELDS["outlier_score"], np.full(500, 1.0))
    assert look.clim == (0.0, 8.0) and look.cmap == "RdBu_r"  # score 1 is blue, not bright


def test_chosen_k_on_a_log_scale_and_manual_limits_win():
    look = colouring(FIELDS["k_point"], np.array([20, 28, 40, 226, 226.0]))
    assert look.log and look.clim == (20.0, 226.0) and look.cmap == "viridis"
    manual = colouring(FIELDS["mean"], np.linspace(-1, 1, 10), clim=(-0.5, 0.5))
    assert manual.clim == (-0.5, 0.5) and not manual.log
    errors = colouring(FIELDS["err_mean"], np.linspace(0.1, 0.2, 50))
    assert errors.clim[0] == 0.0 and errors.cmap == "magma"
