"""Ctrl-C and SIGTERM end a run between two ticks, never inside a library callback.

Python raises ``KeyboardInterrupt`` wherever the main thread happens to be; inside a
finaliser or a C callback the exception is printed and dropped, and the run goes on.
Within :func:`deferred`, the signal only records a request; :func:`check` (called once per
tick) raises it at a safe point. A second signal raises at once.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["check", "deferred"]

_requested = False


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a stop was requested since :func:`deferred` began."""
    if _requested:
        raise KeyboardInterrupt


@contextmanager
def deferred() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM request a stop; the block ends by raising it."""
    global _requested
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def request(signum, frame):
        global _requested
        if _requested:
            raise KeyboardInterrupt
        _requested = True

    _requested = False
    previous = {s: signal.signal(s, request) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
        check()
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
        _requested = False
