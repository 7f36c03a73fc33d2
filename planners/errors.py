"""Errors raised by the planners for bad input.

Bad input raises :class:`ProfileError` (a ``ValueError``) whose message follows the
project format ``"<Owner>.<field> must be <constraint> [unit]; got <value>."``.
Valid input without a legal footstep is *not* an error: the plan's status says so.
"""

from __future__ import annotations

__all__ = ["ProfileError", "invalid"]


class ProfileError(ValueError):
    """Bad planner input (profile, leg, speed or configuration)."""


def invalid(owner: str, field: str, constraint: str, value: object) -> ProfileError:
    """Build a :class:`ProfileError` in the project's message format.

    Parameters
    ----------
    owner, field : str
        Class (or function) and field that received the bad value.
    constraint : str
        What the value must be, with its unit, e.g. ``"finite and > 0 [m]"``.
    value : object
        The offending value (shown with ``repr``; long arrays are summarised).
    """
    text = repr(value)
    if len(text) > 80:
        text = text[:77] + "..."
    return ProfileError(f"{owner}.{field} must be {constraint}; got {text}.")
