"""rtlab in Jupyter: the example notebook executed in a real kernel (nbclient + ipykernel), its
inline images checked against renders made here; and tracer/display.py's tone maps against
their closed forms."""

import base64
import io

import nbformat
import numpy as np
import pytest
from nbclient import NotebookClient
from PIL import Image

import tracer
from tests.helpers import ROOT, SCENES
from tracer.display import picture, scene_preview, tone_map

NOTEBOOK = ROOT / "tracer" / "notebooks" / "first_look.ipynb"


def _png_pixels(data: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(data)) as im:
        assert im.mode == "RGB"
        return np.asarray(im)


def _srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1's encoding, written out again here rather than imported."""
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


@pytest.fixture(scope="module")
def executed() -> nbformat.NotebookNode:
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # The kernel is the venv's own Python (ipykernel's native "python3"); the notebook's
    # directory is its working directory, as when a person opens it in Jupyter.
    client = NotebookClient(
        nb,
        timeout=120,
        kernel_name="python3",
        resources={"metadata": {"path": str(NOTEBOOK.parent)}},
    )
    client.execute()
    return nb


def _images(cell: nbformat.NotebookNode) -> list[np.ndarray]:
    return [
        _png_pixels(base64.b64decode(out["data"]["image/png"]))
        for out in cell.get("outputs", [])
        if "image/png" in out.get("data", {})
    ]


def _code_cells(nb: nbformat.NotebookNode) -> list[nbformat.NotebookNode]:
    return [c for c in nb.cells if c.cell_type == "code"]


def test_the_notebook_runs_without_errors(executed):
    for cell in _code_cells(executed):
        for out in cell.get("outputs", []):
            assert out["output_type"] != "error", "".join(out.get("traceback", []))


def test_a_scene_shows_itself_as_a_preview(executed):
    (shown,) = _images(_code_cells(executed)[0])
    scene = tracer.load_scene(SCENES / "ex25.toml")
    # Ex 25 is 1920x1024 or so: the preview keeps the aspect with 320 pixels along the longer
    # side, and is the classic render of that smaller camera, clipped to sRGB.
    assert scene.camera.width > scene.camera.height
    assert shown.shape[1] == 320
    assert abs(shown.shape[0] / shown.shape[1] - scene.camera.height / scene.camera.width) < 0.01
    assert np.array_equal(shown, scene_preview(scene).pixels)


def test_show_inline_is_the_png_save_image_writes(executed, tmp_path):
    (shown,) = _images(_code_cells(executed)[1])
    scene = tracer.load_scene(SCENES / "ex25.toml").with_overrides(width=480, height=256)
    image = tracer.render(scene, progress=False)  # classic at 1 spp: the same on any threads
    tracer.save_image(tmp_path / "ex25.png", image)
    with Image.open(tmp_path / "ex25.png") as im:
        assert np.array_equal(shown, np.asarray(im))


def test_show_with_reinhard_tone_map(executed):
    (shown,) = _images(_code_cells(executed)[2])
    cornell = tracer.load_scene(SCENES / "cornell_box.toml")
    box = tracer.render(cornell.with_overrides(width=128, height=128, spp=16), progress=False)
    # The path tracer's image depends on the seed and the pixel only (pixel_rng), not on the
    # process or threads, so this is the notebook's image. Reinhard's eq. 3 on the luminance,
    # exposure +1 stop, then sRGB; 8-bit rounding can differ by one level where the float64
    # sums round differently.
    x = box.astype(np.float64) * 2.0
    y = 0.2126 * x[..., 0] + 0.7152 * x[..., 1] + 0.0722 * x[..., 2]
    expected = np.round(_srgb(np.clip(x / (1 + y)[..., None], 0, 1)) * 255)
    assert np.abs(shown.astype(int) - expected).max() <= 1
    # The light seen directly is far above 1: clipping makes it pure white; Reinhard keeps its
    # warm hue (its channels differ).
    light = np.unravel_index(np.argmax(box.sum(axis=2)), box.shape[:2])
    assert box[light].min() > 4
    assert (tone_map(box, exposure=1.0)[light] == 255).all()
    assert len(set(shown[light].tolist())) > 1


def test_aov_channel_and_render_result(executed):
    shown, result = _images(_code_cells(executed)[3])
    scene = tracer.load_scene(SCENES / "ex25.toml")
    aov = tracer.render(
        scene.with_overrides(integrator="aov", width=240, height=128), progress=False
    )
    ids = aov[..., 1]
    # Every object a colour of its own; a miss black.
    assert (shown[ids < 0] == 0).all()
    for a in np.unique(ids[ids >= 0]):
        for b in np.unique(ids[ids >= 0]):
            if a < b:
                assert not np.array_equal(shown[ids == a][0], shown[ids == b][0])
    image = tracer.render(scene.with_overrides(width=240, height=128), progress=False)
    assert np.array_equal(result, tone_map(image))


def test_clip_tone_map_closed_form():
    values = np.array([[[0.0, 0.0031308, 0.5], [1.0, 2.0, -1.0], [np.nan, np.inf, 0.2]]])
    got = tone_map(values)
    x = np.array([[[0.0, 0.0031308, 0.5], [1.0, 1.0, 0.0], [0.0, 0.0, 0.2]]])
    assert np.array_equal(got, np.round(_srgb(x) * 255).astype(np.uint8))
    # One stop of exposure doubles the linear value: 0.25 shows as 0.5 did.
    quarter = tone_map(np.full((1, 1, 3), 0.25), exposure=1.0)
    assert np.array_equal(quarter, tone_map(np.full((1, 1, 3), 0.5)))


def test_bad_choices_name_the_choices():
    with pytest.raises(ValueError, match="tone must be one of 'clip', 'reinhard'"):
        tone_map(np.zeros((1, 1, 3)), tone="gamma")
    with pytest.raises(ValueError, match="channel must be one of"):
        picture(np.zeros((1, 1, 5), dtype=np.float32), channel="albedo")
    with pytest.raises(ValueError, match=r"shape \(height, width, 3\)"):
        tone_map(np.zeros((2, 2)))
