"""What the accuracy and paper benchmarks share: the quantities compared, the noise
unit, the seeding, and the checks of a run's arguments."""

from __future__ import annotations

import threading
import time

import numpy as np

#: (key of metrics.summary, short name, axis label)
QUANTITIES = (
    ("gaussian", "K", "mean |K − K_true|  (1/length²)"),
    ("mean", "H", "mean |H − H_true|  (1/length)"),
    ("direction_deg", "e1", "mean angle(e1, e1_true)  (degrees)"),
)
QUANTITY_TITLES = {"gaussian": "Gaussian curvature K", "mean": "mean curvature H = (k1 + k2)/2",
                   "direction_deg": "principal direction e1"}
NOISE_UNIT = "σ of isotropic Gaussian noise, as a fraction of the mean point spacing"


def seed_of(*parts) -> int:
    """A reproducible seed from integers (the same parts give the same seed)."""
    return int(np.random.SeedSequence([int(p) for p in parts]).generate_state(1)[0])


def check_run(levels, count, count_name, names, valid, what) -> tuple:
    """Noise ``levels`` as a tuple of floats; ValueError for a level < 0 or not finite,
    ``count`` < 1 or a name not in ``valid``."""
    levels = tuple(float(x) for x in levels)
    if not levels or any(not np.isfinite(x) or x < 0 for x in levels):
        raise ValueError(f"levels must be finite numbers >= 0, got {levels}")
    if count < 1:
        raise ValueError(f"{count_name} must be >= 1, got {count}")
    unknown = [s for s in names if s not in valid]
    if unknown:
        raise ValueError(f"unknown {what}(s) {unknown}; valid: {list(valid)}")
    return levels


class Sampler:
    """A context manager that calls :meth:`sample` every ``interval`` seconds in a thread
    (and once more on exit): the memory samplers of the perf and tiled benchmarks."""

    interval = 0.1

    def sample(self) -> None:
        raise NotImplementedError

    def __enter__(self):
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()
        return self

    def _run(self):
        while not self._stop.is_set():
            self.sample()
            time.sleep(self.interval)

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()
        self.sample()
