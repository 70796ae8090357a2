"""Packaging: every package is in the wheel's list, resources are found from a checkout and
from an installed wheel, project files exist, and ``import core`` works read-only."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _pyproject():
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_package_is_listed_for_the_wheel():
    listed = set(_pyproject()["tool"]["setuptools"]["packages"])
    found = {
        ".".join(init.parent.relative_to(ROOT).parts)
        for top in ("core", "app") for init in (ROOT / top).rglob("__init__.py")
    }
    assert found <= listed, f"add {sorted(found - listed)} to [tool.setuptools] packages in pyproject.toml"
    assert "app.resources" in listed


def test_extras_and_library_dependencies():
    project = _pyproject()["project"]
    names = {dep.split(">")[0].split("[")[0].split("<")[0].strip().lower() for dep in project["dependencies"]}
    assert names == {"numpy", "scipy", "numba", "plyfile", "tqdm"}
    extras = project["optional-dependencies"]
    assert {"viewer", "las", "bench", "test", "all"} <= set(extras)
    assert any("pyvista>=0.49" in dep for dep in extras["viewer"])
    pins = [dep for dep in extras["viewer"] if dep.startswith("PySide6")]
    assert any("<6.12" in dep and "python_version < '3.12'" in dep for dep in pins)


def test_project_files():
    assert "BSD 3-Clause" in (ROOT / "LICENSE").read_text()
    cff = (ROOT / "CITATION.cff").read_text()
    assert "Estimating differential quantities from point cloud based on a linear fitting of normal vectors" in cff
    assert "Science in China Series F: Information Sciences" in cff
    assert (ROOT / "CHANGELOG.md").is_file() and (ROOT / "core" / "py.typed").is_file()


def test_resources_found_in_checkout_and_as_package_data(tmp_path):
    import app

    assert app.DEFAULT_CLOUD.is_file() and app.ICON.is_file()
    fake = tmp_path / "app"
    fake.mkdir()
    (fake / "resources").mkdir()
    shutil.copy(ROOT / "app" / "__init__.py", fake / "__init__.py")
    shutil.copy(ROOT / "resources" / "bunny.ply", fake / "resources" / "bunny.ply")
    code = "import app; print(app.RESOURCES)"
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(tmp_path)}, check=True).stdout.strip()
    assert Path(out) == (fake / "resources").resolve()


def _read_only_copy(tmp_path) -> Path:
    """A copy of core where numba cannot cache next to the sources (__pycache__ is a file)."""
    site = tmp_path / "site"
    shutil.copytree(ROOT / "core", site / "core", ignore=shutil.ignore_patterns("__pycache__", "*.nbi", "*.nbc"))
    for init in (site / "core").rglob("__init__.py"):
        (init.parent / "__pycache__").write_text("not a directory")
    return site


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX paths")
def test_import_core_with_read_only_home_and_install(tmp_path):
    site = _read_only_copy(tmp_path)
    home = tmp_path / "home"
    home.write_text("a file, so ~/.cache cannot be created")
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(HOME=str(home), TMPDIR=str(tmp), PYTHONPATH=str(site), PYTHONDONTWRITEBYTECODE="1")
    code = "import core, core._numba_cache as c; print(c.STATE['where'])"
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().startswith(str(tmp / "darboux-numba-"))


def test_no_writable_cache_dir_turns_caching_off():
    code = (
        "from pathlib import Path\nimport numba\nimport core._numba_cache as c\n"
        "where = c.configure(in_tree=Path('/dev/null/x'), fallbacks=[Path('/dev/null/y')])\n"
        "f = numba.njit(cache=True)(lambda x: x + 1)\nprint(where, f(1))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "off 2"
    assert proc.stderr.count("\n") == 1 and "numba's cache" in proc.stderr


def test_numba_cache_is_keyed_by_every_kernel_source(tmp_path):
    """A kernel's cache is stamped by its own file only: editing a callee in another file must
    start a new cache directory, or callers would load stale machine code."""
    site = tmp_path / "site"
    shutil.copytree(ROOT / "core", site / "core", ignore=shutil.ignore_patterns("__pycache__"))
    code = "import core._numba_cache as c; print(c.source_key())"
    env = {**os.environ, "PYTHONPATH": str(site)}

    def key() -> str:
        return subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                              text=True, env=env, check=True).stdout.strip()

    before = key()
    assert before == key()
    callee = site / "core" / "kernels" / "algebra.py"
    callee.write_text(callee.read_text() + "\n# edited\n")
    assert key() != before
