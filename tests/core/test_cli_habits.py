"""darboux-cli habits: --version, several files and globs, - for stdin/stdout, info --json,
Ctrl-C, early refusal of outputs, one line for every failure, option values."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import core
from cli_testutils import one_line_error
from core import cli


@pytest.fixture(scope="module")
def clouds(tmp_path_factory):
    d = tmp_path_factory.mktemp("clis")
    for name, radius in (("a", 1.0), ("b", 2.0)):
        np.savetxt(d / f"{name}.xyz", core.shapes.sphere(300, radius=radius, seed=1).points)
    return d


def test_version(capsys):
    with pytest.raises(SystemExit) as info:
        cli.main(["--version"])
    assert info.value.code == 0 and capsys.readouterr().out.strip() == f"darboux-cli {core.__version__}"


def test_glob_and_directory_output(clouds, tmp_path, capsys):
    assert cli.main(["estimate", str(clouds / "*.xyz"), "-o", str(tmp_path), "--k", "15", "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_darboux.ply", "b_darboux.ply"]
    b = core.io.read_cloud(tmp_path / "b_darboux.ply")
    assert abs(np.median(b.fields["mean"]) - 0.5) < 0.05


def test_several_files_with_stem_pattern(clouds, tmp_path):
    pattern = str(tmp_path / "{stem}_curv.csv")
    assert cli.main(["estimate", str(clouds / "a.xyz"), str(clouds / "b.xyz"), "-o", pattern, "--k", "15", "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_curv.csv", "b_curv.csv"]


def test_several_files_need_directory_or_pattern(clouds, tmp_path, capsys):
    code = cli.main(["estimate", str(clouds / "a.xyz"), str(clouds / "b.xyz"), "-o", str(tmp_path / "x.csv")])
    assert code == 2
    one_line_error(capsys, "directory or a pattern with {stem}")


def test_unmatched_glob_refused(clouds, capsys):
    assert cli.main(["info", str(clouds / "*.nothing")]) == 2
    one_line_error(capsys, "no file matches")


def test_unsupported_output_refused_before_estimate(clouds, tmp_path, capsys, monkeypatch):
    def never(*args, **kwargs):
        raise AssertionError("the estimate ran")

    monkeypatch.setattr(core, "estimate", never)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "out.vtk")]) == 2
    one_line_error(capsys, "unknown file extension '.vtk' for writing")
    assert list(tmp_path.iterdir()) == []


def _run(args, stdin=None, **kwargs):
    env = {**os.environ, "PYTHONPATH": os.getcwd()}
    return subprocess.run([sys.executable, "-m", "core", *args], input=stdin, capture_output=True, env=env,
                          timeout=120, **kwargs)


def test_stdin_to_stdout(clouds):
    proc = _run(["estimate", "-", "-o", "-", "--k", "15"], stdin=(clouds / "b.xyz").read_bytes())
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.decode().splitlines()
    assert lines[0].startswith("x,y,z,nx,ny,nz,k1,k2") and len(lines) == 301
    assert b"wrote standard output" in proc.stderr  # the summary keeps out of the data
    table = np.genfromtxt(lines, delimiter=",", names=True)
    assert abs(np.median(table["mean"]) - 0.5) < 0.05


def test_info_json(clouds, capsys):
    assert cli.main(["info", "--json", str(clouds / "a.xyz"), str(clouds / "b.xyz")]) == 0
    records = json.loads(capsys.readouterr().out)
    assert [r["n_points"] for r in records] == [300, 300] and records[1]["format"] == "xyz"


def _sigint_default():
    """In the child: Ctrl-C's default action, which Python turns into KeyboardInterrupt. A
    shell starts background jobs (``pytest &``, ``nohup``) with SIGINT ignored, the child
    inherits that, and Python then leaves it ignored: the test would fail for the shell."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_ctrl_c_exits_130_without_traceback(tmp_path):
    # noisy, so the estimate runs for seconds after its bar is up (a clean 30k cloud had
    # finished before the signal arrived on a loaded machine)
    big = core.noise.add_noise(core.shapes.torus(100_000, seed=0).points, 0.3, seed=1)
    np.savetxt(tmp_path / "big.xyz", big, fmt="%.6f")
    env = {**os.environ, "PYTHONPATH": os.getcwd()}
    proc = subprocess.Popen([sys.executable, "-m", "core", "estimate", str(tmp_path / "big.xyz"), "-o",
                             str(tmp_path / "o.ply"), "--progress"], stderr=subprocess.PIPE, env=env,
                            preexec_fn=_sigint_default)
    try:
        seen = b""
        while b"%" not in seen:  # the progress bar is up: the estimate is running
            chunk = proc.stderr.read1(256)
            assert chunk, "the process ended before its progress bar"
            seen += chunk
        proc.send_signal(signal.SIGINT)
        err = seen + proc.communicate(timeout=60)[1]
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert b"Traceback" not in err and b"interrupted" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.xyz"]


@pytest.mark.parametrize("exc, code, part", [
    (MemoryError(), 1, "out of memory"),
    (ValueError("points are bad"), 2, "points are bad"),
])
def test_failures_are_one_line(clouds, tmp_path, capsys, monkeypatch, exc, code, part):
    def fail(*args, **kwargs):
        raise exc

    monkeypatch.setattr(core, "estimate", fail)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply")]) == code
    one_line_error(capsys, part)


def test_numba_and_lazrs_errors_are_one_line(clouds, tmp_path, capsys, monkeypatch):
    from numba.core.errors import TypingError

    def fail(*args, **kwargs):
        raise TypingError("Failed in nopython mode pipeline (step: nopython frontend)\nmany more lines")

    monkeypatch.setattr(core, "estimate", fail)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply")]) == 1
    one_line_error(capsys, "compiled kernel failed (TypingError)", "nopython")
    lazrs_error = type("LazrsError", (RuntimeError,), {"__module__": "lazrs"})
    monkeypatch.setattr(core.io, "read_cloud", lambda *a, **k: (_ for _ in ()).throw(lazrs_error("bad chunk")))
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply")]) == 1
    one_line_error(capsys, "LAZ decompression failed: bad chunk")


def test_other_exceptions_keep_their_traceback(clouds, tmp_path, monkeypatch):
    monkeypatch.setattr(core, "estimate", lambda *a, **k: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply")])


@pytest.mark.parametrize("text, value", [("robust=None", None), ("robust=none", None), ("degree=2", 2),
                                         ("robust=tukey", "tukey"), ("x=0.5", 0.5), ("x=true", True)])
def test_option_values(text, value):
    assert cli._parse_option(text) == (text.split("=")[0], value)


def test_robust_none_turns_robust_off(clouds, tmp_path, monkeypatch):
    seen = {}
    real = core.estimate

    def spy(*args, **kwargs):
        res = real(*args, **kwargs)
        seen.update(res.params["options"])
        return res

    monkeypatch.setattr(core, "estimate", spy)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply"), "--option", "robust=None",
                     "-q"]) == 0
    assert "robust" in seen and seen["robust"] is None


def test_parser_has_an_execution_group():
    parser = cli.build_parser()
    estimate = parser._subparsers._group_actions[0].choices["estimate"]
    assert any(g.title == "execution" for g in estimate._action_groups)


def test_warmup_runs_every_method(capsys):
    assert cli.main(["warmup"]) == 0
    assert "compiled" in capsys.readouterr().out
