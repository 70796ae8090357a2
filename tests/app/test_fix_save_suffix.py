"""A screenshot or an export named without a suffix gets the default one of its format (as
Qt applications do) instead of failing with "Could not write the screenshot"."""

from __future__ import annotations


def test_a_name_without_suffix_gets_the_default_one(make_window, tmp_path):
    from app.source import make_shape

    window = make_window(make_shape("torus", 1500), k_auto=False, k=12)
    assert window.save_screenshot(tmp_path / "s_noext")
    assert (tmp_path / "s_noext.png").stat().st_size > 1000
    assert window.export_result(tmp_path / "noext") == tmp_path / "noext.ply"
    assert (tmp_path / "noext.ply").exists()
    assert window.export_result(tmp_path / "table", ".csv") == tmp_path / "table.csv"  # the dialog's filter
    assert not [n.message for n in window.notifier.history if n.level == "error"]


def test_the_suffix_helpers():
    from app.actions import filter_suffix, with_default_suffix, write_filter

    csv = [f for f in write_filter().split(";;") if "*.csv" in f][0]
    assert filter_suffix(csv, ".ply") == ".csv" and filter_suffix("", ".png") == ".png"
    assert with_default_suffix("/x/a.jpg", ".png").name == "a.jpg"  # a suffix given is kept
    assert with_default_suffix("/x/a", ".png").name == "a.png"
    assert with_default_suffix("/", ".png").name == ""  # a directory is not renamed (its error names it)
