"""``import core`` puts numpy's large arrays on 4 KiB pages (core._pages) unless the
environment chose with NUMPY_MADVISE_HUGEPAGE."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

_ADVICE = "import numpy as np, core; print(int(np._core.multiarray._get_madvise_hugepage()))"


def _advice(env_value):
    env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"}
    if env_value is not None:
        env["NUMPY_MADVISE_HUGEPAGE"] = env_value
    out = subprocess.run([sys.executable, "-c", _ADVICE], env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="numpy madvises huge pages on Linux only")
def test_import_core_turns_numpys_huge_page_advice_off_unless_the_environment_chose():
    pytest.importorskip("numpy._core")
    assert _advice(None) == "0"
    assert _advice("1") == "1"  # the user's choice wins
