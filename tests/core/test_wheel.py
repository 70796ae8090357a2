"""The built wheel, installed into fresh virtual environments (marked ``wheel``: run by
``.ci/run``, or ``python -m pytest -m wheel``; deselected from the default run).

Offline and quick: the fresh environments see the dependencies already installed through
a ``.pth`` file (all of the current environment for the viewer; only the library's own
dependencies for the library-only install), and pip installs the wheel with
``--no-index``, so the wheel's metadata must resolve against them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

import pytest

pytestmark = pytest.mark.wheel
ROOT = Path(__file__).resolve().parents[2]
SHARED = Path(sysconfig.get_paths()["purelib"])
#: the library's dependencies (and theirs), as top-level import names and distributions
LIBRARY = ("numpy", "scipy", "numba", "llvmlite", "plyfile", "tqdm")
GUI = {"PySide6", "vtk", "vtkmodules", "matplotlib", "pyvista", "pyvistaqt", "superqt", "laspy"}


def _run(cmd, **kwargs):
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900, **kwargs)
    assert proc.returncode == 0, f"{cmd}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    _run([sys.executable, "-m", "build", "--wheel", "--outdir", str(out), str(ROOT)])
    (whl,) = out.glob("darboux-*.whl")
    return whl


def _venv(path: Path, visible: Path) -> Path:
    venv.create(path, with_pip=False)
    purelib = Path(subprocess.check_output(
        [str(path / "bin" / "python"), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        text=True).strip())
    (purelib / "_deps.pth").write_text(f"{visible}\n")
    return path / "bin" / "python"


def _install(python: Path, wheel: Path, extras: str = "") -> None:
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-index", "--no-cache-dir",
          "--find-links", str(wheel.parent), f"darboux{extras}"])


def _linked(tmp_path, keep) -> Path:
    """A directory of links to the entries of this environment's site-packages that
    ``keep(top-level name)`` selects; never darboux itself (its editable install)."""
    deps = tmp_path / "deps"
    deps.mkdir()
    for entry in SHARED.iterdir():
        top = entry.name.split("-")[0].split(".")[0].lower()
        if keep(top) and "darboux" not in entry.name.lower() and not entry.name.endswith(".pth"):
            (deps / entry.name).symlink_to(entry)
    return deps


def _read_only_home(tmp_path) -> dict:
    home = tmp_path / "home"
    home.write_text("not a directory: nothing can be written under ~")
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME", "PYTHONPATH")}
    return {**env, "HOME": str(home)}


def test_library_only_install_imports_without_gui(wheel, tmp_path):
    python = _venv(tmp_path / "lib-venv", _linked(tmp_path, lambda top: top in LIBRARY))
    _install(python, wheel)
    code = ("import sys, core, core.io, core.cli\n"
            "info = core.io.describe(sys.argv[1])\n"
            f"bad = sorted({{m.split('.')[0] for m in sys.modules}} & {GUI!r})\n"
            "assert not bad, bad\n"
            "assert core.__file__.startswith(sys.prefix), core.__file__\n"
            "print(info['n_points'])\n")
    bunny = ROOT / "resources" / "bunny.ply"
    proc = _run([str(python), "-c", code, str(bunny)], cwd=tmp_path, env=_read_only_home(tmp_path))
    assert proc.stdout.strip() == "28088"
    cli = _run([str(python.parent / "darboux-cli"), "--version"], cwd=tmp_path, env=_read_only_home(tmp_path))
    assert cli.stdout.startswith("darboux-cli ")


def test_viewer_install_shows_its_own_bunny(wheel, tmp_path):
    python = _venv(tmp_path / "app-venv", _linked(tmp_path, lambda top: True))
    _install(python, wheel, "[viewer,las]")
    env = _read_only_home(tmp_path)
    where = _run([str(python), "-c", "import app; print(app.DEFAULT_CLOUD)"], cwd=tmp_path, env=env)
    assert where.stdout.strip().startswith(str(tmp_path / "app-venv")), where.stdout
    shot = tmp_path / "shot.png"
    cmd = [str(python.parent / "darboux"), "--screenshot", str(shot), "--k", "15", "--timeout", "600"]
    if not env.get("DISPLAY"):
        cmd = ["xvfb-run", "-a", *cmd]
    _run(cmd, cwd=tmp_path, env=env)
    assert shot.stat().st_size > 20_000
