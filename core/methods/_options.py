"""Checking a method option's value: exact type and one of the allowed values."""

from __future__ import annotations

import numpy as np


def choose(name: str, value, allowed: tuple, allowed_text: str | None = None):
    """``value`` if it is one of ``allowed`` *and of the same type* (3.0, "3" and True
    are not the integer 3, None is not a string); otherwise a ValueError naming the
    option, the value and what is allowed (``allowed_text``, default "one of [...]")."""
    for choice in allowed:
        if _same_type(value, choice) and value == choice:
            return value
    raise ValueError(f"{name} {value!r} is invalid; must be {allowed_text or f'one of {list(allowed)}'}")


def _same_type(value, choice) -> bool:
    if choice is None or isinstance(choice, str):
        return type(value) is type(choice) or (isinstance(choice, str) and isinstance(value, str))
    if isinstance(choice, int):  # bool is an int subclass but never a degree
        return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    return isinstance(value, type(choice))
