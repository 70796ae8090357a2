"""The XML of a VTK XML file, parsed as VTK parses it (expat), for the checks made before VTK
reads it (:mod:`core.io.vtp_sizes`, :mod:`core.io.vtp_blocks`): quotes of either kind, spaces
around '=', character references and comments are read as VTK reads them, where byte
patterns saw only one spelling (``NumberOfPoints='1000000000000'`` aborted the process)."""

from __future__ import annotations

from xml.parsers import expat

from .cloud import CloudFileError

_CHUNK = 1 << 20  # bytes of XML given to expat at a time
_MAX_MARKUP = 1 << 24  # a longer tag is refused: VTK writes none, and expat 2.5 rescans it per chunk
#: elements nested deeper are refused (VTK's files nest fewer than 10; 200,000 crashed VTK's parser)
MAX_DEPTH = 1000
#: attributes an element may have (VTK writes fewer than 10; it reads n of them in n**2 time)
MAX_ATTRIBUTES = 1000


def scan_xml(data, handler, path) -> None:
    """Give expat the XML before the first '<AppendedData' (where VTK stops parsing), a chunk at
    a time, calling ``handler.start(name, attributes, position)`` at each start tag (the byte
    of its '<' in ``data``) and ``handler.end(name)``, if it has one, at each end tag. A
    document type is refused (its entities could spell what is checked), so are elements nested
    more than :data:`MAX_DEPTH` deep; at a syntax error
    parsing stops quietly (VTK's parser stops there too, and names the error)."""
    end = data.find(b"<AppendedData")
    end = len(data) if end < 0 else end
    parser = expat.ParserCreate()
    skipped = [0]  # bytes of long comments not given to expat (:func:`_resume`), before the current chunk
    depth = [0]

    def on_start(name, attrs):
        depth[0] += 1
        if depth[0] > MAX_DEPTH:  # VTK's parser recursed into each: 200,000 levels overflowed its stack
            _refuse(path, f"its XML nests elements more than {MAX_DEPTH} deep (<{name}> at byte "
                          f"{parser.CurrentByteIndex + skipped[0]}); allowed: at most {MAX_DEPTH}")
        if len(attrs) > MAX_ATTRIBUTES:  # VTK stores each after a search of those before: 300,000 took minutes
            _refuse(path, f"its XML gives <{name}> (at byte {parser.CurrentByteIndex + skipped[0]}) {len(attrs)} "
                          f"attributes; allowed: at most {MAX_ATTRIBUTES}")
        handler.start(name, attrs, parser.CurrentByteIndex + skipped[0])

    def on_end(name):
        depth[0] -= 1
        if hasattr(handler, "end"):
            handler.end(name)

    parser.StartElementHandler, parser.EndElementHandler = on_start, on_end
    parser.StartDoctypeDeclHandler = lambda *_: _refuse(path, "its XML has a document type (<!DOCTYPE>); allowed: none")
    pos = 0
    with memoryview(data) as view:
        try:
            while pos < end:
                stop = min(pos + _CHUNK, end)
                parser.Parse(view[pos:stop], False)
                token = parser.CurrentByteIndex  # where the markup expat waits to complete starts
                pos = stop if token < 0 else _resume(data, token + skipped[0], stop, end, path)
                skipped[0] += pos - stop
        except expat.ExpatError:
            return


def _resume(data, token: int, stop: int, end: int, path) -> int:
    """Where to go on after giving expat the bytes up to ``stop``, ``token`` being where the
    markup it waits to complete starts. expat 2.5 scans an open token again with every chunk
    (quadratic): the rest of a long comment is skipped (up to its '--', which expat then
    checks), and a longer tag than ``_MAX_MARKUP`` is refused."""
    if stop - token <= _CHUNK or stop == end:
        return stop
    if data[token : token + 4] == b"<!--":
        close = data.find(b"--", token + 4, end)
        return max(stop, end if close < 0 else close)
    if stop - token > _MAX_MARKUP:
        _refuse(path, f"its XML has a tag (or other markup but a comment) of more than {_MAX_MARKUP} bytes at "
                      f"byte {token}; allowed: at most {_MAX_MARKUP}")
    return stop


def _refuse(path, problem: str):
    raise CloudFileError(path, problem)
