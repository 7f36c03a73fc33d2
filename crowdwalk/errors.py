"""Errors a person can act on.

Bad input raises :class:`InputError` (a ``ValueError``) whose message names the owner,
the field, the constraint and the value. Valid input that has no solution raises
:class:`InfeasibleError` or is reported as a status.
"""

from __future__ import annotations

import errno
from pathlib import Path

__all__ = ["InputError", "InfeasibleError", "invalid", "existing_file"]


class InputError(ValueError):
    """Bad input: ``"<Owner>.<field> must be <constraint> [unit]; got <value>."``"""


class InfeasibleError(RuntimeError):
    """Valid input with no solution (no route, no legal foothold)."""


def invalid(owner: str, field: str, constraint: str, value: object) -> InputError:
    """Build an :class:`InputError` in the project's message format."""
    return InputError(f"{owner}.{field} must be {constraint}; got {value!r}.")


def existing_file(path) -> Path:
    """``path`` as a :class:`~pathlib.Path`; ``FileNotFoundError`` naming it if absent."""
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(errno.ENOENT, "No such file", str(path))
    return path
