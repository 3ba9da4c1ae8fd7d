"""The command line and image files: formats, atomic writes, errors, interruption."""

from __future__ import annotations

import argparse
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import tracer
from tests.helpers import SCENES
from tracer.cli import _duration, demo_scene_path, main
from tracer.image import linear_to_srgb

RTLAB = [sys.executable, "-m", "tracer.cli"]


def small_demo(tmp_path: Path, width: int = 32, height: int = 24) -> Path:
    text = demo_scene_path().read_text()
    text = text.replace("width = 640", f"width = {width}").replace(
        "height = 480", f"height = {height}"
    )
    path = tmp_path / "demo.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("suffix", [".exr", ".npy", ".png"])
def test_render_writes_each_format(tmp_path, suffix):
    scene = small_demo(tmp_path)
    out = tmp_path / f"img{suffix}"
    assert main(["render", str(scene), "-o", str(out), "--threads", "2", "--quiet"]) == 0
    direct = tracer.render(tracer.load_scene(scene), threads=1)
    back = tracer.load_image(out)
    assert back.shape == (24, 32, 3) and back.dtype == np.float32
    if suffix == ".png":
        # 8-bit sRGB: compare in the encoded domain, where rounding is half a step of 1/255.
        assert np.abs(linear_to_srgb(back) - linear_to_srgb(direct)).max() <= 0.5 / 255 + 1e-6
    else:
        assert np.array_equal(back, direct)  # float32 stored losslessly
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


# sRGB (IEC 61966-2-1): V = 12.92 L for L <= 0.0031308, else 1.055 L^(1/2.4) - 0.055. The bytes
# below were computed apart from tracer.image, with Python's decimal module at 40 digits from
# that formula as the standard writes it, then rounded to the nearest of 255 steps (255 V
# shown to 4 places). A plain 2.2 gamma gives the bytes in the last column: 0.5 -> 186,
# 0.18 -> 117, 0.0031308 -> 19, 0.001 -> 11; and 128 -> 0.2158605 is the value the sRGB
# literature tabulates for mid-grey code 128.
SRGB_BYTES = [  # linear value, 255 V, the byte; (plain 2.2 gamma's byte)
    (0.0, 0.0, 0),  # (0)
    (0.001, 3.2946, 3),  # (11) on the linear segment: 12.92 * 0.001 * 255
    (0.0031308, 10.3147, 10),  # (19) the segments' joint: 0.04045 * 255
    (0.05, 63.1891, 63),  # (65)
    (0.18, 117.6458, 118),  # (117) photographic mid-grey
    (0.5, 187.5160, 188),  # (186)
    (0.8, 231.1146, 231),  # (230)
    (1.0, 255.0, 255),  # (255)
]
SRGB_DECODED = [  # byte, its linear value (the same decimal computation, 10 digits)
    (1, 0.0003035270),
    (10, 0.0030352698),
    (64, 0.0512694584),
    (118, 0.1811642442),
    (128, 0.2158605001),
    (188, 0.5028864580),
    (255, 1.0),
]


def test_png_holds_the_srgb_bytes_of_the_standard(tmp_path):
    """The PNG's bytes themselves, read back with Pillow alone, not through our decoder (which a
    wrong encoder would mirror: a 2.2 gamma pair round-trips as well as sRGB does)."""
    from PIL import Image

    linear = np.array([[[v, v, v] for v, _, _ in SRGB_BYTES]], dtype=np.float32)
    out = tracer.save_image(tmp_path / "ramp.png", linear)
    with Image.open(out) as im:
        assert im.mode == "RGB"
        got = np.asarray(im)[0, :, 0].tolist()
    assert got == [byte for _, _, byte in SRGB_BYTES]


def test_png_bytes_decode_to_the_linear_values_of_the_standard(tmp_path):
    """An 8-bit PNG written by Pillow alone, decoded by load_image. Tolerance: the result is
    float32, one rounding of a value up to 1, 2^-24 relative ~ 6e-8; 1e-7 absolute holds it
    and is 3,000 times below the smallest gap to a 2.2 gamma's value here (3e-4, at byte 1)."""
    from PIL import Image

    row = np.array([[[b, b, b] for b, _ in SRGB_DECODED]], dtype=np.uint8)
    Image.fromarray(row, mode="RGB").save(tmp_path / "bytes.png")
    got = tracer.load_image(tmp_path / "bytes.png")[0, :, 1]
    assert got.tolist() == pytest.approx([v for _, v in SRGB_DECODED], abs=1e-7)


def test_exr_has_rgb_float_channels(tmp_path):
    import OpenEXR

    out = tmp_path / "a.exr"
    tracer.save_image(out, np.full((2, 3, 3), 0.25, dtype=np.float32))
    with OpenEXR.File(str(out), separate_channels=True) as f:
        channels = f.channels()
        assert sorted(channels) == ["B", "G", "R"]
        assert channels["R"].pixels.dtype == np.float32


def test_cli_overrides(tmp_path):
    out = tmp_path / "o.npy"
    code = main(
        [
            "render",
            str(small_demo(tmp_path)),
            "-o",
            str(out),
            "--width",
            "20",
            "--height",
            "10",
            "--spp",
            "4",
            "--threads",
            "1",
            "--quiet",
        ]
    )
    assert code == 0 and np.load(out).shape == (10, 20, 3)


SUMMARY = re.compile(
    r"(\d+)x(\d+), (\d+) spp, (\d+) threads: .* \((\d+) primary, (\d+) secondary, (\d+) shadow\)"
)


def render_cli(capsys, scene: Path, out: Path, *flags: str) -> tuple[np.ndarray, dict[str, int]]:
    """`rtlab render` through main(); the image written and the summary's numbers."""
    assert main(["render", str(scene), "-o", str(out), "--threads", "1", *flags]) == 0
    m = SUMMARY.search(capsys.readouterr().out)
    assert m, "no summary line"
    keys = ("width", "height", "spp", "threads", "primary", "secondary", "shadow")
    return np.load(out), dict(zip(keys, map(int, m.groups()), strict=True))


@pytest.mark.parametrize(
    ("text", "seconds"),
    [("10s", 10.0), ("2m", 120.0), ("500ms", 0.5), ("1h", 3600.0), ("3", 3.0), ("1.5m", 90.0)],
)
def test_duration_units(text, seconds):
    assert _duration(text) == seconds


@pytest.mark.parametrize("text", ["0s", "-1s", "abc", "10x", "", "ms", "nan", "inf", "1e999s"])
def test_duration_refuses(text):
    with pytest.raises(argparse.ArgumentTypeError, match="expected a"):
        _duration(text)


def test_bad_time_is_refused_by_the_cli(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["render", str(small_demo(tmp_path)), "-o", str(tmp_path / "x.npy"), "--time", "10x"])
    assert exit_.value.code == 2
    assert "expected a duration like 10s or 2m, got '10x'" in capsys.readouterr().err
    assert not (tmp_path / "x.npy").exists()


def test_time_renders_passes_and_averages_them(tmp_path, capsys):
    """--time 0.3s: passes of 4 spp until the time is spent, pass k with the seed
    (seed * 1000003 + k), averaged. The summary's spp counts every pass's samples; the image
    must be the average of exactly that many passes, bit for bit. (A pass of this 16x12 image
    takes about a millisecond: 0.3 s holds dozens, so at least two passes is certain.)"""
    scene = small_demo(tmp_path, 16, 12)
    image, summary = render_cli(capsys, scene, tmp_path / "t.npy", "--time", "0.3s",
                                "--spp", "4", "--seed", "5")  # fmt: skip
    passes, rest = divmod(summary["spp"], 4)
    assert rest == 0 and passes >= 2, summary
    assert summary["primary"] == passes * 4 * 16 * 12
    model = tracer.load_scene(scene).with_overrides(spp=4)
    total = np.zeros((12, 16, 3))
    for k in range(passes):
        one = model.with_overrides(seed=(5 * 1_000_003 + k) % 2**64)
        total += tracer.render(one, threads=1).astype(np.float64)
    assert np.array_equal(image, (total / passes).astype(np.float32))


def test_seed_changes_a_jittered_image_and_reproduces_it(tmp_path, capsys):
    scene = small_demo(tmp_path)
    a, _ = render_cli(capsys, scene, tmp_path / "a.npy", "--spp", "4", "--seed", "1")
    b, _ = render_cli(capsys, scene, tmp_path / "b.npy", "--spp", "4", "--seed", "2")
    again, _ = render_cli(capsys, scene, tmp_path / "c.npy", "--spp", "4", "--seed", "1")
    assert np.array_equal(a, again)
    assert np.sum(np.any(a != b, axis=-1)) > 50  # edges and highlights move with the jitter
    # One sample per pixel is its centre: nothing random, the seed changes nothing.
    c, _ = render_cli(capsys, scene, tmp_path / "d.npy", "--spp", "1", "--seed", "1")
    d, _ = render_cli(capsys, scene, tmp_path / "e.npy", "--spp", "1", "--seed", "2")
    assert np.array_equal(c, d)


def test_spp_sets_the_primary_rays(tmp_path, capsys):
    scene = small_demo(tmp_path)
    one, n1 = render_cli(capsys, scene, tmp_path / "a.npy", "--spp", "1")
    nine, n9 = render_cli(capsys, scene, tmp_path / "b.npy", "--spp", "9")
    assert (n1["spp"], n1["primary"]) == (1, 32 * 24)
    assert (n9["spp"], n9["primary"]) == (9, 9 * 32 * 24)
    assert np.sum(np.any(one != nine, axis=-1)) > 50  # antialiased edges


def test_max_depth_1_removes_reflections(tmp_path, capsys):
    """At --max-depth 1 the chain ends at the first hit: no reflected ray, and the image is
    the one where no material reflects (the local colour C1 of each pixel)."""
    mirrors = tmp_path / "mirrors.toml"
    mirrors.write_text((SCENES / "mirrors.toml").read_text())
    deep, nd = render_cli(capsys, mirrors, tmp_path / "a.npy", "--width", "40", "--height", "30")
    flat, n1 = render_cli(capsys, mirrors, tmp_path / "b.npy", "--width", "40", "--height", "30",
                          "--max-depth", "1")  # fmt: skip
    assert nd["secondary"] > 0 and n1["secondary"] == 0
    data = tracer.load_scene(mirrors).with_overrides(width=40, height=30).to_dict()
    for m in data["materials"].values():
        m["reflectivity"] = 0.0
    assert np.array_equal(flat, tracer.render(tracer.load_scene(data), threads=1))
    assert np.sum(np.any(np.abs(deep - flat) > 1e-3, axis=-1)) > 100


def test_bad_scene_fails_cleanly_and_keeps_the_old_image(tmp_path, capsys):
    out = tmp_path / "keep.png"
    out.write_bytes(b"precious")
    bad = tmp_path / "bad.toml"
    bad.write_text(small_demo(tmp_path).read_text().replace("radius = 1.0", "radius = -1.0", 1))
    assert main(["render", str(bad), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: objects[0].radius: expected a positive number" in err
    assert out.read_bytes() == b"precious"


def test_unknown_output_format_fails_before_rendering(tmp_path, capsys):
    out = tmp_path / "x.jpg"
    assert main(["render", str(small_demo(tmp_path)), "-o", str(out), "--quiet"]) == 2
    assert "unknown image format '.jpg'" in capsys.readouterr().err
    assert not out.exists()


def test_failed_write_leaves_the_old_image(tmp_path, monkeypatch):
    out = tmp_path / "keep.exr"
    out.write_bytes(b"precious")

    def boom(path, channels):
        Path(path).write_bytes(b"half")
        raise OSError("disk full")

    monkeypatch.setattr("tracer.image._write_exr", boom)
    with pytest.raises(OSError, match="disk full"):
        tracer.save_image(out, np.zeros((2, 2, 3), dtype=np.float32))
    assert out.read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.exr"]


class Started:
    """A child rtlab whose stderr is a terminal (a pseudo-terminal), so that it shows its
    progress bar: the sign that the render is under way."""

    def __init__(self, args: list[str], cwd: Path, env: dict[str, str] | None = None):
        import fcntl
        import pty
        import struct
        import termios

        self.master, slave = pty.openpty()
        # A new terminal is 0 columns wide, and a progress bar in 0 columns is empty: 24 x 80.
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
        self.proc = subprocess.Popen([*RTLAB, *args], stdout=subprocess.PIPE, stderr=slave,
                                     stdin=subprocess.DEVNULL, cwd=cwd, env=env)  # fmt: skip
        os.close(slave)
        self.err = b""

    def read(self, timeout: float) -> bool:
        """Read what the child wrote to its terminal; False at the end of it."""
        import select

        ready, _, _ = select.select([self.master], [], [], timeout)
        if not ready:
            return True
        try:
            data = os.read(self.master, 4096)
        except OSError:  # EIO: the child closed its terminal
            return False
        self.err += data
        return bool(data)

    def wait_for(self, marker: bytes, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while marker not in self.err:
            assert time.monotonic() < deadline, f"no {marker!r} after {timeout} s: {self.err!r}"
            assert self.proc.poll() is None, f"rtlab ended early: {self.err!r}"
            self.read(0.1)

    def finish(self, timeout: float = 60.0) -> tuple[int, str]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and self.read(0.2):
            pass
        self.proc.communicate(timeout=max(1.0, deadline - time.monotonic()))
        os.close(self.master)
        return self.proc.returncode, self.err.decode(errors="replace")


SIGNALS = {
    "SIGINT": (signal.SIGINT, 130, "SIGINT (Ctrl-C)"),
    "SIGTERM": (signal.SIGTERM, 143, "SIGTERM"),
}


@pytest.mark.parametrize("name", SIGNALS)
def test_interrupted_render_writes_nothing(tmp_path, name):
    """SIGINT or SIGTERM during a long render: it is cancelled through the core's watcher (the
    same path as Ctrl-C); exit 128 + the signal's number, one clear line, no output and no
    temporary file, and the image that was there before is left alone."""
    signum, status, said = SIGNALS[name]
    scene = small_demo(tmp_path, 2000, 1500)  # some 30 s at 64 spp on one thread
    out = tmp_path / "big.exr"
    out.write_bytes(b"precious")
    child = Started(["render", str(scene), "-o", str(out), "--spp", "64", "--threads", "1"],
                    tmp_path)  # fmt: skip
    child.wait_for(b"render:")  # the progress bar: the render is under way (tqdm, delay 0.5 s)
    child.proc.send_signal(signum)
    code, err = child.finish()
    assert code == status, err
    assert f"rtlab: interrupted by {said}; no output written" in err
    assert "Traceback" not in err
    assert out.read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.exr", "demo.toml"]


def test_interrupted_compare_writes_nothing(tmp_path):
    """SIGTERM while `rtlab compare` renders: exit 143, one line, no image, heat map or JSON
    written; an old metrics file stays as it was."""
    scene = small_demo(tmp_path, 2000, 1500)
    js = tmp_path / "metrics.json"
    js.write_text("precious")
    child = Started(["compare", str(scene), "--against", "povray", "--out-dir", "cmp",
                     "--json", str(js), "--spp", "64", "--threads", "1"], tmp_path)  # fmt: skip
    child.wait_for(b"render:")
    child.proc.send_signal(signal.SIGTERM)
    code, err = child.finish()
    assert code == 143, err
    assert "rtlab: interrupted by SIGTERM; no output written" in err
    assert js.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo.toml", "metrics.json"]


def _children(pid: int) -> list[int]:
    text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    return [int(c) for c in text.split()]


def _cmdline(pid: int) -> str:
    """A process's command line; empty for a zombie, or for one already gone."""
    try:
        return Path(f"/proc/{pid}/cmdline").read_text()
    except (FileNotFoundError, ProcessLookupError):
        return ""


def _povray_children(pid: int) -> list[int]:
    """The children of `pid` that run POV-Ray now. A child caught between its fork and its exec
    still shows the parent's command line, and one that has ended (a zombie) an empty one: the
    caller waits until POV-Ray itself is running (a test once failed reading one too soon)."""
    return [c for c in _children(pid) if "povray" in _cmdline(c)]


def test_interrupted_compare_stops_povray_and_leaves_no_temporary_files(tmp_path):
    """Ctrl-C while POV-Ray renders for `rtlab compare`: its child process is ended, its
    temporary directory removed, and rtlab exits 130 having written nothing."""
    scene = small_demo(tmp_path, 3000, 2250)
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp))
    child = Started(["compare", str(scene), "--against", "povray", "--out-dir", "cmp",
                     "--threads", "1", "--quiet"], tmp_path, env)  # fmt: skip
    deadline = time.monotonic() + 60
    while not (povray := _povray_children(child.proc.pid)):
        assert time.monotonic() < deadline and child.proc.poll() is None, child.err
        child.read(0.05)
    child.proc.send_signal(signal.SIGINT)
    code, err = child.finish()
    assert code == 130, err
    assert "rtlab: interrupted by SIGINT (Ctrl-C); no output written" in err
    # subprocess.run sends SIGKILL on Ctrl-C and, by design, does not wait for the child: the
    # kernel ends it when it is next scheduled, which on a loaded machine (the suite's other
    # worker) can be after rtlab's exit. Killed means gone or a zombie within seconds; a
    # POV-Ray left rendering would still run at the deadline.
    deadline = time.monotonic() + 10
    while Path(f"/proc/{povray[0]}").exists() and "zombie" not in _state(povray[0]):
        assert time.monotonic() < deadline, f"POV-Ray still runs:\n{_state(povray[0])}"
        time.sleep(0.05)
    assert list(tmp.iterdir()) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo.toml", "tmp"]


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return "zombie"


def test_check_and_demo_verbs(tmp_path, capsys):
    assert main(["check", str(small_demo(tmp_path))]) == 0
    assert "ok (4 objects, 2 lights, 4 materials)" in capsys.readouterr().out
    assert (
        main(["demo", "--out-dir", str(tmp_path / "out"), "--width", "16", "--height", "12"]) == 0
    )
    printed = capsys.readouterr().out
    assert "ex25-rtlab.png" in printed
    assert (tmp_path / "out" / "ex25-rtlab.exr").exists()


def test_console_script_is_installed():
    exe = Path(sys.executable).parent / "rtlab"
    assert exe.exists() and os.access(exe, os.X_OK)
    done = subprocess.run([str(exe), "--help"], capture_output=True, text=True, check=True)
    assert "render" in done.stdout


def test_an_atomic_write_gets_the_mode_a_plain_write_gets(tmp_path):
    """mkstemp's temporary file is private (0600); renamed into place it must not keep that
    mode, or a web server could not serve a page and another user could not read a result."""
    import os
    import stat

    from tracer.image import atomic_path

    old = os.umask(0o022)  # the usual one, set so that the expected mode is known
    try:
        plain = tmp_path / "plain.txt"
        plain.write_text("x")
        with atomic_path(tmp_path / "atomic.txt") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(old)
    assert stat.S_IMODE(os.stat(plain).st_mode) == 0o644
    assert stat.S_IMODE(os.stat(tmp_path / "atomic.txt").st_mode) == 0o644
