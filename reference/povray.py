"""Running POV-Ray 3.7 as a subprocess on a converted scene.

Output precision decides the tolerances of every comparison, so it is chosen per pixel:
POV-Ray's linear 16-bit PNG (``+FN16 File_Gamma=1.0``) is exact to half a step of 1/65535,
under 8e-6, but clamps at 1; where a pixel is clamped the scene is rendered again to OpenEXR,
which POV-Ray always writes as half float (relative error 2^-11, about 5e-4), and those pixels
are taken from there. ``PovrayResult.error_bound`` carries the bound for each pixel.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from converters.povray import write_povray
from tracer.image import load_image
from tracer.scene import Scene

#: Half a step of a 16-bit channel.
PNG16_BOUND = 0.5 / 65535
#: Relative rounding of a half float (11 significant bits), as an upper bound.
HALF_RELATIVE = 2.0**-11


class PovrayError(RuntimeError):
    pass


@dataclass(frozen=True)
class PovrayResult:
    image: npt.NDArray[np.float32]  # linear RGB, (height, width, 3)
    error_bound: npt.NDArray[np.float32]  # per-pixel, per-channel bound on the output rounding
    trace_seconds: float  # POV-Ray's own "Trace Time", start-up excluded
    total_seconds: float  # the whole process(es), start-up included
    rays: dict[str, int]
    sdl: str


def povray_executable() -> str:
    exe = shutil.which("povray")
    if exe is None:
        raise PovrayError(
            "POV-Ray is not installed (no 'povray' on PATH): run 'make setup', which installs "
            "the Debian package 'povray'"
        )
    return exe


def read_png16(path: str | Path) -> npt.NDArray[np.float64]:
    """A 16-bit PNG as floats in [0, 1], at full precision (Pillow would cut it to 8 bits)."""
    import png

    width, height, rows, info = png.Reader(filename=str(path)).asDirect()
    if info["bitdepth"] != 16:
        raise PovrayError(f"{path}: expected a 16-bit PNG, got {info['bitdepth']} bits")
    planes = info["planes"]
    data = np.vstack([np.asarray(row, dtype=np.uint16) for row in rows])
    return data.reshape(height, width, planes)[..., :3].astype(np.float64) / 65535.0


_TRACE_TIME = re.compile(r"Trace Time:.*\(([\d.]+) seconds\)")
_COUNTS = {
    "rays": re.compile(r"^Rays:\s+(\d+)", re.M),
    "shadow": re.compile(r"^Shadow Ray Tests:\s+(\d+)", re.M),
    "reflected": re.compile(r"^Reflected Rays:\s+(\d+)", re.M),
}


def _run(
    sdl_path: Path, out: Path, args: list[str], threads: int, aa: tuple[str, ...] = ("-A",)
) -> tuple[float, str]:
    cmd = [povray_executable(), f"+I{sdl_path}", f"+O{out}", *args, "-D", *aa, "-P",
           f"+WT{threads}", "-V"]  # fmt: skip
    done = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if done.returncode != 0 or not out.exists():
        raise PovrayError(
            f"povray failed (exit {done.returncode}) on {sdl_path}:\n{done.stderr[-2000:]}"
        )
    match = _TRACE_TIME.search(done.stderr)
    if match is None:
        raise PovrayError(f"no 'Trace Time' in POV-Ray's statistics:\n{done.stderr[-2000:]}")
    return float(match.group(1)), done.stderr


def run_povray(
    scene: Scene,
    *,
    threads: int = 1,
    workdir: str | Path | None = None,
    sdl: str | None = None,
    exr_pass: bool = True,
    antialias: int = 0,
) -> PovrayResult:
    """Render ``scene`` with POV-Ray; the image and its per-pixel precision.

    ``sdl`` renders that text instead of the converter's (the tests feed wrong conversions).
    ``exr_pass=False`` skips the second, EXR render of clamped pixels (for timing one pass).
    ``antialias=n`` supersamples every pixel with a jittered n x n grid (``+A0.0 +AM1 +Rn +J``:
    threshold 0, so no pixel is skipped), the estimator of rtlab's stratified spp = n^2, in one
    half-float EXR pass (its rounding is far below the noise of any such render).
    """
    cam = scene.camera
    with tempfile.TemporaryDirectory(prefix="rtlab-povray-") as tmp:
        work = Path(workdir) if workdir is not None else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        sdl_path = work / "scene.pov"
        if sdl is None:
            write_povray(scene, sdl_path)
        else:
            sdl_path.write_text(sdl)
        size = [f"+W{cam.width}", f"+H{cam.height}"]
        start = time.perf_counter()
        if antialias > 0:
            aa = ("+A0.0", "+AM1", f"+R{antialias}", "+J1.0")
            trace, log = _run(sdl_path, work / "out.exr", [*size, "+FE"], threads, aa)
            image = load_image(work / "out.exr").astype(np.float64)
            return PovrayResult(
                image.astype(np.float32),
                (HALF_RELATIVE * np.abs(image)).astype(np.float32),
                trace,
                time.perf_counter() - start,
                {},
                sdl_path.read_text(),
            )
        trace, log = _run(sdl_path, work / "out.png", [*size, "+FN16", "File_Gamma=1.0"], threads)
        image = read_png16(work / "out.png")
        bound = np.full(image.shape, PNG16_BOUND)
        clamped = image >= 1.0
        if clamped.any() and exr_pass:
            trace_exr, _ = _run(sdl_path, work / "out.exr", [*size, "+FE"], threads)
            trace += trace_exr
            exr = load_image(work / "out.exr").astype(np.float64)
            image = np.where(clamped, exr, image)
            bound = np.where(clamped, HALF_RELATIVE * np.abs(exr), bound)
        total = time.perf_counter() - start
        rays = {}
        for key, pattern in _COUNTS.items():
            m = pattern.search(log)
            if m:
                rays[key] = int(m.group(1))
        return PovrayResult(
            image=image.astype(np.float32),
            error_bound=bound.astype(np.float32),
            trace_seconds=trace,
            total_seconds=total,
            rays=rays,
            sdl=sdl_path.read_text(),
        )
