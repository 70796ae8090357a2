"""The Teach mode's command-line flags (``darboux --teach --pick N --theta 30 ...``)."""

from __future__ import annotations

from .examples import EXAMPLES, OVERLAYS

__all__ = ["add_arguments", "settings_from_args"]


def add_arguments(p) -> None:
    """Add --teach, --overlays, --theta, --focus and --example to an argparse parser."""
    p.add_argument("--teach", action="store_true", help="open the Teach panel (frame, sections, Dupin, Euler plot)")
    p.add_argument("--overlays", metavar="LIST", help="with --teach: comma-separated overlays: "
                   f"{', '.join(OVERLAYS)} (default frame,sections,dupin)")
    p.add_argument("--theta", type=float, metavar="DEG", help="with --teach: direction of the swept normal section")
    p.add_argument("--focus", action="store_true", help="with --teach and --pick: zoom to the picked point")
    p.add_argument("--example", metavar="NAME",
                   help=f"a guided example (implies --teach): {', '.join(EXAMPLES)}")


def settings_from_args(args, parser) -> dict:
    """Keyword arguments for :meth:`app.teach.Teach.configure` (empty: teach mode off);
    bad values end in ``parser.error``."""
    if args.example is not None and args.example not in EXAMPLES:
        parser.error(f"--example {args.example!r} is unknown; valid: {', '.join(EXAMPLES)}")
    if not (args.teach or args.example):
        if args.overlays or args.theta is not None or args.focus:
            parser.error("--overlays, --theta and --focus need --teach")
        return {}
    out = {"enabled": True}
    if args.overlays:
        out["overlays"] = _overlays(args.overlays, parser)
    given = {"theta": args.theta, "focus": args.focus or None, "example": args.example}
    out.update({key: value for key, value in given.items() if value is not None})
    return out


def _overlays(text: str, parser) -> list[str]:
    names = [x.strip().lower() for x in text.split(",") if x.strip()]
    bad = [n for n in names if n not in OVERLAYS]
    if bad:
        parser.error(f"--overlays: {', '.join(bad)} unknown; valid: {', '.join(OVERLAYS)}")
    return names
