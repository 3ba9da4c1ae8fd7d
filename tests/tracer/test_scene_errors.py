"""Bad input: every error names the file, the key path and what was expected."""

from __future__ import annotations

import pytest

import tracer
from tests.helpers import scene_dict, sphere
from tracer.scene import SceneError

GOOD = """
[camera]
eye = [0.0, 1.5, 6.0]
look_at = [0.0, 1.0, 0.0]

[materials.red]
color = [0.8, 0.1, 0.1]

[[lights]]
type = "point"
position = [-3.0, 5.0, 4.0]

[[objects]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 1.0
material = "red"

[[objects]]
type = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
material = "red"
"""


def error_for(tmp_scene, text):
    path = tmp_scene(text)
    with pytest.raises(SceneError) as info:
        tracer.load_scene(path)
    message = str(info.value)
    assert message.startswith(str(path) + ": "), message
    return info.value


def test_the_good_scene_loads(tmp_scene):
    scene = tracer.load_scene(tmp_scene(GOOD))
    assert len(scene.objects) == 2 and scene.objects[0].radius == 1.0


@pytest.mark.parametrize(
    ("old", "new", "key", "words"),
    [
        ("radius = 1.0", "radus = 1.0", "objects[0].radus", "did you mean 'radius'"),
        ("[camera]", "[camra]", "camra", "did you mean 'camera'"),
        ('type = "sphere"', 'type = "sphear"', "objects[0].type", "did you mean 'sphere'"),
        ("radius = 1.0", 'radius = "big"', "objects[0].radius", "expected a number, got string"),
        ("radius = 1.0", "radius = true", "objects[0].radius", "expected a number, got boolean"),
        ("radius = 1.0", "radius = nan", "objects[0].radius", "expected a finite number"),
        ("radius = 1.0", "radius = inf", "objects[0].radius", "expected a finite number"),
        ("radius = 1.0", "radius = -1.0", "objects[0].radius", "expected a positive number"),
        ("radius = 1.0", "radius = 0.0", "objects[0].radius", "expected a positive number"),
        ("center = [0.0, 1.0, 0.0]", "center = [0.0, 1.0]", "objects[0].center", "three numbers"),
        ("center = [0.0, 1.0, 0.0]", "center = [0.0, -inf, 0.0]", "objects[0].center[1]", "finite"),
        ("normal = [0.0, 1.0, 0.0]", "normal = [0.0, 0.0, 0.0]", "objects[1].normal", "non-zero"),
        (
            'material = "red"\n\n[[objects]]\ntype = "plane"',
            'material = "rde"\n\n[[objects]]\ntype = "plane"',
            "objects[0].material",
            "unknown material 'rde' (did you mean 'red'?)",
        ),
        ("color = [0.8, 0.1, 0.1]", "color = [0.8, -0.1, 0.1]", "materials.red.color", ">= 0"),
        ("[camera]", "[camera]\nwidth = 0", "camera.width", "from 1 to"),
        ("[camera]", "[camera]\nwidth = 100000", "camera.width", "from 1 to"),
        ("[camera]", "[camera]\nheight = 2.5", "camera.height", "expected an integer"),
        ("[camera]", "[camera]\nfov_y = 180.0", "camera.fov_y", "< 180"),
        ("[camera]", "[camera]\nup = [0.0, 0.0, 0.0]", "camera.up", "non-zero"),
        ("look_at = [0.0, 1.0, 0.0]", "look_at = [0.0, 1.5, 6.0]", "camera.look_at", "differ"),
        ("[camera]", "[camera]\nup = [0.0, -1.0, -12.0]", "camera.up", "parallel"),
        (
            "position = [-3.0, 5.0, 4.0]",
            "direction = [0.0, 0.0, 0.0]",
            "lights[0].direction",
            "unknown key for a point light",
        ),
        (
            'type = "point"\nposition = [-3.0, 5.0, 4.0]',
            'type = "directional"\ndirection = [0.0, 0.0, 0.0]',
            "lights[0].direction",
            "non-zero",
        ),
        ("[[lights]]", "[render]\nspp = 0\n\n[[lights]]", "render.spp", "from 1 to"),
        ("[[lights]]", "[render]\nmax_depth = -1\n\n[[lights]]", "render.max_depth", "from 1 to"),
        (
            "[[lights]]",
            "[render]\nmin_coefficient = -0.5\n\n[[lights]]",
            "render.min_coefficient",
            ">= 0",
        ),
        (
            "[[lights]]",
            '[render]\nintegrator = "clasic"\n\n[[lights]]',
            "render.integrator",
            "did you mean 'classic'",
        ),
        (
            "[[lights]]",
            "[materials.red2]\nshininess = 0.0\n\n[[lights]]",
            "materials.red2.shininess",
            "positive",
        ),
    ],
)
def test_bad_values_are_named(tmp_scene, old, new, key, words):
    assert old in GOOD
    err = error_for(tmp_scene, GOOD.replace(old, new, 1))
    assert err.key == key, str(err)
    assert words in str(err)


def test_missing_required_key(tmp_scene):
    err = error_for(tmp_scene, GOOD.replace("radius = 1.0\n", "", 1))
    assert err.key == "objects[0].radius" and "missing" in str(err)


def test_missing_camera(tmp_scene):
    text = GOOD.replace("[camera]\neye = [0.0, 1.5, 6.0]\nlook_at = [0.0, 1.0, 0.0]\n", "")
    assert "camera" not in text
    err = error_for(tmp_scene, text)
    assert err.key == "camera" and "missing" in str(err)


def test_invalid_toml_names_the_file_and_the_line(tmp_scene):
    err = error_for(tmp_scene, GOOD.replace("radius = 1.0", "radius = = 1.0"))
    assert "invalid TOML" in str(err) and "line" in str(err)


def test_unreadable_files(tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(SceneError, match=r"nope\.toml: cannot read the scene file: No such file"):
        tracer.load_scene(missing)
    folder = tmp_path / "dir.toml"
    folder.mkdir()
    with pytest.raises(SceneError, match=r"dir\.toml: cannot read the scene file"):
        tracer.load_scene(str(folder))
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(SceneError, match=r"bin\.toml: cannot read the scene file"):
        tracer.load_scene(binary)


def test_dicts_and_strings_load_too():
    from_dict = tracer.load_scene(scene_dict(objects=[sphere([0, 0, 0], 2.0)]))
    assert from_dict.objects[0].radius == 2.0
    from_text = tracer.load_scene(GOOD)
    assert from_text.source == "<string>" and len(from_text.objects) == 2
    with pytest.raises(SceneError, match=r"^<dict>: objects\[0\]\.radius"):
        tracer.load_scene(scene_dict(objects=[sphere([0, 0, 0], -2.0)]))


def test_overrides_are_checked_too():
    scene = tracer.load_scene(GOOD)
    assert scene.with_overrides(width=1920, spp=4).camera.width == 1920
    with pytest.raises(SceneError, match=r"camera\.width"):
        scene.with_overrides(width=0)
