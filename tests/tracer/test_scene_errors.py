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


# --------------------------------------------------------------------------- bad input, by class
# Each class of bad input gets its own case: the message names the file (error_for) and the key.

HEAD = GOOD[: GOOD.index("[[objects]]")]


def one_object(block: str) -> str:
    return HEAD + "[[objects]]\n" + block.strip() + '\nmaterial = "red"\n'


TRIANGLE = "vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]"
BOX = 'type = "box"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 1.0, 1.0]'
PATH = '[render]\nintegrator = "path"\n\n'

BAD_INPUT = {
    "box min not below max": (
        one_object('type = "box"\nmin = [0.0, 0.0, 0.0]\nmax = [1.0, 0.0, 1.0]'),
        "objects[0].max", "expected each coordinate above min",
    ),
    "zero-area triangle": (
        one_object('type = "triangle"\n'
                   "vertices = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]"),
        "objects[0].vertices", "non-zero area",
    ),
    "parallel quad edges": (
        one_object('type = "quad"\ncorner = [0.0, 0.0, 0.0]\nedge1 = [1.0, 0.0, 0.0]\n'
                   "edge2 = [-2.0, 0.0, 0.0]"),
        "objects[0].edge2", "not parallel to edge1",
    ),
    "mesh index out of range": (
        one_object(f'type = "mesh"\n{TRIANGLE}\nfaces = [[0, 1, 3]]'),
        "objects[0].faces[0]", "expected vertex indices 0..2 (the mesh has 3 vertices), got 3",
    ),
    "mesh face of two vertices": (
        one_object(f'type = "mesh"\n{TRIANGLE}\nfaces = [[0, 1]]'),
        "objects[0].faces[0]", "three or more vertex indices",
    ),
    "mesh without vertices": (
        one_object('type = "mesh"\nvertices = []\nfaces = [[0, 1, 2]]'),
        "objects[0].vertices", "one or more points",
    ),
    "NaN in a mesh vertex": (
        one_object('type = "mesh"\nvertices = [[0.0, 0.0, 0.0], [1.0, 0.0, nan], [0.0, 1.0, 0.0]]\n'
                   "faces = [[0, 1, 2]]"),
        "objects[0].vertices[1][2]", "expected a finite number",
    ),
    "missing mesh file": (
        one_object('type = "mesh"\nfile = "nowhere.ply"'), "objects[0].file", "no such file",
    ),
    "mesh file of an unknown format": (
        one_object('type = "mesh"\nfile = "bunny.stl"'), "objects[0].file", "a .ply or .obj file",
    ),
    "mesh file and vertices both": (
        one_object(f'type = "mesh"\nfile = "m.obj"\n{TRIANGLE}\nfaces = [[0, 1, 2]]'),
        "objects[0].file", "either file or vertices and faces, not both",
    ),
    "mesh file in a package not installed": (
        one_object('type = "mesh"\nfile = "package:no_such_package_here/m.ply"'),
        "objects[0].file", "no installed Python package 'no_such_package_here'",
    ),
    "cylinder top = base": (
        one_object('type = "cylinder"\nbase = [0.0, 1.0, 0.0]\ntop = [0.0, 1.0, 0.0]\n'
                   "radius = 0.5"),
        "objects[0].top", "a point other than base",
    ),
    "zero scale": (
        one_object(BOX + "\ntransform = { scale = [1.0, 0.0, 1.0] }"),
        "objects[0].transform.scale", "three non-zero numbers",
    ),
    "zero rotation axis": (
        one_object(BOX + "\ntransform = { rotate = { axis = [0.0, 0.0, 0.0], degrees = 30.0 } }"),
        "objects[0].transform.rotate.axis", "non-zero vector",
    ),
    "spindle torus": (
        one_object('type = "torus"\ncenter = [0.0, 1.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n'
                   "major_radius = 0.5\nminor_radius = 0.75"),
        "objects[0].minor_radius", "at most major_radius (0.5), got 0.75",
    ),
    "type given as a table": (
        GOOD.replace('type = "sphere"', 'type = { name = "sphere" }', 1),
        "objects[0].type", "got table",
    ),
    "type given as an array": (
        GOOD.replace('type = "point"', 'type = ["point"]', 1), "lights[0].type", "got array",
    ),
    "negative emission": (
        GOOD.replace("color = [0.8, 0.1, 0.1]", "emission = [1.0, -0.5, 1.0]", 1),
        "materials.red.emission", "three numbers >= 0",
    ),
    "unknown acceleration": (
        '[render]\nacceleration = "bhv"\n' + GOOD,
        "render.acceleration", "(did you mean 'bvh'?)",
    ),
    "lights given as a table": (
        GOOD.replace("[[lights]]", "[lights]", 1), "lights", "expected an array of tables",
    ),
    "a key that is not bare": (
        GOOD.replace("[materials.red]", '[materials."dark red"]\ncolour = 1\n\n[materials.red]', 1),
        'materials."dark red".colour', "did you mean 'color'",
    ),
    "an empty key": (
        GOOD.replace("[camera]", '"" = 1\n\n[camera]', 1), '""', "unknown key",
    ),
    "material that overflows float32": (
        GOOD.replace("color = [0.8, 0.1, 0.1]", "color = [1e18, 0.1, 0.1]\ndiffuse = 100.0", 1),
        "materials.red.color", "a value of 1e+18 could make the image overflow float32",
    ),
    "a highlight exponent past the core's x^n": (
        GOOD.replace("color = [0.8, 0.1, 0.1]", "specular = 0.5\nshininess = 1.2e16", 1),
        "materials.red.shininess", "expected a number <= 1e+12, got 1.2e+16",
    ),
    "a number past 1e18": (
        GOOD.replace("color = [0.8, 0.1, 0.1]", "color = [1e299, 0.1, 0.1]", 1),
        "materials.red.color[0]", "magnitude at most 1e+18, got 1e+299",
    ),
    "an integer past a double": (
        GOOD.replace("radius = 1.0", f"radius = {10**400}", 1),
        "objects[0].radius", "expected a finite number",
    ),
    "a mesh vertex near the largest double": (
        one_object('type = "mesh"\nvertices = [[0.0, 0.0, 0.0], [1.7976931348623157e308, 0.0, 0.0],'
                   " [0.0, 1.0, 0.0]]\nfaces = [[0, 1, 2]]"),
        "objects[0].vertices[1][0]", "magnitude at most 1e+18",
    ),
    "a transform that carries an object too far": (
        one_object(BOX + "\ntransform = { scale = [1e17, 1.0, 1.0], "
                   "translate = [1e18, 0.0, 0.0] }"),
        "objects[0].transform", "within 1e+18 of the origin, got one reaching 1.3e+18",
    ),
    "light that overflows float32": (
        GOOD.replace("position = [-3.0, 5.0, 4.0]",
                     "position = [-3.0, 5.0, 4.0]\ncolor = [1e18, 1.0, 1.0]", 1)
        .replace("color = [0.8, 0.1, 0.1]", "diffuse = 100.0", 1),
        "lights[0].color", "a value of 1e+18 could make the image overflow float32",
    ),
    "reflection chain that overflows float32": (
        "[render]\nmax_depth = 10000\n"
        + GOOD.replace("color = [0.8, 0.1, 0.1]", "reflectivity = 1.5", 1),
        "materials.red.reflectivity", "returning 1.5 times what it receives, over render.max_depth",
    ),
    "path emission that overflows float32": (
        PATH + GOOD.replace("color = [0.8, 0.1, 0.1]",
                            "emission = [1e18, 1e18, 1e18]\ndiffuse = 100.0", 1),
        "materials.red.emission", "a value of 1e+18 could make the image overflow float32",
    ),
}  # fmt: skip


@pytest.mark.parametrize(("text", "key", "words"), BAD_INPUT.values(), ids=BAD_INPUT.keys())
def test_bad_input_names_the_file_and_the_key(tmp_scene, text, key, words):
    err = error_for(tmp_scene, text)
    assert err.key == key, str(err)
    assert f": {key}: " in str(err) and words in str(err), str(err)


def test_a_mesh_file_with_a_nan_vertex_is_refused(tmp_scene):
    path = tmp_scene(one_object('type = "mesh"\nfile = "m.obj"'))
    (path.parent / "m.obj").write_text("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError) as info:
        tracer.load_scene(path)
    assert info.value.key == "objects[0].file" and "non-finite vertices" in str(info.value)
    assert str(info.value).startswith(f"{path}: objects[0].file: ")


def test_a_mesh_file_that_reaches_too_far_is_refused(tmp_scene):
    """A mesh file's vertices pass no number check of the reader: its reach is checked."""
    path = tmp_scene(one_object('type = "mesh"\nfile = "m.obj"'))
    (path.parent / "m.obj").write_text("v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(SceneError) as info:
        tracer.load_scene(path)
    assert str(info.value).startswith(f"{path}: objects[0]: expected an object within 1e+18")


def test_tiny_directions_are_made_unit_length(tmp_scene):
    """A normal or light direction so short that its squared length underflows (1e-300) is
    still a direction: it becomes a unit vector, not a division by zero."""
    text = GOOD.replace("normal = [0.0, 1.0, 0.0]", "normal = [0.0, 1e-300, 0.0]", 1).replace(
        'type = "point"\nposition = [-3.0, 5.0, 4.0]',
        'type = "directional"\ndirection = [-1e-300, -1e-300, 0.0]', 1)  # fmt: skip
    scene = tracer.load_scene(tmp_scene(text))
    assert scene.objects[1].normal == (0.0, 1.0, 0.0)
    assert scene.lights[0].direction == pytest.approx((-(0.5**0.5), -(0.5**0.5), 0.0), rel=1e-15)


def test_a_file_that_is_not_utf8_says_where(tmp_scene):
    path = tmp_scene("")
    path.write_bytes(GOOD.encode().replace(b"red", b"r\xffd", 1))
    with pytest.raises(SceneError) as info:
        tracer.load_scene(path)
    message = str(info.value)
    assert message.startswith(f"{path}: cannot read the scene file: "), message
    assert f"position {GOOD.index('red') + 1}" in message, message


def test_a_horn_torus_and_values_near_the_bound_load(tmp_scene):
    """The limits are where they say: a tube as wide as its ring (a horn torus, which touches
    itself at one point but does not pass through itself) loads, and so does a bright light
    whose image stays far inside float32."""
    horn = one_object('type = "torus"\ncenter = [0.0, 1.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n'
                      "major_radius = 0.5\nminor_radius = 0.5")  # fmt: skip
    assert tracer.load_scene(tmp_scene(horn)).objects[0].minor_radius == 0.5
    bright = GOOD.replace("position = [-3.0, 5.0, 4.0]", "position = [-3.0, 5.0, 4.0]\n"
                          "color = [1e15, 1.0, 1.0]", 1)  # fmt: skip
    assert tracer.load_scene(tmp_scene(bright)).lights[0].color[0] == 1e15


def test_errors_that_are_not_about_a_scene_are_not_scene_errors():
    """A variant this Mitsuba cannot run and a benchmark suite that does not exist are faults
    of the set-up or the command, with their own types."""
    import converters.mitsuba as cm
    from reference.bench import UnknownSuiteError, run_suites

    with pytest.raises(cm.MitsubaVariantError, match="'no_such_variant' is not in this build"):
        cm.use_variant("no_such_variant")
    with pytest.raises(UnknownSuiteError, match="unknown suite 'nope'") as info:
        run_suites(["nope"], None)
    assert not isinstance(info.value, SceneError)
    assert not issubclass(cm.MitsubaVariantError, SceneError)


@pytest.mark.parametrize("bad", [3, -1])
def test_the_core_refuses_a_face_that_names_a_missing_vertex(bad):
    """The scene reader refuses such faces first (above); the core checks again, for whoever
    calls it directly (tracer.rays, the study), and must not read past the vertex array."""
    import numpy as np

    from tracer import _core
    from tracer.render import to_core

    vertices = np.zeros((3, 3))
    good = np.array([[0, 1, 2]], dtype=np.int32)
    assert len(_core.mesh_hierarchy(vertices, good, 1)[1]) >= 1  # the same call, well formed
    faces = np.array([[0, 1, bad]], dtype=np.int32)
    with pytest.raises(IndexError, match="mesh face refers to a missing vertex"):
        _core.mesh_hierarchy(vertices, faces, 1)
    core = to_core(tracer.load_scene(scene_dict(objects=[sphere([0, 0, 0], 1)])))
    with pytest.raises(IndexError, match="mesh face refers to a missing vertex"):
        core.add_mesh(vertices, faces, None, "bvh", 0, 0)


def test_a_scene_dict_from_python_may_give_vectors_as_tuples():
    """TOML arrays arrive as lists; a Python user writes (0, 0, 0). Both mean a vector, and the
    scene is the same either way; a tuple of the wrong length is still named."""
    as_lists = tracer.load_scene(scene_dict(objects=[sphere([0, 1, 0], 1)]))
    with_tuples = scene_dict(objects=[sphere([0, 1, 0], 1)])
    with_tuples["objects"][0]["center"] = (0, 1, 0)
    with_tuples["camera"]["eye"] = tuple(with_tuples["camera"]["eye"])
    assert tracer.load_scene(with_tuples).objects == as_lists.objects
    assert tracer.load_scene(with_tuples).camera == as_lists.camera
    with_tuples["objects"][0]["center"] = (0, 1)
    with pytest.raises(SceneError, match=r"objects\[0\]\.center: expected an array of three"):
        tracer.load_scene(with_tuples)
