"""SIGINT and SIGTERM as an exception, Interrupted, for the CLI's verbs (tracer/cli.py main()).

The handler raises Interrupted once, wherever the main thread is. Where that is inside a
``__del__`` or a weakref finaliser (a subprocess or a temporary directory being collected),
Python prints "Exception ignored" and goes on: the interrupt would be lost, and a batch would
run to its end and exit 0. So the signal is also remembered: a batch checks it between tasks
(``raise_if_interrupted()``, tracer/batch.py), ``rtlab bench`` before each timed run
(reference/bench.py), ``rtlab report`` before each scene (reports/lesson.py), ``rtlab view``
four times a second (tracer/viewer/server.py), and main() checks it at the end."""

from __future__ import annotations

import signal
import threading


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM. Raised by the signal handler, so it travels the path of Ctrl-C: the
    core's watching thread checks for signals every 100 ms (tracer/cpp/bindings.cpp), cancels
    the render and re-raises it; every atomic write on the way unwinds (tracer/image.py); a
    reference renderer's child process is killed by subprocess.run."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


_signum: int | None = None  # the first signal since install(), None before one


def _on_signal(signum: int, frame: object) -> None:
    global _signum
    if _signum is not None:  # a second signal while the first unwinds: let the clean-up finish
        return
    _signum = signum
    raise Interrupted(signum)


def install() -> dict[int, object]:
    """From now on SIGINT and SIGTERM raise Interrupted; returns the handlers they had, for
    restore(). (Python delivers signals to the main thread only: elsewhere, nothing.)"""
    global _signum
    _signum = None
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {s: signal.signal(s, _on_signal) for s in (signal.SIGINT, signal.SIGTERM)}


def restore(previous: dict[int, object]) -> None:
    """The handlers install() replaced put back, and the signal forgotten: a library call after
    the verb (a test's, a notebook's) is not interrupted by it."""
    handled()
    for s, handler in previous.items():
        signal.signal(s, handler)  # type: ignore[arg-type]


def handled() -> None:
    """The signal received is the way the verb ends (rtlab view stops on Ctrl-C): forgotten, so
    that main() does not raise it again."""
    global _signum
    _signum = None


def raise_if_interrupted() -> None:
    """Raise Interrupted again if a signal came since install() (its first raising may have
    been swallowed: see the module's text)."""
    if _signum is not None:
        raise Interrupted(_signum)
