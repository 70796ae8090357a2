"""No output of ``darboux-cli estimate`` (or of ``estimate_tiled``) may replace an input:
not by its name, nor through a symlink or a hard link, on every route (in memory, the
whole cloud into LAS/LAZ at k="auto", tiles)."""

from __future__ import annotations

import hashlib
import os

import numpy as np
import pytest

import core
from core.cli import main
from core.io.atomic import refuse_input_as_output
from core.tiled.run import estimate_tiled

laspy = pytest.importorskip("laspy")

REFUSED = "is the input file; choose another name"


def _write_scan(path):
    """A small LAS/LAZ scan with attributes an overwrite would lose (RGB, intensity)."""
    pts = core.shapes.sphere(600, seed=1).points + [500000.5, 4200000.5, 300.0]
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-3), np.floor(pts.min(axis=0))
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.red = np.full(len(pts), 50000, np.uint16)
    las.intensity = np.arange(len(pts), dtype=np.uint16)
    las.write(str(path))
    return path


def _digest(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def _routes(tmp_path, ext):
    """(input given, output given, the file that must stay): plain name, output a symlink to
    the input, input a symlink to the output, output a hard link to the input."""
    scan = _write_scan(tmp_path / f"scan.{ext}")
    (tmp_path / f"out_link.{ext}").symlink_to(scan.name)
    (tmp_path / f"in_link.{ext}").symlink_to(scan.name)
    os.link(scan, tmp_path / f"hard.{ext}")
    return scan, [(scan, scan), (scan, tmp_path / f"out_link.{ext}"), (tmp_path / f"in_link.{ext}", scan),
                  (scan, tmp_path / f"hard.{ext}"), (tmp_path / f"hard.{ext}", scan)]


@pytest.mark.parametrize("ext", ["las", "laz"])
@pytest.mark.parametrize("k", [None, "15"])
def test_las_output_onto_the_input_is_refused(tmp_path, capsys, ext, k):
    scan, routes = _routes(tmp_path, ext)
    before = _digest(scan)
    extra = [] if k is None else ["--k", k]  # None: the default k="auto" (the whole cloud into LAS)
    for src, dst in routes:
        assert main(["estimate", str(src), "-o", str(dst), "-q", *extra]) == 2, (src, dst)
        assert REFUSED in capsys.readouterr().err
        assert _digest(scan) == before and os.path.islink(tmp_path / f"out_link.{ext}")
    assert laspy.read(scan).red[0] == 50000  # the attributes are still there


@pytest.mark.parametrize("tiles", [["--workers", "0"], ["--tile-points", "200"]])
def test_tiled_route_refuses_links_too(tmp_path, capsys, tiles):
    scan, routes = _routes(tmp_path, "laz")
    before = _digest(scan)
    for src, dst in routes:
        assert main(["estimate", str(src), "-o", str(dst), "-q", "--k", "15", *tiles]) == 2
        assert REFUSED in capsys.readouterr().err
    assert _digest(scan) == before
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tiles")]  # refused before any work


def test_other_outputs_onto_an_input_are_refused(tmp_path, capsys):
    core.io.write_cloud(tmp_path / "a.ply", core.shapes.sphere(300, seed=0).points)
    core.io.write_cloud(tmp_path / "b.ply", core.shapes.sphere(300, seed=1).points)
    os.link(tmp_path / "a.ply", tmp_path / "a_hard.ply")
    (tmp_path / "b_link.csv").symlink_to("b.ply")
    (tmp_path / "a_x.ply").symlink_to("b.ply")  # a's output with -o {stem}_x.ply is input b
    before = {name: _digest(tmp_path / name) for name in ("a.ply", "b.ply")}
    a, b = str(tmp_path / "a.ply"), str(tmp_path / "b.ply")
    for args in ([a, "-o", str(tmp_path / "a_hard.ply")], [b, "-o", str(tmp_path / "b_link.csv")],
                 [a, b, "-o", str(tmp_path / "{stem}_x.ply")], [a, b, "-o", str(tmp_path / "{stem}.ply")]):
        assert main(["estimate", *args, "--k", "15", "-q"]) == 2, args
        assert REFUSED in capsys.readouterr().err
    assert {name: _digest(tmp_path / name) for name in before} == before


def test_estimate_tiled_refuses_a_link_to_its_input(tmp_path):
    scan = _write_scan(tmp_path / "scan.laz")
    os.link(scan, tmp_path / "hard.laz")
    (tmp_path / "soft.laz").symlink_to("scan.laz")
    before = _digest(scan)
    for out in (scan, tmp_path / "hard.laz", tmp_path / "soft.laz"):
        with pytest.raises(ValueError, match=REFUSED):
            estimate_tiled(scan, out, k=15, workers=0)
    assert _digest(scan) == before


def test_the_check_itself(tmp_path):
    a = tmp_path / "a.ply"
    a.write_bytes(b"x")
    (tmp_path / "dangling.ply").symlink_to("nowhere.ply")
    refuse_input_as_output([a, "-"], tmp_path / "new.ply")  # a new file: fine
    refuse_input_as_output([a], tmp_path / "dangling.ply")  # points at no input
    refuse_input_as_output([np.zeros((3, 3))], a)  # arrays and stdin are no files
    refuse_input_as_output([a], "-")
    with pytest.raises(ValueError, match=REFUSED):
        refuse_input_as_output(["-", str(a)], str(tmp_path / "." / "a.ply"))
