"""What a file's first bytes say it is: for the message of a read that failed because the
file is compressed or its extension names another format than its content."""

from __future__ import annotations

import codecs
import re

from .cloud import CloudFileError

#: the UTF-8 byte-order mark (EF BB BF), which a text editor may put before a text file's
#: first line: the readers of text formats skip it (the legacy VTK reader refuses it by name)
UTF8_BOM = codecs.BOM_UTF8
#: leading bytes -> the compression that writes them
_COMPRESSED = {b"\x1f\x8b": "gzip", b"PK\x03\x04": "zip", b"BZh": "bzip2", b"\xfd7zXZ\x00": "xz",
               b"(\xb5/\xfd": "zstd", b"7z\xbc\xaf\x27\x1c": "7z"}
#: (pattern on the first bytes, format names it may be read as, the extension to suggest)
_CONTENT = (
    (re.compile(rb"ply\r?\n"), ("ply",), "ply"),
    (re.compile(rb"LASF"), ("las", "laz"), "las"),
    (re.compile(rb"ASTM-E57"), ("e57",), "e57"),
    (re.compile(rb"# vtk DataFile"), ("vtk",), "vtk"),
    (re.compile(b"(" + re.escape(UTF8_BOM) + rb")?\s*(<\?xml[^>]*>\s*)?<VTKFile"), ("vtp", "vtk"), "vtp"),
    (re.compile(rb"(#[^\n]*\n)*\s*VERSION[ \t]+\.?\d[^\n]*\n(\s*#[^\n]*\n)*\s*FIELDS\s"), ("pcd",), "pcd"),  # not "VERSION 2" alone
    (re.compile(rb"(#[^\n]*\n)*\s*(ST)?C?N?4?n?OFF(\s|\d)"), ("off",), "off"),
)


def content_hint(path, fmt: str) -> str:
    """"it is a gzip-compressed file: ..." or "its content is a .ply file, not .xyz: ...", or ""
    when the first bytes name no other format than ``fmt`` (or cannot be read)."""
    try:
        with open(path, "rb") as f:
            head = f.read(1024)
    except OSError:
        return ""
    for magic, kind in _COMPRESSED.items():
        if head.startswith(magic):
            return f"it is a {kind}-compressed file: decompress it first and read the file inside"
    for pattern, formats, ext in _CONTENT:
        if fmt not in formats and pattern.match(head):
            return f"its content is a .{ext} file, not .{fmt}: rename it to .{ext}"
    return ""


def refuse_other_content(path, fmt: str) -> None:
    """Refuse, before reading, a compressed file or one whose first bytes are another format's
    (a PLY, LAS, E57, VTK, PCD or OFF header) named as ``fmt``: the delimited text reader took
    an ASCII PLY's or an OFF's header for a names line and read on, the normals of
    ``nx ny nz x y z`` as the points, an OFF's counts line as a point."""
    hint = content_hint(path, fmt)
    if hint:
        raise CloudFileError(path, hint)


#: byte-order marks of the UTF-16 and UTF-32 encodings (UTF-32 first: FF FE begins both)
_WIDE_BOMS = ((b"\xff\xfe\x00\x00", "utf-32"), (b"\x00\x00\xfe\xff", "utf-32"), (b"\xff\xfe", "utf-16"),
              (b"\xfe\xff", "utf-16"))
#: the formats whose readers take text only in ASCII or UTF-8 (the delimited text reader
#: decodes UTF-16 and UTF-32 itself; LAS, LAZ and E57 are binary)
_NARROW = ("ply", "pcd", "obj", "off", "vtk", "vtp", "ptx")  # not STL: a binary header may begin FF FE
#: the formats whose readers split lines at LF only (PLY, OBJ, STL and delimited text take CR too)
_LF_LINES = ("off", "pcd", "vtk", "ptx")


def refuse_misread_text(path, fmt: str) -> None:
    """Refuse a file of a text format in UTF-16 or UTF-32 (a PowerShell redirect writes
    UTF-16), whose reader found no points or named its first bytes as garbage; a legacy
    VTK file behind a UTF-8 byte-order mark, which VTK's reader calls an unrecognized file
    type; and an OFF, PCD, VTK or PTX file whose lines end in CR alone (classic Mac OS),
    which their readers took for one line ("truncated", "premature EOF")."""
    if fmt not in _NARROW:
        return
    with open(path, "rb") as f:
        head = f.read(4096)
    kind = wide_encoding(head)
    if kind is not None:
        raise CloudFileError(path, f"is {kind.upper()} text (a PowerShell redirect writes it so); .{fmt} files are read as "
                                   "ASCII or UTF-8: save it as UTF-8 (or ASCII) text")
    if fmt in _LF_LINES and _cr_lines(head):
        raise CloudFileError(path, "has lines ending in CR alone (classic Mac OS); convert them to LF or CR LF line "
                                   "endings (e.g. with dos2unix -c mac)")
    if fmt == "vtk" and head.startswith(UTF8_BOM):
        raise CloudFileError(path, "starts with a UTF-8 byte-order mark (a text editor's), which VTK's legacy reader "
                                   "does not take; save it without one")


def wide_encoding(head: bytes) -> str | None:
    """"utf-32" or "utf-16" where ``head`` begins with that encoding's byte-order mark, else None."""
    return next((name for bom, name in _WIDE_BOMS if head.startswith(bom)), None)


def _cr_lines(head: bytes) -> bool:
    """Whether the first line break in ``head`` is a CR without an LF after it."""
    at = re.search(rb"[\r\n]", head)
    return at is not None and head[at.start() : at.start() + 2] not in (b"\r\n", b"\n") and \
        not head[at.start() :].startswith(b"\n")
