"""``rtlab lesson autograder Lnn --out autograder.zip``: the zip Gradescope takes.

Gradescope's autograder specification (gradescope-autograders.readthedocs.io, "Autograder
Specifications"): the zip holds ``setup.sh`` and ``run_autograder`` at its root and is unpacked
into ``/autograder/source``; ``setup.sh`` runs once, as root, when the image is built (Ubuntu);
for each submission ``run_autograder`` runs with the student's files in
``/autograder/submission`` and must write ``/autograder/results/results.json``.

What goes in: the rtlab sources the grader needs (tracer/ with the C++ core, lessons/, and
reference/ and converters/, whose sources key the references), ``requirements.txt``, and the
references of every scene the lesson's checks and the integration check render, pre-rendered
here by POV-Ray and Mitsuba (``references/``), so that neither runs on Gradescope. ``setup.sh``
installs Python, a compiler and the requirements, then builds the solution's extension (the
grader's own scene loading imports tracer) without CMake, as the sandbox builds a student's.

``RTLAB_AUTOGRADER_ROOT`` (default /autograder) moves the whole layout, so that a test can run
it in a temporary directory; ``RTLAB_PYTHON`` names the Python (default the one setup.sh made).
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
# The sources the grader imports or builds, and those the references' digest covers.
SOURCES = ("tracer", "lessons", "reference", "converters")
SKIP = ("__pycache__", ".so", ".pyc", ".o")
REQUIREMENTS = """\
# The grader's run time on Gradescope (POV-Ray and Mitsuba are not needed: the references are
# pre-rendered in references/; scipy for the path-traced scenes' statistical tests).
numpy>=1.24
scipy>=1.10
nanobind>=2.0
openexr>=3.2
pillow>=10
tqdm>=4.60
matplotlib>=3.7
"""

SETUP_SH = """\
#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder's image.
set -euo pipefail
ROOT="${RTLAB_AUTOGRADER_ROOT:-/autograder}"
SOURCE="$ROOT/source"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq g++ make python3.11 python3.11-venv \\
  python3.11-dev >/dev/null
python3.11 -m venv "$ROOT/venv"
"$ROOT/venv/bin/pip" install -q -r "$SOURCE/requirements.txt"
cd "$SOURCE" && "$ROOT/venv/bin/python" lessons/autograder.py setup
"""

RUN_AUTOGRADER = """\
#!/usr/bin/env bash
# Gradescope runs this for each submission: the student's files are in $ROOT/submission, the
# grade goes to $ROOT/results/results.json (written whatever happens).
set -uo pipefail
ROOT="${{RTLAB_AUTOGRADER_ROOT:-/autograder}}"
SOURCE="$ROOT/source"
PY="${{RTLAB_PYTHON:-$ROOT/venv/bin/python}}"
mkdir -p "$ROOT/results"
cd "$SOURCE"
RTLAB_REFERENCES="$SOURCE/references" RTLAB_REFERENCES_ONLY=1 \\
  "$PY" lessons/autograder.py run {lesson} "$ROOT/submission" "$ROOT/results/results.json"
"""


def _isolate() -> None:
    """Import the grader's sources from the directory they were unpacked in, never from an
    editable install of rtlab that a development machine's Python carries (its import hook
    would take precedence over the current directory)."""
    sys.meta_path[:] = [f for f in sys.meta_path if not type(f).__module__.startswith("_editable")]
    sys.path.insert(0, str(ROOT))
    for name in [m for m in sys.modules if m.split(".")[0] in ("tracer", "lessons")]:
        del sys.modules[name]


def build_solution_extension() -> Path:
    """tracer/_core built from the solution (the grader's own scene loading imports tracer),
    with the sandbox's CMake-free build."""
    from lessons.sandbox import build_extension
    from lessons.student import CORE

    with tempfile.TemporaryDirectory(prefix="rtlab-setup-") as tmp:
        build = build_extension(CORE, Path(tmp), optimisation="-O2")
        if build.binary is None:
            raise SystemExit(f"rtlab: the solution does not build: {build.outcome.message}")
        target = ROOT / "tracer" / build.binary.name
        shutil.copyfile(build.binary, target)
    return target


def run(lesson: str, submission: Path, results: Path) -> int:
    """Grade, write results.json; a grader that fails still writes one that says so."""
    import json

    try:
        from lessons.grader import grade

        grade(submission, lesson=lesson).write(results)
    except Exception as error:  # the grader's fault: the student sees it, never a blank
        results.parent.mkdir(parents=True, exist_ok=True)
        text = f"{lesson}: the grader failed: {error!r} (tell your instructor)"
        results.write_text(json.dumps({"score": 0, "output": text, "tests": []}) + "\n")
        return 1
    return 0


def _add_tree(archive: zipfile.ZipFile, folder: Path, arcname: str) -> None:
    for path in sorted(folder.rglob("*")):
        if path.is_file() and not any(s in path.name or s in path.parts for s in SKIP):
            archive.write(path, f"{arcname}/{path.relative_to(folder)}")


def build_zip(lesson: str, out: Path) -> list[str]:
    """Write the autograder zip for `lesson` to `out`, atomically (a temporary file beside it,
    renamed); the references are rendered first where the cache lacks them. Returns the
    references' names."""
    from lessons.catalog import get_lesson
    from lessons.grader import INTEGRATION_SCENE, NoChecksError, lessons_with_checks
    from lessons.scene_checks import lesson_scenes, reference_dir, reference_file, references

    info = get_lesson(lesson)
    if lesson not in lessons_with_checks():
        raise NoChecksError(f"{lesson}: no checks yet: nothing to grade on Gradescope")
    checks = [*lesson_scenes(lesson), INTEGRATION_SCENE]
    for check in checks:
        references(check)  # rendered by POV-Ray and Mitsuba here, once (cached)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fd, partial = tempfile.mkstemp(prefix=f".{out.name}.", dir=out.parent)
    os.close(fd)
    names = []
    try:
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as archive:
            for name, text in (
                ("setup.sh", SETUP_SH),
                ("run_autograder", RUN_AUTOGRADER.format(lesson=info.id)),
            ):
                script = zipfile.ZipInfo(name)
                script.external_attr = 0o755 << 16  # executable, as Gradescope runs them
                script.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(script, text)
            archive.writestr(zipfile.ZipInfo("requirements.txt"), REQUIREMENTS)
            for name in SOURCES:
                _add_tree(archive, ROOT / name, name)
            for check in checks:
                path = reference_file(check)
                arc = f"references/{path.relative_to(reference_dir())}"
                archive.write(path, arc)
                names.append(arc)
        os.chmod(partial, 0o644)  # mkstemp's 0600 is for the half-written file only
        os.replace(partial, out)
    except BaseException:
        Path(partial).unlink(missing_ok=True)
        raise
    return names


def main(argv: list[str]) -> int:
    _isolate()
    if argv[:1] == ["setup"]:
        print(f"rtlab: built {build_solution_extension()}")
        return 0
    if argv[:1] == ["run"] and len(argv) == 4:
        return run(argv[1], Path(argv[2]), Path(argv[3]))
    print("usage: lessons/autograder.py setup | run Lnn SUBMISSION RESULTS", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
