"""The progress bar and the render's cancel path (tracer/cpp/bindings.cpp): every 100 ms the
core's watching thread takes the GIL, checks for signals (Ctrl-C) and reports progress; an
exception from either cancels the render, and it is re-raised once the workers have stopped."""

from __future__ import annotations

import os
import signal
import sys
import threading

import pytest

import tracer
from tests.helpers import SCENES


def small(width=40, height=30, spp=1):
    scene = tracer.load_scene(SCENES / "ex25.toml")
    return scene.with_overrides(width=width, height=height, spp=spp)


def long_render():
    """Seconds of work on one thread (2000 x 1500 at 16 spp: about 2.5 s here), so the
    watcher polls many times before it ends; a cancelled render stops at the first poll."""
    return small(2000, 1500, spp=16)


def cpu_seconds() -> float:
    """CPU time of this process, all threads: the work done, whatever the machine's load."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def a_sixteenth_of_the_long_render() -> float:
    """The CPU time of a render with 1/16 of long_render's pixels, all of them done."""
    start = cpu_seconds()
    tracer.render_with_stats(small(500, 375, spp=16), threads=1, progress=False)
    return cpu_seconds() - start


def assert_cancelled_early(cpu: float) -> None:
    """Cancelled at the first poll, 100 ms of wall time into the render (so at most 0.1 s of
    one thread's work, less on a loaded machine): the work done must be well under the whole
    render's, 16 sixteenths. Measured in CPU time, work, not speed: load slows the clock but
    does not add work. The bound, 4 sixteenths, leaves room for a slow first tile."""
    sixteenth = a_sixteenth_of_the_long_render()
    assert cpu < 4 * sixteenth, f"{cpu:.2f} CPU s: not cancelled (1/16 render: {sixteenth:.2f})"


def test_progress_bar_shows_on_stderr_when_asked(capsys):
    image = tracer.render_with_stats(small(), threads=1, progress=True).image
    err = capsys.readouterr().err
    assert "render: 100%" in err  # the last report, made when the render is done
    assert (image == tracer.render(small(), threads=1, progress=False)).all()


def test_no_progress_bar_when_not_asked_or_not_a_terminal(capsys):
    tracer.render_with_stats(small(), threads=1, progress=False)
    tracer.render_with_stats(small(), threads=1)  # None: a bar only on a terminal
    assert capsys.readouterr().err == ""


class Stderr:
    """A stderr that records each write, and raises from the first one when ``fail`` is set
    (a terminal gone away): an exception from inside the progress callback."""

    class Gone(Exception):
        pass

    def __init__(self, fail: bool):
        self.fail = fail
        self.writes = 0
        self.first = threading.Event()

    def write(self, text: str) -> int:
        self.writes += 1
        self.first.set()
        if self.fail:
            raise self.Gone("stderr is gone")
        return len(text)

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return True


def test_an_exception_from_the_progress_callback_cancels_the_render(monkeypatch):
    """The bar's first write raises: the render stops and the exception comes out of
    render_with_stats, once the render has stopped early."""
    stderr = Stderr(fail=True)
    monkeypatch.setattr(sys, "stderr", stderr)
    scene, start = long_render(), cpu_seconds()
    with pytest.raises(Stderr.Gone):
        tracer.render_with_stats(scene, threads=1, progress=True)
    cpu = cpu_seconds() - start
    assert stderr.writes == 1
    assert_cancelled_early(cpu)


class Interrupted(Exception):
    pass


def test_ctrl_c_cancels_the_render_and_is_re_raised(monkeypatch):
    """SIGINT arrives while the core renders (sent from another thread once the bar has shown,
    so the watcher's PyErr_CheckSignals sees it, not Python code): the handler's exception comes
    out of the render, and the bar reports nothing after it."""

    def handler(signum, frame):
        raise Interrupted(signum)

    stderr = Stderr(fail=False)
    monkeypatch.setattr(sys, "stderr", stderr)

    def interrupt():
        stderr.first.wait(30)
        os.kill(os.getpid(), signal.SIGINT)

    previous = signal.signal(signal.SIGINT, handler)
    try:
        sender = threading.Thread(target=interrupt)
        sender.start()
        scene, start = long_render(), cpu_seconds()
        with pytest.raises(Interrupted):
            tracer.render_with_stats(scene, threads=1, progress=True)
        cpu = cpu_seconds() - start
        sender.join()
    finally:
        signal.signal(signal.SIGINT, previous)
    # The bar's first report, perhaps one more polled before the signal landed; never the
    # dozens of a render left to run to its end.
    assert 1 <= stderr.writes <= 2
    assert_cancelled_early(cpu)
