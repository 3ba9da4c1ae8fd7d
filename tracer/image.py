"""Reading and writing images: EXR (float32 linear), PNG (8-bit sRGB), NPY (float32 linear).

Every write is atomic: the image goes to a temporary file in the target's directory, which is
then renamed over the target. An interrupted or failed write leaves no truncated file and never
touches an existing image.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import numpy.typing as npt

FORMATS = (".exr", ".png", ".npy")

FloatImage = npt.NDArray[np.float32]


class ImageFormatError(ValueError):
    pass


def image_format(path: str | os.PathLike[str]) -> str:
    """The format a path asks for, by suffix; raises ImageFormatError for an unknown one."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise ImageFormatError(
            f"{path}: unknown image format {suffix or '(no suffix)'!r}; "
            f"expected one of {', '.join(FORMATS)}"
        )
    return suffix


def _umask() -> int:
    """This process's umask, read without changing it (os.umask can only set it, which would
    race with other threads creating files); Linux lists it in /proc/self/status."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    return 0o022


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it over ``path``."""
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    os.close(fd)
    try:
        # mkstemp makes the file readable by its owner alone; the output gets the mode any
        # new file of this process gets (0666 less the umask), as open() would have given it.
        os.chmod(tmp, 0o666 & ~_umask())
        yield Path(tmp)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def linear_to_srgb(linear: npt.NDArray[np.floating]) -> npt.NDArray[np.float64]:
    """The sRGB transfer function (IEC 61966-2-1), on values clipped to [0, 1]."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb_to_linear(encoded: npt.NDArray[np.floating]) -> npt.NDArray[np.float64]:
    x = np.asarray(encoded, dtype=np.float64)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def save_image(path: str | os.PathLike[str], image: npt.ArrayLike) -> Path:
    """Write a float linear RGB image of shape (height, width, 3), atomically."""
    fmt = image_format(path)
    rgb = np.ascontiguousarray(image, dtype=np.float32)
    if rgb.ndim != 3 or rgb.shape[2] != 3:
        raise ValueError(f"expected an image of shape (height, width, 3), got {rgb.shape}")
    with atomic_path(path) as tmp:
        if fmt == ".npy":
            with open(tmp, "wb") as f:
                np.save(f, rgb)
        elif fmt == ".png":
            from PIL import Image

            srgb = np.round(linear_to_srgb(rgb) * 255.0).astype(np.uint8)
            Image.fromarray(srgb, mode="RGB").save(tmp, format="PNG")
        else:
            _write_exr(tmp, {"RGB": rgb})
    return Path(path)


def save_aov(path: str | os.PathLike[str], channels: dict[str, npt.ArrayLike]) -> Path:
    """Write named float32 channels (an aov render) to EXR, or stacked to NPY, atomically."""
    fmt = image_format(path)
    if fmt == ".png":
        raise ImageFormatError(f"{path}: an aov render has no colours to show; write .exr or .npy")
    data = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in channels.items()}
    with atomic_path(path) as tmp:
        if fmt == ".npy":
            with open(tmp, "wb") as f:
                np.save(f, np.stack(list(data.values()), axis=-1))
        else:
            _write_exr(tmp, data)
    return Path(path)


def load_exr_channels(path: str | os.PathLike[str]) -> dict[str, npt.NDArray[np.float32]]:
    """Every channel of an EXR file by name, e.g. depth, object_id, N.X, N.Y, N.Z."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        return {name: np.asarray(c.pixels, dtype=np.float32) for name, c in f.channels().items()}


def _write_exr(path: Path, channels: dict[str, npt.NDArray[np.float32]]) -> None:
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))


def load_image(path: str | os.PathLike[str]) -> FloatImage:
    """Read an image written by ``save_image`` (or any RGB EXR / PNG) as float32 linear RGB.

    16-bit PNGs are read at full precision with their own decoder (Pillow reduces 16-bit RGB to
    8 bits); 8-bit PNGs are taken to be sRGB-encoded, 16-bit PNGs to be linear, as POV-Ray writes
    them with File_Gamma=1.0.
    """
    fmt = image_format(path)
    if fmt == ".npy":
        return np.load(path).astype(np.float32)
    if fmt == ".exr":
        import OpenEXR

        with OpenEXR.File(str(path)) as f:
            channels = f.channels()
            if "RGB" in channels:
                return np.asarray(channels["RGB"].pixels, dtype=np.float32)
            return np.stack([channels[c].pixels for c in "RGB"], axis=-1).astype(np.float32)
    from PIL import Image

    with Image.open(path) as im:
        if im.mode in ("I;16", "I;16B", "I") or "16" in str(im.info.get("bitdepth", "")):
            raise ImageFormatError(f"{path}: 16-bit PNG needs reference.povray's reader")
        data = np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    return srgb_to_linear(data).astype(np.float32)
