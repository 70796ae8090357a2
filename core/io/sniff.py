"""What a file's first bytes say it is: for the message of a read that failed because the
file is compressed or its extension names another format than its content."""

from __future__ import annotations

import re

#: leading bytes -> the compression that writes them
_COMPRESSED = {b"\x1f\x8b": "gzip", b"PK\x03\x04": "zip", b"BZh": "bzip2", b"\xfd7zXZ\x00": "xz",
               b"(\xb5/\xfd": "zstd", b"7z\xbc\xaf\x27\x1c": "7z"}
#: (pattern on the first bytes, format names it may be read as, the extension to suggest)
_CONTENT = (
    (re.compile(rb"ply\r?\n"), ("ply",), "ply"),
    (re.compile(rb"LASF"), ("las", "laz"), "las"),
    (re.compile(rb"ASTM-E57"), ("e57",), "e57"),
    (re.compile(rb"# vtk DataFile"), ("vtk",), "vtk"),
    (re.compile(rb"(\xef\xbb\xbf)?\s*(<\?xml[^>]*>\s*)?<VTKFile"), ("vtp", "vtk"), "vtp"),
    (re.compile(rb"(#[^\n]*\n)*\s*VERSION\s+\.?\d"), ("pcd",), "pcd"),
    (re.compile(rb"(#[^\n]*\n)*\s*(ST)?C?N?4?n?OFF(\s|\d)"), ("off",), "off"),
)


def content_hint(path, fmt: str) -> str:
    """"; it is a gzip-compressed file: ..." or "; its content is a PLY file: ...", or ""
    when the first bytes name no other format than ``fmt`` (or cannot be read)."""
    try:
        with open(path, "rb") as f:
            head = f.read(1024)
    except OSError:
        return ""
    for magic, kind in _COMPRESSED.items():
        if head.startswith(magic):
            return f"; it is a {kind}-compressed file: decompress it first and read the file inside"
    for pattern, formats, ext in _CONTENT:
        if fmt not in formats and pattern.match(head):
            return f"; its content is a .{ext} file, not .{fmt}: rename it to .{ext}"
    return ""
