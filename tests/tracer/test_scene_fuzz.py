"""The scene reader under random edits of every canonical scene (Hypothesis).

Each example takes one canonical scene (reference/scenes/*.toml, tracer/scenes/*.toml), applies
one to three random edits to its tables (keys dropped, renamed, added; values retyped; numbers
made NaN, inf, negative, huge, tiny or zero; arrays shortened or lengthened; tables nested
wrongly), writes it back as TOML, sometimes breaks the bytes (not UTF-8, cut short), and loads
the file. The property: it loads, or it raises a ``SceneError`` whose message starts with the
file's name and a key path that starts at a key of the document, and says what was expected (or,
for a file that is not UTF-8 or not TOML, says where in the file). Never any other exception.
A scene that loads renders a tiny image with no NaN and no inf.

The suite tries ``RTLAB_FUZZ_EXAMPLES`` examples per scene (100 by default, the same every run:
about half a second per scene); a long session sets it higher and draws fresh examples:
``RTLAB_FUZZ_EXAMPLES=20000 pytest -s tests/tracer/test_scene_fuzz.py`` tries about 400,000 cases
in about 30 minutes on one core. It prints how many cases each scene tried, loaded, rendered and
refused, and appends them as JSON lines to the file ``RTLAB_FUZZ_LOG`` names, when set (under
pytest-xdist only the log shows).
"""

from __future__ import annotations

import copy
import datetime
import json
import math
import os
import re
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.helpers import ROOT
from tracer.render import render
from tracer.scene import SceneError, load_scene

SCENES = sorted((ROOT / "reference" / "scenes").glob("*.toml")) + sorted(
    (ROOT / "tracer" / "scenes").glob("*.toml")
)
EXAMPLES = int(os.environ.get("RTLAB_FUZZ_EXAMPLES", "100"))
# The suite's short run is derandomised (the same examples every run, so CI is reproducible);
# a long session (RTLAB_FUZZ_EXAMPLES set) draws fresh examples each time.
DERANDOMIZE = "RTLAB_FUZZ_EXAMPLES" not in os.environ

#: Numbers at the edges: not numbers, infinite, negative, zero, denormal-small, near float32's
#: and float64's largest, and integers past 64 bits and past a double's range.
SPECIAL_NUMBERS = [math.nan, math.inf, -math.inf, -1, -1.0, -1e-300, 0, 0.0, -0.0, 1e-300,
                   5e-324, 1e-45, 3.5e38, -3.5e38, 1e299, -1e299, 1.7976931348623157e308,
                   2**63, 2**64, -(2**63) - 1, 10**30, 10**400, 1, 2, 0.5]  # fmt: skip

#: Any value TOML can hold: what a retyped key may become.
SCALARS = st.one_of(
    st.booleans(),
    st.integers(),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(SPECIAL_NUMBERS),
    st.text(max_size=12),
    st.datetimes(timezones=st.none() | st.just(datetime.UTC)),
    st.dates(),
    st.times(),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=3)
    ),
    max_leaves=6,
)


# --------------------------------------------------------------------------- TOML out


def _toml_key(key: str) -> str:
    return _toml_string(key)


def _toml_string(text: str) -> str:
    # JSON's escapes are TOML's basic-string escapes, but for DEL, which TOML wants escaped.
    return json.dumps(text, ensure_ascii=False).replace("\x7f", "\\u007f")


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, datetime.datetime | datetime.date | datetime.time):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        items = ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items())
        return "{" + items + "}"
    raise TypeError(f"not a TOML value: {value!r}")


def toml_dumps(data: dict[str, Any]) -> str:
    """The document as TOML: every table inline, so any nesting can be written."""
    return "".join(f"{_toml_key(k)} = {_toml_value(v)}\n" for k, v in data.items())


def test_toml_dumps_round_trips_every_canonical_scene():
    """The fuzzer's writer is faithful: what it writes reads back equal (NaN aside)."""
    for path in SCENES:
        data = tomllib.loads(path.read_text())
        assert tomllib.loads(toml_dumps(data)) == data, path


# --------------------------------------------------------------------------- edits


def _places(node: Any, path: tuple = ()) -> list[tuple]:
    """Every (container path, key or index) in the document."""
    out = []
    if isinstance(node, dict):
        for k, v in node.items():
            out.append((path, k))
            out += _places(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out.append((path, i))
            out += _places(v, (*path, i))
    return out


def _at(doc: Any, path: tuple) -> Any:
    for k in path:
        doc = doc[k]
    return doc


def _near_miss(key: str, draw: Any) -> str:
    choices = [key + "s", key[:-1], key.upper(), key.replace("_", "-"), " " + key, key * 2]
    if len(key) > 1:
        choices.append(key[1] + key[0] + key[2:])
    return draw(st.sampled_from(choices) | st.text(max_size=10))


def edit(doc: dict[str, Any], draw: Any) -> str:
    """One random edit of the document, in place; returns what it did (for the failure note)."""
    places = _places(doc)
    container_path, key = draw(st.sampled_from(places)) if places else ((), None)
    parent = _at(doc, container_path)
    op = draw(
        st.sampled_from(
            ["drop", "rename", "retype", "number", "shorten", "lengthen", "nest", "add", "type"]
        )
    )
    where = ".".join(map(str, (*container_path, key)))
    if key is None:
        op = "add"
    if op == "drop":
        del parent[key]
    elif op == "rename" and isinstance(parent, dict):
        new = _near_miss(key, draw)
        parent[new] = parent.pop(key)
        where += f" -> {new!r}"
    elif op == "retype":
        parent[key] = draw(VALUES)
    elif op == "number":
        parent[key] = draw(st.sampled_from(SPECIAL_NUMBERS) | st.floats() | st.integers())
    elif op == "shorten" and isinstance(parent[key], list) and parent[key]:
        parent[key] = parent[key][: draw(st.integers(0, len(parent[key]) - 1))]
    elif op == "lengthen" and isinstance(parent[key], list):
        parent[key] = [*parent[key], draw(VALUES)]
    elif op == "nest":
        value = parent[key]
        parent[key] = draw(
            st.sampled_from([{"type": value}, [value], {str(key): value}, [[value]]])
        )
    elif op == "type":  # the table's `type` given as something that is not a name
        target = parent[key] if isinstance(parent[key], dict) else parent
        if isinstance(target, dict):
            target["type"] = draw(VALUES)
    else:  # add: a key nobody asked for, or a value where one is expected
        target = parent[key] if key is not None and isinstance(parent[key], dict) else parent
        if isinstance(target, dict):
            target[draw(st.text(max_size=8))] = draw(VALUES)
        elif isinstance(target, list):
            target.append(draw(VALUES))
    return f"{op} {where}"


def break_bytes(raw: bytes, draw: Any) -> tuple[bytes, str]:
    """Sometimes: bytes that are not UTF-8, or the file cut short."""
    how = draw(st.sampled_from(["keep"] * 6 + ["not-utf8", "cut"]))
    if how == "not-utf8":
        at = draw(st.integers(0, len(raw)))
        bad = draw(st.sampled_from([b"\xff", b"\xfe\xff", b"\xc3", b"\xed\xa0\x80", b"\x80"]))
        return raw[:at] + bad + raw[at:], f"not-utf8 at byte {at}"
    if how == "cut":
        at = draw(st.integers(0, len(raw)))
        return raw[:at], f"cut at byte {at}"
    return raw, ""


# --------------------------------------------------------------------------- the property

#: Errors about the whole file rather than a key: it is not UTF-8, or not TOML.
FILE_LEVEL = ("cannot read the scene file", "invalid TOML")


#: Every message says what was wrong in one of these words.
SAYS_WHAT_WAS_EXPECTED = ("expected", "missing", "unknown", "must", "cannot", "could make")


def _first_segment(key: str) -> str:
    """The top-level key a key path starts with (``objects[2].radius`` -> ``objects``; a quoted
    key, ``"dark red".color``, unquoted)."""
    if key.startswith('"'):
        return json.JSONDecoder().raw_decode(key)[0]
    return re.split(r"[.\[]", key, maxsplit=1)[0]


class Tally:
    def __init__(self) -> None:
        self.tried = self.loaded = self.refused = self.rendered = 0


@pytest.fixture(scope="module")
def tallies(request):
    found: dict[str, Tally] = {}
    yield found
    lines = [f"{n}: {t.tried} cases, {t.loaded} loaded ({t.rendered} rendered), {t.refused} "
             "refused" for n, t in found.items()]  # fmt: skip
    total = sum(t.tried for t in found.values())
    capture = request.config.pluginmanager.getplugin("capturemanager")
    with capture.global_and_fixture_disabled():
        print(f"\nscene reader fuzz: {total} cases over {len(found)} scenes", *lines, sep="\n  ")
    log = os.environ.get("RTLAB_FUZZ_LOG")
    if log:
        with open(log, "a") as f:
            for name, t in found.items():
                f.write(json.dumps({"scene": name, **vars(t)}) + "\n")


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@pytest.mark.parametrize("scene_path", SCENES, ids=lambda p: f"{p.parent.parent.name}/{p.stem}")
def test_edited_scenes_load_or_raise_a_scene_error(scene_path: Path, tallies, fuzz_dir):
    original = tomllib.loads(scene_path.read_text())
    tally = tallies.setdefault(f"{scene_path.parent.parent.name}/{scene_path.stem}", Tally())
    path = fuzz_dir / f"{scene_path.stem}.toml"

    @settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=DERANDOMIZE,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])  # fmt: skip
    @given(st.data())
    def check(data: st.DataObject) -> None:
        doc = copy.deepcopy(original)
        done = [edit(doc, data.draw) for _ in range(data.draw(st.integers(1, 3)))]
        raw, broke = break_bytes(toml_dumps(doc).encode(), data.draw)
        path.write_bytes(raw)
        tally.tried += 1
        try:
            scene = load_scene(path)
        except SceneError as err:
            tally.refused += 1
            message = str(err)
            context = f"{done} {broke}: {message}"
            assert message.startswith(f"{path}: "), context
            if err.key:
                assert message.startswith(f"{path}: {err.key}: "), context
                # the key is a place in this document (or the [camera] it lacks)
                assert _first_segment(err.key) in {*doc, "camera"}, context
                assert any(w in message for w in SAYS_WHAT_WAS_EXPECTED), context
            else:
                assert message.startswith(tuple(f"{path}: {w}" for w in FILE_LEVEL)), context
                # where in the file: TOML's "at line 3, column 7" or "at end of document", or
                # the undecodable byte's "position 12"
                assert any(w in message for w in ("line", "end of document", "position")), context
        else:
            tally.loaded += 1
            if scene.render.integrator != "aov":  # depth, id and normal: no light to overflow
                # What loads renders: a tiny image of it has no inf (a value the reader let
                # through that overflows float32) and no NaN.
                image = render(scene.with_overrides(width=8, height=6, spp=1), threads=1,
                               progress=False)  # fmt: skip
                assert np.all(np.isfinite(image)), f"{done}: {np.sum(~np.isfinite(image))} pixels"
                tally.rendered += 1

    check()
    assert tally.tried >= min(EXAMPLES, 10)
