"""Every header of tracer/cpp/ stands alone: it compiles on its own with the project's warning
flags (so a lesson can hand out any one file), it includes the project headers whose names it
uses and no others, and its comments name files and functions that exist. Shared constants
live in constants.h only."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from tests.helpers import ROOT

CPP = ROOT / "tracer" / "cpp"
HEADERS = sorted(CPP.glob("*.h"))
SOURCES = [*HEADERS, CPP / "bindings.cpp"]

# The warning and floating-point flags of CMakeLists.txt's target_compile_options (without -O3
# and -march=native, which change no diagnostic here), plus -Werror: a warning fails the test.
FLAGS = [
    "-std=c++17",
    "-fsyntax-only",
    "-Wall",
    "-Wextra",
    "-Werror",
    "-ffp-contract=off",
    "-fno-math-errno",
    "-Wno-psabi",
]


def compile_alone(directory: Path, header: str, tmp_path: Path) -> subprocess.CompletedProcess:
    """Compile a file that includes just `header` of `directory`."""
    source = tmp_path / f"only_{Path(header).stem}.cpp"
    source.write_text(f'#include "{header}"\n')
    return subprocess.run(
        ["c++", *FLAGS, f"-I{directory}", str(source)], capture_output=True, text=True
    )


@pytest.mark.parametrize("header", HEADERS, ids=[h.name for h in HEADERS])
def test_header_compiles_alone(header, tmp_path):
    result = compile_alone(CPP, header.name, tmp_path)
    assert result.returncode == 0, f"{header.name} does not compile alone:\n{result.stderr}"


def test_a_header_missing_an_include_does_not_compile_alone(tmp_path):
    """The test above can fail: drop the include that brings reflect() and Rng into 20_path.h
    (the bug this issue found) and the header must no longer compile on its own."""
    broken = tmp_path / "cpp"
    shutil.copytree(CPP, broken)
    path = broken / "20_path.h"
    text = path.read_text()
    injected = text.replace('#include "10_classic.h"\n', "").replace('#include "11_render.h"\n', "")
    assert injected != text, "the injection found nothing to remove"
    path.write_text(injected)
    result = compile_alone(broken, "20_path.h", tmp_path)
    assert result.returncode != 0
    assert "Rng" in result.stderr or "reflect" in result.stderr


def code_of(text: str) -> str:
    """The text without comments and string literals (so a word in a comment is not a use)."""
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return re.sub(r'"(?:\\.|[^"\\])*"', '""', text)


def comments_of(text: str) -> str:
    return "\n".join(re.findall(r"//([^\n]*)", text))


# Names a header declares at namespace scope (the files put them at the start of a line).
DECLARATION = re.compile(
    r"^(?:struct|class|enum class|enum)\s+(\w+)"
    r"|^(?:inline |static )?constexpr\s+[\w:<>]+\s+(\w+)\s*[={]"
    r"|^typedef\b[^;]*?\b(\w+)\s*(?:__attribute__|;)"
    r"|^using\s+(\w+)\s*="
    # (an attribute may come first: [[gnu::always_inline]] inline ...)
    r"|^(?:template\s*<[^>]*>\s*)?(?:\[\[[^\]]*\]\]\s*)?inline\s+(?:const\s+)?[\w:<>]+[\s&*]+(\w+)\s*\(",
    re.M,
)


def declared(path: Path) -> set[str]:
    names = set()
    for match in DECLARATION.finditer(code_of(path.read_text())):
        names.update(g for g in match.groups() if g)
    return names


def project_includes(path: Path) -> list[str]:
    return re.findall(r'^#include "([^"]+)"', path.read_text(), re.M)


def words(path: Path) -> set[str]:
    """The identifiers a file's code uses, less the standard library's (std::sqrt is not
    12_packet.h's sqrt) and members reached through . or -> (a member `count` is not count())."""
    code = re.sub(r"(?:std::|\.|->)\s*\w+", " ", code_of(path.read_text()))
    return set(re.findall(r"\b[A-Za-z_]\w*\b", code))


DECLARES = {h.name: declared(h) for h in HEADERS}


def test_the_declaration_scanner_sees_what_the_headers_declare():
    """So the include checks below are not vacuous."""
    assert {"Vec3", "Color", "dot", "normalize"} <= DECLARES["01_vec3.h"]
    assert {"infinity", "pi"} <= DECLARES["constants.h"]
    assert {"Lanes", "Mask", "rays_per_packet", "power"} <= DECLARES["power.h"]
    assert {"Facing", "face_the_ray", "secondary_ray", "shadow_ray_to"} <= DECLARES["04_hit.h"]
    assert {"pixel_rng", "for_each_sample", "Rng", "tile_size"} <= DECLARES["11_render.h"]


@pytest.mark.parametrize("source", SOURCES, ids=[s.name for s in SOURCES])
def test_includes_only_headers_it_uses(source):
    """Nothing else: every project header a file includes declares a name the file uses."""
    used = words(source)
    unused = [h for h in project_includes(source) if not DECLARES[h] & used]
    assert not unused, f"{source.name} includes {unused} without using anything they declare"


# Names declared in more than one header (the packet tracer's overloads share the one-ray
# names), or used as plain local names elsewhere, say nothing about which header a file needs.
OVERLOADED = {
    name
    for name in set().union(*DECLARES.values())
    if sum(name in d for d in DECLARES.values()) > 1
}
# 16_mesh.h's `any` flag, 11_render.h's `tile` size, 02_ray.h's `bits` of a double.
LOCAL_NAMES = {"any", "count", "tile", "bits"}


@pytest.mark.parametrize("source", SOURCES, ids=[s.name for s in SOURCES])
def test_includes_what_it_uses(source):
    """Every project name a file uses is declared in the file itself or in a header it includes
    directly (not one that happens to come along through another include)."""
    own = declared(source) if source.suffix == ".h" else set()
    reachable = own.union(*(DECLARES[h] for h in project_includes(source)))
    missing = {}
    for header, names in DECLARES.items():
        if header == source.name:
            continue
        for name in (names & words(source)) - reachable - OVERLOADED - LOCAL_NAMES:
            missing.setdefault(header, []).append(name)
    assert not missing, f"{source.name} uses names of headers it does not include: {missing}"


def test_the_include_checks_can_fail(tmp_path):
    """Drop 01_vec3.h from 06_plane.h, which uses Vec3: the check above must name it."""
    text = (CPP / "06_plane.h").read_text()
    assert '#include "01_vec3.h"\n' in text and "Vec3" in code_of(text)
    reachable = set().union(
        *(DECLARES[h] for h in project_includes(CPP / "06_plane.h") if h != "01_vec3.h")
    )
    assert "Vec3" not in reachable  # so 06_plane.h without the include would fail the check


def test_constants_are_defined_once():
    for source in SOURCES:
        code = code_of(source.read_text())
        assert "M_PI" not in code, f"{source.name} uses M_PI (use rt::pi, constants.h)"
        if source.name != "constants.h":
            for name in ("infinity", "pi"):
                assert not re.search(rf"\b{name}\s*=", code), f"{source.name} defines {name}"


FILE_NAME = re.compile(r"(?<![\w/.-])((?:[\w-]+/)*[\w-]+\.(?:h|cpp|py|md|toml|txt))\b")


def named_files(source: Path) -> list[str]:
    return FILE_NAME.findall(comments_of(source.read_text()))


def test_the_file_name_scanner_finds_names():
    assert "05_sphere.h" in named_files(CPP / "01_vec3.h")
    assert "tests/tracer/test_packet.py" in named_files(CPP / "12_packet.h")


@pytest.mark.parametrize("source", SOURCES, ids=[s.name for s in SOURCES])
def test_comments_name_files_that_exist(source):
    """A comment that names a file (a header, a test, a Python module) names one that exists,
    inside the repository."""
    text = comments_of(source.read_text())
    missing = [n for n in named_files(source) if not (CPP / n).exists() and not (ROOT / n).exists()]
    assert not missing, f"{source.name}: comments name files that do not exist: {missing}"
    outside = re.findall(r"(?:\.\./|~/|(?<![\w.])/(?:work|home|usr|tmp)/)\S*", text)
    assert not outside, f"{source.name}: comments point outside the repository: {outside}"


DEFINED_FUNCTIONS = {
    m for s in SOURCES for m in re.findall(r"\b(\w+)\s*\([^;{)]*\)[^;{]*\{", code_of(s.read_text()))
} | {  # the Python side's functions (bindings.cpp names the caller)
    m
    for s in (ROOT / "tracer").glob("*.py")
    for m in re.findall(r"^def (\w+)", s.read_text(), re.M)
}
# Functions of the C++ standard library that comments compare with (std::pow, std::min, ...).
STANDARD_FUNCTIONS = {"pow", "min", "max", "sqrt", "nextafter"}


@pytest.mark.parametrize("source", SOURCES, ids=[s.name for s in SOURCES])
def test_comments_name_functions_that_exist(source):
    """A comment that names a function `f()` of the core (as in "sphere_hit() below" or
    "11_render.h for_each_sample()") names one the core defines."""
    text = comments_of(source.read_text())
    named = set(re.findall(r"\b([a-z_][a-z0-9_]*)\(\)", text))
    missing = sorted(named - DEFINED_FUNCTIONS - STANDARD_FUNCTIONS)
    assert not missing, f"{source.name}: comments name functions that do not exist: {missing}"
    for header, name in re.findall(r"\b(\d\d_\w+\.h) ([a-z_]\w*)\(\)", text):
        assert name in code_of((CPP / header).read_text()), f"{name}() is not in {header}"


# The width ruff holds the Python to (pyproject.toml line-length): a lesson's file is read
# side by side with its slide, and a student's editor wraps longer lines.
WIDTH = 100


def _long_lines(text: str) -> list[int]:
    return [n for n, line in enumerate(text.splitlines(), 1) if len(line) > WIDTH]


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.name)
def test_lines_fit_the_width(source):
    assert _long_lines(source.read_text()) == [], f"{source.name}: lines over {WIDTH} columns"


def test_the_width_check_can_fail():
    assert _long_lines("short\n" + "x" * (WIDTH + 1) + "\n" + "y" * WIDTH) == [2]
