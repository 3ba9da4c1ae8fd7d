"""Scene checks (kinds (b) and (c) of issue 9's part 5): small scenes built to isolate one
concept, rendered with the student's extension (the one-ray tracer, never packets) in a child
process, and compared with

- POV-Ray's and Mitsuba's images, under the reference suite's own rule and tolerances
  (reference/metrics.py: ``agrees``, FLOAT32_SLACK on POV-Ray's per-pixel output precision,
  MITSUBA_TOLERANCE; MAX_SHARE_OVER of the pixels, scaled to the image's width as
  tests/reference/test_against_references.py argues for its 64-pixel images);
- analytic values of chosen pixels (closed forms written in the lesson's scenes module);
- (c) the ``aov`` output (what each primary ray hits, how far, with which normal) against
  Mitsuba's own ``aov`` integrator, with tests/reference/test_geometry_references.py's
  tolerances, and the ray counts (primary: one per pixel; shadow: one per light in front of
  each lit primary hit, counted from Mitsuba's hits).

A lesson's scene checks are data: ``lessons/Lnn_name/scenes/*.toml`` (scene files in the scene
language) and ``the lesson folder's scenes/__init__.py``, whose ``SCENES`` list names each
scene's concept, visibility, references and analytic values (lessons/README.md).

The references are rendered by POV-Ray and Mitsuba once and cached in ``reference_dir()``
(build/lesson-references, or $RTLAB_REFERENCES), keyed by the scene's text and the digest of the
converters' and runners' sources: a change to either renders them again. Never our own
solution's image: the reference is theirs.
"""

from __future__ import annotations

import fcntl
import hashlib
import importlib
import json
import math
import os
import secrets
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from lessons.catalog import get_lesson
from lessons.probe import HIDDEN, Vec
from lessons.sandbox import Build, Limits, run_limited

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

# The sources that turn a scene into a reference image: a change to any renders it again.
REFERENCE_SOURCES = (
    "converters/povray.py",
    "converters/mitsuba/*.py",
    "converters/pyrender.py",
    "reference/povray.py",
    "reference/mitsuba.py",
    "reference/geometry.py",
    "tracer/scene/*.py",
)
REFERENCE_NAMES = ("povray", "mitsuba")
# The reference suite's images are 160 pixels wide; silhouette pixels grow with an image's
# width, all pixels with its area, so at width w the same silhouettes are a 160 / w times
# larger share (the argument of tests/reference/test_against_references.py's scalar test).
REFERENCE_WIDTH = 160
# A child renders every scene of a check in a few tenths of a second; a student's loop that
# never ends is stopped after 20 s of CPU; 4 GiB of address space as render_in_child argues.
RENDER_LIMITS = Limits(cpu_s=20, wall_s=60.0, memory_bytes=4 << 30)


# Vector arithmetic in double for the closed forms of the lessons' scene modules
# (each lesson folder's scenes/__init__.py): their tolerances argue from double precision.
def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def unit(a: Vec) -> Vec:
    n = math.sqrt(dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


@dataclass(frozen=True)
class Analytic:
    """A value at one pixel (x right, y down, from 0) known in closed form: ``what`` is
    "color" (the classic render's RGB), "depth" (the distance along the primary ray) or
    "normal" (the aov's front-side normal); ``tolerance`` absolute, argued in ``why``."""

    x: int
    y: int
    what: str
    expected: tuple[float, ...]
    tolerance: float
    why: str


@dataclass(frozen=True)
class SceneCheck:
    lesson: str
    name: str  # the scene file's stem, unique in the lesson
    concept: str  # one of the lesson's concepts (lessons/catalog.py)
    title: str  # what the scene shows, as the student reads it
    visibility: str = "visible"  # or HIDDEN ("after_published")
    references: tuple[str, ...] = REFERENCE_NAMES
    aov: bool = True  # compare what is hit, where and with which normal with Mitsuba's aov
    rays: bool = True  # compare the ray counts with the ones Mitsuba's hits imply
    analytic: tuple[Analytic, ...] = ()
    hint: str = ""
    path: Path | None = None  # the scene file (default: the lesson's scenes/<name>.toml)
    size: tuple[int, int] | None = None  # (width, height) overriding the file's

    @property
    def scene_path(self) -> Path:
        if self.path is not None:
            return self.path
        return get_lesson(self.lesson).folder / "scenes" / f"{self.name}.toml"

    def load(self):  # noqa: ANN201 - a tracer.Scene
        import tracer

        scene = tracer.load_scene(self.scene_path)
        if self.size is not None:
            scene = scene.with_overrides(width=self.size[0], height=self.size[1])
        return scene


class SceneCheckError(ValueError):
    """A lesson's scenes module that names an unknown concept, a missing file, a bad value."""


def lesson_scenes(lesson: str) -> list[SceneCheck]:
    """The lesson's scene checks (``SCENES`` of the lesson folder's scenes/__init__.py), or []."""
    info = get_lesson(lesson)
    if not (info.folder / "scenes" / "__init__.py").exists():
        return []
    module = importlib.import_module(f"lessons.{info.id}_{info.name}.scenes")
    checks: list[SceneCheck] = list(module.SCENES)
    names = set()
    for check in checks:
        where = f"{info.folder.relative_to(ROOT)}/scenes/__init__.py: scene {check.name!r}"
        if check.lesson != lesson:
            raise SceneCheckError(f"{where}: lesson {check.lesson!r}, expected {lesson!r}")
        if check.concept not in info.concepts:
            raise SceneCheckError(
                f"{where}: unknown concept {check.concept!r}; expected one of "
                + "; ".join(info.concepts)
            )
        if check.visibility not in ("visible", HIDDEN):
            raise SceneCheckError(f"{where}: visibility {check.visibility!r}")
        if not check.scene_path.exists():
            raise SceneCheckError(f"{where}: no scene file {check.scene_path}")
        unknown = set(check.references) - set(REFERENCE_NAMES)
        if unknown:
            raise SceneCheckError(f"{where}: unknown references {sorted(unknown)}")
        if check.name in names:
            raise SceneCheckError(f"{where}: a second scene of that name")
        names.add(check.name)
    return checks


# --- the references: rendered by POV-Ray and Mitsuba once, cached -------------------------


def reference_dir() -> Path:
    return Path(os.environ.get("RTLAB_REFERENCES") or ROOT / "build" / "lesson-references")


def sources_digest() -> str:
    """The digest of the code a reference image depends on (REFERENCE_SOURCES)."""
    from tracer.batch import sources_digest as digest_of

    return digest_of(ROOT, REFERENCE_SOURCES)


def reference_key(check: SceneCheck) -> str:
    h = hashlib.sha256()
    h.update(check.scene_path.read_bytes())
    h.update(repr(check.size).encode())
    h.update(sources_digest().encode())
    return h.hexdigest()[:20]


def reference_file(check: SceneCheck) -> Path:
    return reference_dir() / check.lesson / f"{check.name}-{reference_key(check)}.npz"


def render_references(check: SceneCheck) -> dict[str, np.ndarray]:
    """POV-Ray's image and per-pixel bound, Mitsuba's image (llvm_ad_rgb, as the reference
    suite) and Mitsuba's aov (scalar_rgb: depth, object id, normal). A stereo pair's: each eye
    rendered alone (the converters take one eye: tracer.render.eye_scene), then laid out.
    A path-traced scene's: Mitsuba's path tracer's mean and variance (render_path_references)."""
    if isinstance(check, PathSceneCheck):
        return render_path_references(check)
    return _references_of(check.load())


# Where a two-eye stereo layout puts the right eye: beside the left (side_by_side), below it
# (over_under). An anaglyph mixes the eyes' colours: no layout of the references' arrays.
STEREO_AXIS = {"side_by_side": 1, "over_under": 0}


def _stereo_layout(scene: Any) -> str | None:
    st = scene.camera.stereo
    if st is None or st.layout in ("left", "right"):
        return None
    if st.layout not in STEREO_AXIS:
        raise SceneCheckError(
            f"{scene.source}: camera.stereo.layout {st.layout!r}: a scene check takes "
            f"{', '.join(STEREO_AXIS)}, left or right (the references render one eye at a time)"
        )
    return st.layout


def _references_of(scene: Any) -> dict[str, np.ndarray]:
    from reference.geometry import mitsuba_geometry
    from reference.mitsuba import run_mitsuba
    from reference.povray import run_povray
    from tracer.render import eye_scene

    layout = _stereo_layout(scene)
    if layout is not None:
        eyes = [_references_of(eye_scene(scene, eye)) for eye in ("left", "right")]
        axis = STEREO_AXIS[layout]
        return {k: np.concatenate([eyes[0][k], eyes[1][k]], axis=axis) for k in eyes[0]}
    pov = run_povray(scene, threads=2)
    out: dict[str, np.ndarray] = {"povray": pov.image, "povray_bound": pov.error_bound}
    geometry = mitsuba_geometry(scene)
    out["aov_depth"] = geometry.depth
    out["aov_id"] = geometry.object_id
    assert geometry.normal is not None
    out["aov_normal"] = geometry.normal
    out["mitsuba"] = run_mitsuba(scene, variant="llvm_ad_rgb", warm=False).image
    return out


def references(check: SceneCheck, render: bool = True) -> dict[str, np.ndarray]:
    """The cached references of a scene, rendered first where missing (``render``); the file
    is written atomically, so a half-written one is never read."""
    path = reference_file(check)
    if not path.exists():
        if not render:
            raise FileNotFoundError(
                f"{path}: no pre-rendered references for {check.lesson} {check.name}"
            )
        path.parent.mkdir(parents=True, exist_ok=True)
        # One process renders a scene's references; another that wants them meanwhile (the
        # suite's two workers) waits for its file rather than rendering them beside it.
        with open(path.with_name(f".{path.stem}.lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.exists():
                images = render_references(check)
                partial = path.with_name(f".{path.stem}.{os.getpid()}.{secrets.token_hex(4)}.npz")
                np.savez_compressed(partial, **images)
                os.replace(partial, path)
    with np.load(path, allow_pickle=False) as data:
        return {k: data[k] for k in data.files}


# --- the student's renders, in a child process ------------------------------------------

# Loads the built extension as tracer._core and, for each job from the first, renders the
# classic image (one ray at a time: packets=False, the student's code as written) and the aov,
# saving them with the ray counts; a line with the token before and after each, so that a
# crash is charged to the scene that was rendering. A stub called on the child's own thread
# (the camera's, set before the workers start) is a RuntimeError: it exits as a worker's does.
# The tracer package is the one in ROOT (the child's directory), never an editable install's:
# an unpacked autograder runs its own.
RENDER_CHILD = """
import importlib.util, json, sys
sys.meta_path[:] = [f for f in sys.meta_path if not type(f).__module__.startswith("_editable")]
import numpy as np
spec = importlib.util.spec_from_file_location("tracer._core", sys.argv[1])
core = importlib.util.module_from_spec(spec)
sys.modules["tracer._core"] = core
spec.loader.exec_module(core)
from tracer.render import render_with_stats
from tracer.scene import load_scene
jobs = json.loads(open(sys.argv[2]).read())
token = sys.argv[3]
for k in range(int(sys.argv[4]), len(jobs)):
    job = jobs[k]
    print(token, "begin", k, flush=True)
    scene = load_scene(job["scene"])
    if job["size"]:
        scene = scene.with_overrides(width=job["size"][0], height=job["size"][1])
    try:
        if job.get("seeds"):  # a path-traced scene: independent renders, one per seed
            runs = [render_with_stats(scene.with_overrides(seed=s), threads=2, progress=False,
                                      packets=False) for s in job["seeds"]]
            np.savez(job["out"], image=np.stack([r.image for r in runs]), aov=np.zeros(0),
                     rays=np.array(json.dumps(runs[0].rays)))
            print(token, "done", k, flush=True)
            continue
        result = render_with_stats(scene, threads=2, progress=False, packets=False)
        aov = render_with_stats(scene.with_overrides(integrator="aov"), threads=2, progress=False)
    except RuntimeError as error:  # a stub called on this thread (the camera's initialize)
        if not str(error).startswith("not implemented:"):
            raise
        print(error, flush=True)
        sys.exit(86)  # what a stub in a worker thread exits with (NOT_IMPLEMENTED_STATUS)
    np.savez(job["out"], image=result.image, aov=aov.image,
             rays=np.array(json.dumps(result.rays)))
    print(token, "done", k, flush=True)
"""


@dataclass
class Rendered:
    kind: str  # "ok", or the outcome's kind: not_implemented, crash, hang, memory, flood, ...
    message: str = ""
    image: npt.NDArray[np.float32] | None = None
    aov: npt.NDArray[np.float32] | None = None
    rays: dict[str, int] = field(default_factory=dict)


def render_student(build: Build, checks: list[SceneCheck], work: Path) -> list[Rendered]:
    """Render every check's scene with the built extension; a scene that crashed, hung or
    flooded is charged alone and the child starts again from the next one."""
    assert build.binary is not None
    work.mkdir(parents=True, exist_ok=True)
    jobs = [
        {
            "scene": str(c.scene_path),
            "size": c.size,
            "out": str(work / f"scene{k}.npz"),
            "seeds": path_seeds(c),
        }
        for k, c in enumerate(checks)
    ]
    job_file = work / "scenes.json"
    job_file.write_text(json.dumps(jobs))
    token = "@rtlab-" + secrets.token_hex(8)
    results: dict[int, Rendered] = {}
    first = 0
    while first < len(checks):
        command = [sys.executable, "-c", RENDER_CHILD, str(build.binary), str(job_file), token,
                   str(first)]  # fmt: skip
        outcome = run_limited(command, ROOT, RENDER_LIMITS, "the render")
        done, begun = set(), None
        for line in outcome.output.splitlines():
            words = line.split()
            if len(words) == 3 and words[0] == token and words[2].isdigit():
                if words[1] == "begin":
                    begun = int(words[2])
                elif words[1] == "done":
                    done.add(int(words[2]))
        for k in done:
            with np.load(jobs[k]["out"], allow_pickle=False) as data:
                results[k] = Rendered(
                    "ok", "", data["image"], data["aov"], json.loads(str(data["rays"]))
                )
        if outcome.ok:
            break
        if begun is None or begun in done:  # before the first scene (loading) or at exit
            for k in range(first, len(checks)):
                results.setdefault(k, Rendered(outcome.kind, _message(outcome)))
            break
        results[begun] = Rendered(outcome.kind, _message(outcome))
        first = begun + 1
    return [results.get(k, Rendered("not_run", "not run")) for k in range(len(checks))]


def _message(outcome: Any) -> str:
    if outcome.kind == "failed":  # a Python error in the child: its last line says which
        lines = [ln for ln in outcome.output.splitlines() if ln.strip()]
        return f"{outcome.message}: {lines[-1] if lines else ''}"
    return outcome.message


# --- the comparisons ---------------------------------------------------------------------


@dataclass
class Verdict:
    ok: bool
    lines: list[str]  # Markdown bullet lines, each one comparison
    heat_maps: dict[str, tuple[np.ndarray, np.ndarray]]  # name -> (reference, student image)
    # name -> the pixels that fail, where the check's rule is not per pixel (a path scene's
    # blocks); a per-pixel rule's failing pixels are those over its tolerance (the grader's).
    failing: dict[str, np.ndarray] = field(default_factory=dict)


def share_bound(width: int) -> float:
    from reference.metrics import MAX_SHARE_OVER

    return MAX_SHARE_OVER * max(1.0, REFERENCE_WIDTH / width)


def _rgb(v: np.ndarray) -> str:
    return "(" + ", ".join(f"{float(c):.4g}" for c in v) + ")"


def _where(mask: np.ndarray) -> str:
    ys, xs = np.nonzero(mask)
    return f"x {xs.min()}..{xs.max()}, y {ys.min()}..{ys.max()}"


def compare_image(
    name: str, reference: np.ndarray, ours: np.ndarray, tolerance: Any, share: float
) -> tuple[bool, str]:
    """The reference suite's rule (metrics.agrees), and where it fails: the share of pixels
    over tolerance, their bounding box, and the worst pixel's expected and got colours."""
    from reference.metrics import agrees, over_tolerance

    ok, text = agrees(reference, ours, tolerance, share)
    if ok:
        return True, f"against {name}: agrees ({text}; at most {100 * share:.3g}% allowed)"
    mask = over_tolerance(reference, ours, tolerance)
    diff = np.abs(np.asarray(reference, np.float64) - np.asarray(ours, np.float64)).max(-1)
    diff = np.where(np.isfinite(diff), diff, np.inf)
    y, x = np.unravel_index(int(np.argmax(diff)), diff.shape)
    where = f"; failing pixels in {_where(mask)}" if mask.any() else ""
    return False, (
        f"against {name}: **differs**: {text} (at most {100 * share:.3g}% may){where}; "
        f"worst pixel ({x}, {y}): expected {_rgb(reference[y, x])}, got {_rgb(ours[y, x])}"
    )


def compare_aov(refs: dict[str, np.ndarray], aov: np.ndarray, share: float) -> tuple[bool, str]:
    """What each primary ray hits, how far and with which normal, against Mitsuba's aov, with
    tests/reference/test_geometry_references.py's tolerances: other objects seen in at most
    the share of silhouette pixels; depth within 1e-4 relative (float32 intersection ~1e-6)
    and normals within 1e-3 rad (float32: 1e-6) for 99% of the pixels that see the same."""
    ids = np.rint(aov[..., 1]).astype(np.int64)
    depth = aov[..., 0].astype(np.float64)
    normal = aov[..., 2:5].astype(np.float64)
    their_ids = refs["aov_id"]
    differ = ids != their_ids
    problems = []
    if differ.mean() > share:
        y, x = np.argwhere(differ)[0]
        problems.append(
            f"{int(differ.sum())} pixels see another object than Mitsuba's primary rays "
            f"(in {_where(differ)}; e.g. pixel ({x}, {y}): object {ids[y, x]}, expected "
            f"{their_ids[y, x]}; -1 is nothing)"
        )
    both = ~differ & (ids >= 0)
    if both.any():
        rel = np.abs(depth[both] - refs["aov_depth"][both]) / refs["aov_depth"][both]
        rel = np.where(np.isfinite(rel), rel, np.inf)
        if (rel <= 1e-4).mean() < 0.99:
            problems.append(
                f"the hit's distance differs from Mitsuba's by more than 1e-4 (relative) in "
                f"{int((rel > 1e-4).sum())} pixels (worst {float(rel.max()):.3g})"
            )
        cos = np.sum(normal * refs["aov_normal"], axis=-1)[both]
        if (cos >= math.cos(1e-3)).mean() < 0.99:
            worst = math.degrees(math.acos(max(-1.0, min(1.0, float(np.nanmin(cos))))))
            problems.append(
                f"the normal differs from Mitsuba's by more than 1e-3 rad in "
                f"{int((cos < math.cos(1e-3)).sum())} pixels (worst {worst:.3g} degrees)"
            )
    if problems:
        return False, "what is hit (aov): **differs**: " + "; ".join(problems)
    return True, "what is hit (aov): the same objects, distances and normals as Mitsuba's"


def expected_rays(scene: Any, refs: dict[str, np.ndarray]) -> tuple[dict[str, int], int]:
    """Primary rays: one per pixel (spp = 1). Shadow rays, in a scene without mirrors: one per
    light in front of each primary hit whose material has a light term (10_classic.h's
    local_color()), counted from Mitsuba's hits and normals; hits where |N.L| < 1e-6 may go
    either way (float32 against double): the second value is their number, the slack."""
    from tracer.render import eye_scene
    from tracer.scene import PointLight

    layout = _stereo_layout(scene)
    if layout is not None:  # each eye's share of the references' arrays, counted alone
        axis, total, slack = STEREO_AXIS[layout], {}, 0
        for k, eye in enumerate(("left", "right")):
            part = {n: np.array_split(a, 2, axis=axis)[k] for n, a in refs.items()}
            counts, more = expected_rays(eye_scene(scene, eye), part)
            total = {n: total.get(n, 0) + v for n, v in counts.items()}
            slack += more
        return total, slack
    cam = scene.camera
    counts = {"primary": cam.width * cam.height * scene.render.spp}
    if any(m.reflectivity > 0 for m in scene.materials.values()) and scene.render.max_depth > 1:
        return counts, 0
    ids = refs["aov_id"]
    hit = ids >= 0
    depth = np.where(hit, refs["aov_depth"], 0.0)
    eye_at, look_at, shift = cam.one_eye() if cam.stereo is not None else (cam.eye, cam.look_at, 0)
    eye = np.array(eye_at, dtype=np.float64)
    # Primary directions through pixel centres (03_camera.h's primary_ray()); a stereo eye's
    # window shifted along right (stereo_eye()).
    forward = np.array(look_at) - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.array(cam.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    ph = 2 * math.tan(math.radians(cam.fov_y) / 2)
    pw = ph * cam.width / cam.height
    i, j = np.meshgrid(np.arange(cam.width) + 0.5, np.arange(cam.height) + 0.5)
    x, y = i / cam.width - 0.5, 0.5 - j / cam.height
    d = forward + (x * pw + shift)[..., None] * right + (y * ph)[..., None] * up
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    p = eye + depth[..., None] * d
    n = refs["aov_normal"].astype(np.float64)
    n = np.where(np.sum(n * d, axis=-1, keepdims=True) > 0, -n, n)  # facing the ray
    lit = np.zeros(ids.shape, dtype=bool)
    for k, obj in enumerate(scene.objects):
        m = scene.materials[obj.material]
        if m.diffuse != 0 or m.specular != 0:
            lit |= ids == k
    shadow, slack = 0, 0
    for light in scene.lights:
        if isinstance(light, PointLight):
            to = np.array(light.position) - p
            to /= np.linalg.norm(to, axis=-1, keepdims=True)
        else:
            to = np.broadcast_to(-np.array(light.direction), p.shape)
        nl = np.sum(n * to, axis=-1)
        shadow += int(np.sum(lit & hit & (nl > 0)))
        slack += int(np.sum(lit & hit & (np.abs(nl) < 1e-6)))
    counts["shadow"] = shadow
    return counts, slack


def compare_rays(scene: Any, refs: dict[str, np.ndarray], rays: dict[str, int]) -> tuple[bool, str]:
    want, slack = expected_rays(scene, refs)
    wrong = []
    for key, value in want.items():
        got = int(rays.get(key, 0))
        allowed = slack if key == "shadow" else 0
        if abs(got - value) > allowed:
            what = "one per pixel" if key == "primary" else "one per light in front of each hit"
            wrong.append(f"{key}: expected {value} ({what}), got {got}")
    if wrong:
        return False, "ray counts: **differ**: " + "; ".join(wrong)
    return True, "ray counts: " + ", ".join(f"{k} {rays.get(k, 0)}" for k in want) + " as expected"


def compare_analytic(value: Analytic, rendered: Rendered) -> tuple[bool, str]:
    assert rendered.image is not None and rendered.aov is not None
    if value.what == "color":
        got = rendered.image[value.y, value.x, :3]
    elif value.what == "depth":
        got = rendered.aov[value.y, value.x, :1]
    else:
        got = rendered.aov[value.y, value.x, 2:5]
    err = np.abs(np.asarray(got, np.float64) - np.asarray(value.expected))
    ok = bool(np.all(err <= value.tolerance))  # NaN fails
    text = (
        f"pixel ({value.x}, {value.y}) {value.what}: expected {_rgb(np.array(value.expected))} "
        f"(closed form: {value.why}), got {_rgb(got)}"
    )
    return ok, ("analytic: " if ok else "analytic: **differs**: ") + text


def judge(check: SceneCheck, rendered: Rendered, refs: dict[str, np.ndarray]) -> Verdict:
    """Every comparison of one scene: the references' images, the analytic values, the aov
    and the ray counts."""
    from reference.metrics import FLOAT32_SLACK, MITSUBA_TOLERANCE

    if isinstance(check, PathSceneCheck):
        return judge_path(check, rendered, refs)
    assert rendered.image is not None and rendered.aov is not None
    scene = check.load()
    share = share_bound(scene.camera.width)
    lines, heat, ok = [], {}, True
    ours = rendered.image
    for name in check.references:
        if name == "povray":
            good, text = compare_image(
                "POV-Ray", refs["povray"], ours, refs["povray_bound"] + FLOAT32_SLACK, share
            )
        else:
            good, text = compare_image("Mitsuba", refs["mitsuba"], ours, MITSUBA_TOLERANCE, share)
        if not good:
            heat[name] = (refs[name], ours)
        ok &= good
        lines.append(text)
    for value in check.analytic:
        good, text = compare_analytic(value, rendered)
        ok &= good
        lines.append(text)
    if check.aov:
        good, text = compare_aov(refs, rendered.aov, share)
        ok &= good
        lines.append(text)
    if check.rays:
        good, text = compare_rays(scene, refs, rendered.rays)
        ok &= good
        lines.append(text)
    return Verdict(ok, lines, heat)


def heat_map_path(directory: Path, check: SceneCheck, name: str) -> Path:
    return directory / f"{check.lesson}-{check.name}-{name}.png"


# --- path-traced scenes: a statistical comparison with Mitsuba's path tracer --------------
#
# A path-traced image is a Monte Carlo estimate: it cannot agree with Mitsuba's pixel by pixel
# under a fixed tolerance. The reference suite's argument (reference/stats.py,
# tests/reference/test_path_stats.py) carries over: Mitsuba's own path tracer at high spp gives
# each pixel's expected value and the variance of one sample; the student's tracer renders
# `replicates` independent images (other seeds) of `spp` samples; Mitsuba's per-pixel z-test
# (on their mean) catches a broken image, and the aggregate t-test over the replicates (the
# whole image's mean and blocks of pixels) catches a bias of a few percent that no one pixel's
# noise would show. POV-Ray has no path tracer of this estimator: it does not apply.


@dataclass(frozen=True)
class PathSceneCheck(SceneCheck):
    """A path-traced scene compared with Mitsuba's path tracer in the statistical sense.

    ``closed_form``: where every pixel's expected value is known exactly (a furnace), that
    value and why; the replicates are then also tested against it, with no reference noise."""

    references: tuple[str, ...] = ("mitsuba",)
    aov: bool = False  # a path scene's primary hits are the classic lessons' (L01-L03)
    rays: bool = False  # its ray counts are random (Russian roulette)
    replicates: int = 6  # as tests/reference/test_path_stats.py: t with 5 degrees of freedom
    reference_spp: int = 4096  # Mitsuba's, as the reference suite's (16 chunks of 256)
    # A correct submission whose code differs from the solution's (another sampling map, other
    # roundings) is a fresh random draw: it fails a scene with probability alpha. At the
    # suite's 1% a correct student would fail one of a lesson's four path scenes 4% of the
    # time; at 1e-3, 0.4%, while the known-wrong versions' biases (5% and more of the image's
    # mean, tens of its standard errors) are still caught (tests/lessons/test_grader.py).
    alpha: float = 1e-3
    block: int = 8  # pixels per block side: about 16 blocks in a 40 x 30 image, as the suite's
    closed_form: tuple[tuple[float, float, float], str] | None = None

    @property
    def seeds(self) -> list[int]:
        seed = self.load().render.seed
        return [seed + 1009 * k for k in range(self.replicates)]  # far apart: independent


def path_seeds(check: SceneCheck) -> list[int] | None:
    """The seeds of a path scene's independent renders (None for a classic scene)."""
    return check.seeds if isinstance(check, PathSceneCheck) else None


def render_path_references(check: PathSceneCheck) -> dict[str, np.ndarray]:
    """Mitsuba's path tracer at reference_spp: each pixel's mean and one sample's variance
    (reference.stats.mitsuba_reference, CHUNKS independent renders)."""
    from reference.stats import mitsuba_reference

    ref = mitsuba_reference(check.load(), check.reference_spp)
    return {
        "path_mean": ref.mean,
        "path_variance": ref.variance,
        "path_spp": np.array(ref.spp),
    }


def _failing_blocks(
    images: list[np.ndarray], mean: np.ndarray, ref_var: np.ndarray, block: int, alpha: float
) -> np.ndarray:
    """A pixel mask of the blocks whose mean differs from the reference's (the aggregate test's
    block t statistics, Sidak-corrected over the blocks, at alpha / 2)."""
    from scipy import stats

    h, w = mean.shape[:2]
    hb, wb = h // block, w // block
    diffs = np.stack([np.asarray(im, np.float64) - mean for im in images])  # (k, h, w, 3)
    k = len(images)
    cut = diffs[:, : hb * block, : wb * block]
    means = cut.reshape(k, hb, block, wb, block, 3).mean(axis=(2, 4))  # (k, hb, wb, 3)
    rv = ref_var[: hb * block, : wb * block].reshape(hb, block, wb, block, 3).mean(axis=(1, 3))
    se = np.sqrt(means.var(axis=0, ddof=1) / k + rv / block**2)
    t = means.mean(axis=0) / np.maximum(se, 1e-300)
    p = 2 * stats.t.sf(np.abs(t), df=k - 1)
    p_sidak = 1 - (1 - p) ** p.size
    bad = (p_sidak < alpha / 2).any(axis=-1)  # (hb, wb)
    mask = np.zeros((h, w), dtype=bool)
    for by, bx in np.argwhere(bad):
        mask[by * block : (by + 1) * block, bx * block : (bx + 1) * block] = True
    return mask


def _statistical(
    name: str,
    check: PathSceneCheck,
    images: list[np.ndarray],
    spp: int,
    mean: np.ndarray,
    variance: np.ndarray,
    ref_spp: int,
) -> tuple[bool, str, np.ndarray | None]:
    """The aggregate test (and, against a noisy reference, the per-pixel z-test of the
    replicates' mean) of one path scene, and where it fails: the line, and the mask of the
    failing blocks (None when it passes)."""
    from reference.stats import Reference, aggregate_test, pixel_test

    ref = Reference(mean, variance, ref_spp)
    agg = aggregate_test(images, ref, alpha=check.alpha, block=check.block)
    ours = np.mean(images, axis=0)
    bias = float(agg.detail["relative_bias"])
    text = (
        f"mean {100 * bias:+.2g}% off (p = {agg.detail['p_whole']:.2g} for the whole image, "
        f"{agg.detail['p_block']:.2g} for the worst of {agg.detail['blocks']} blocks; "
        f"fails below {check.alpha / 2:g})"
    )
    ok = agg.passed
    if np.any(variance > 0):  # a noisy reference (Mitsuba's), not a closed form
        # One sample's variance from both estimates, the larger: 16 chunks underestimate it
        # where a few rare, bright samples carry the mean (a glossy floor's reflection of a
        # small light), and 5 pixels of glossy_mis then had z > 5 on the solution's renders.
        ours_var = np.var(images, axis=0, ddof=1) * spp
        both = Reference(mean, np.maximum(variance, ours_var), ref_spp)
        pix = pixel_test(ours, spp * len(images), both, alpha=check.alpha)
        text += f"; {100 * pix.statistic:.4g}% of the pixels pass the z-test (at least 99.75%)"
        ok &= pix.passed
    if ok:
        return True, f"against {name}: agrees in the statistical sense ({text})", None
    mask = _failing_blocks(images, mean, variance / ref_spp, check.block, check.alpha)
    if not mask.any():  # a bias spread over the whole image: every block a little
        mask = np.ones(mean.shape[:2], dtype=bool)
    diff = np.abs(ours - mean).max(-1)
    diff = np.where(mask, np.where(np.isfinite(diff), diff, np.inf), -1)
    y, x = np.unravel_index(int(np.argmax(diff)), diff.shape)
    line = (
        f"against {name}: **differs**: {text}; failing pixels in {_where(mask)}; "
        f"worst pixel ({x}, {y}): expected {_rgb(mean[y, x])}, got {_rgb(ours[y, x])} "
        f"(the mean of {len(images)} renders of {spp} samples)"
    )
    return False, line, mask


def judge_path(check: PathSceneCheck, rendered: Rendered, refs: dict[str, np.ndarray]) -> Verdict:
    """A path scene: the student's independent renders against Mitsuba's path tracer, and
    against the closed form where there is one."""
    assert rendered.image is not None
    images = [np.asarray(im, np.float64)[..., :3] for im in rendered.image]
    spp = check.load().render.spp
    ours = np.mean(images, axis=0).astype(np.float32)
    lines, heat, failing, ok = [], {}, {}, True
    if "mitsuba" in check.references:
        mean = refs["path_mean"]
        good, text, mask = _statistical(
            "Mitsuba's path tracer", check, images, spp, mean, refs["path_variance"],
            int(refs["path_spp"]),
        )  # fmt: skip
        if not good:
            heat["mitsuba"] = (mean.astype(np.float32), ours)
            failing["mitsuba"] = mask
        ok &= good
        lines.append(text)
    if check.closed_form is not None:
        value, why = check.closed_form
        exact = np.broadcast_to(np.asarray(value, np.float64), images[0].shape)
        good, text, mask = _statistical(
            "the closed form", check, images, spp, exact, np.zeros_like(exact), 1
        )  # no reference noise: variance 0
        text = text.replace("against the closed form", f"against the closed form ({why})")
        if not good and "mitsuba" not in heat:
            heat["closed_form"] = (exact.astype(np.float32), ours)
            failing["closed_form"] = mask
        ok &= good
        lines.append(text)
    return Verdict(ok, lines, heat, failing)
