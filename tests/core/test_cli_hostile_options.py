"""darboux-cli on hostile option values and tiny files: one line naming the problem, exit 2.

Found by a hostile-input sweep: --memory values that overflow, a file of 1 or 2 points, a
broken -o pattern, a {stem} pattern with one input, keywords typed in upper case.
"""

from __future__ import annotations

import pytest

import core
from cli_testutils import one_line_error
from core import cli
from core.tiled.run import MAX_MEMORY, parse_memory


@pytest.fixture(scope="module")
def clouds(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile")
    for name, seed in (("a", 1), ("b", 2)):
        core.io.write_cloud(d / f"{name}.ply", core.shapes.sphere(300, seed=seed).points)
    return d


def _tiny(path, n):
    """An ASCII PLY of ``n`` points."""
    rows = "".join(f"{i} {i * i} 0\n" for i in range(n))
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty double x\nproperty double y\n"
                    f"property double z\nend_header\n{rows}")
    return path


# 1. --memory that overflows to infinity, or is beyond any machine

@pytest.mark.parametrize("memory", ["1e400GB", "1e308GB", "1e400", "1e300"])
def test_memory_overflow_refused(clouds, tmp_path, capsys, memory):
    argv = ["estimate", str(clouds / "a.ply"), "-o", str(tmp_path / "o.ply"), "-q", "--memory", memory]
    assert cli.main(argv) == 2
    one_line_error(capsys, f"memory {memory!r} is invalid")
    assert not (tmp_path / "o.ply").exists()


@pytest.mark.parametrize("memory", ["1e400GB", "1e300", "inf"])
def test_memory_budget_refuses_like_inf(memory):
    with pytest.raises(ValueError, match=f"memory '{memory}' is invalid"):
        parse_memory(memory)


def test_memory_budget_takes_sizes():
    assert parse_memory("2GB") == 2_000_000_000
    assert parse_memory("9000PB") == 9 * 10**18
    assert parse_memory(MAX_MEMORY) == MAX_MEMORY


# 4. a file of 1 or 2 points: the error names the file

@pytest.mark.parametrize("n", [1, 2])
@pytest.mark.parametrize("ext", [".ply", ".las"])
def test_too_few_points_names_the_file(tmp_path, capsys, n, ext):
    src = _tiny(tmp_path / f"tiny{n}.ply", n)
    assert cli.main(["estimate", str(src), "-o", str(tmp_path / f"out{ext}"), "-q"]) == 2
    one_line_error(capsys, str(src), f"has {n} point", "at least 3")


# 5. a -o pattern str.format cannot fill: the error names -o and the pattern

@pytest.mark.parametrize("pattern", ["{stem}{.ply", "{stem}_{name}.ply", "{stem}_{}.ply", "{stem}}.ply"])
@pytest.mark.parametrize("n_inputs", [1, 2])
def test_bad_output_pattern_names_the_option(clouds, tmp_path, capsys, pattern, n_inputs):
    inputs = [str(clouds / "a.ply"), str(clouds / "b.ply")][:n_inputs]
    output = str(tmp_path / pattern)
    assert cli.main(["estimate", *inputs, "-o", output, "-q"]) == 2
    one_line_error(capsys, f"-o {output!r}", "not a valid output pattern")
    assert list(tmp_path.iterdir()) == []


# 6. {stem} is filled for one input as for several

@pytest.mark.parametrize("how", ["file", "glob"])
def test_stem_pattern_filled_for_one_input(clouds, tmp_path, how):
    src = clouds / "a.ply" if how == "file" else clouds / "a*.ply"
    assert cli.main(["estimate", str(src), "-o", str(tmp_path / "{stem}_k.ply"), "--k", "15", "-q"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["a_k.ply"]
    assert len(core.io.read_cloud(tmp_path / "a_k.ply")) == 300


def test_name_without_stem_kept_for_one_input(clouds, tmp_path):
    assert cli.main(["estimate", str(clouds / "a.ply"), "-o", str(tmp_path / "plain.ply"), "--k", "15", "-q"]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["plain.ply"]


# 7. keywords in any case, as the Python API takes them

@pytest.mark.parametrize("k, method, orientation", [("AUTO", "NR", "Outward"), ("Auto", "Nf", "KEEP"),
                                                     (" auto ", "nr", "auto")])
def test_keywords_any_case(k, method, orientation):
    args = cli.build_parser().parse_args(["estimate", "a.ply", "-o", "o.ply", "--k", k, "--method", method,
                                          "--orientation", orientation])
    assert (args.k, args.method, args.orientation) == ("auto", method.lower(), orientation.lower())


def test_upper_case_keywords_estimate(clouds, tmp_path):
    out = tmp_path / "o.ply"
    assert cli.main(["estimate", str(clouds / "a.ply"), "-o", str(out), "--k", "AUTO", "--method", "NR", "-q"]) == 0
    assert len(core.io.read_cloud(out)) == 300


def test_unknown_method_still_refused(capsys):
    with pytest.raises(SystemExit) as info:
        cli.build_parser().parse_args(["estimate", "a.ply", "-o", "o.ply", "--method", "NX"])
    assert info.value.code == 2 and "invalid choice: 'nx'" in capsys.readouterr().err


def test_stdin_with_too_few_points_named_stdin(tmp_path, capsys, monkeypatch):
    import io
    import sys

    monkeypatch.setattr(sys, "stdin", type("In", (), {"buffer": io.BytesIO(b"0 0 0\n1 0 0\n")})())
    assert cli.main(["estimate", "-", "-o", str(tmp_path / "o.ply"), "-q"]) == 2
    one_line_error(capsys, "stdin: has 2 points")
    assert list(tmp_path.iterdir()) == []
