"""The command line and image files: formats, atomic writes, errors, interruption."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import tracer
from tracer.cli import demo_scene_path, main
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


def test_interrupted_render_writes_nothing(tmp_path):
    """Ctrl-C during a long render: exit 130, no output, no temporary file, old image kept."""
    scene = small_demo(tmp_path, 4000, 3000)
    out = tmp_path / "big.exr"
    out.write_bytes(b"precious")
    proc = subprocess.Popen(
        [*RTLAB, "render", str(scene), "-o", str(out), "--spp", "64", "--threads", "1"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(1.5)  # well into the render: python start-up and scene loading take ~0.3 s
    assert proc.poll() is None, "the render finished too soon to be interrupted"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert "interrupted" in err
    assert out.read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["big.exr", "demo.toml"]


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
