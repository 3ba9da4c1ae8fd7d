"""Reading values out of nested tables: each check names the file and the key path
(``objects[2].radius``) and says what was expected; an unknown key suggests the near spelling."""

from __future__ import annotations

import difflib
import json
import math
import re
from collections.abc import Mapping
from typing import Any

from tracer.scene.errors import SceneError
from tracer.scene.vectors import Color, Vec3

#: How alike a word must be to a known one to be suggested (difflib's ratio, 2 * matches / total
#: length): 0.6, difflib's own default, takes "radus" for "radius" (0.91), not "colour" for
#: "center" (0.33).
SUGGEST_CUTOFF = 0.6
#: No number of a scene is larger in magnitude: coordinates squared and summed (every distance
#: test) stay finite in the references' float32 (3 (2e18)^2 ~ 1.2e37 < 3.4e38), and their fourth
#: powers (the torus quartic, 18_torus.h) in double; a colour or coefficient this large is
#: refused anyway by tracer.scene.brightness.
MAX_MAGNITUDE = 1e18
#: A value quoted in a message is cut to this many characters, so one line stays readable.
DESCRIBE_WIDTH = 40
#: A key TOML lets one write bare; any other is quoted when a message names it.
_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def join_key(path: str, key: str) -> str:
    """The key path of ``key`` inside the table at ``path``, as TOML writes it: a key that is not
    bare (empty, with spaces or dots) is quoted, so the message names it unambiguously."""
    name = key if _BARE_KEY.fullmatch(key) else json.dumps(key, ensure_ascii=False)
    return f"{path}.{name}" if path else name


def suggest(word: str, choices: Any) -> str:
    near = difflib.get_close_matches(word, list(choices), n=1, cutoff=SUGGEST_CUTOFF)
    return f" (did you mean {near[0]!r}?)" if near else ""


def describe(value: Any) -> str:
    kind = {bool: "boolean", str: "string", int: "integer", float: "number", list: "array"}
    name = "table" if isinstance(value, Mapping) else kind.get(type(value), type(value).__name__)
    text = repr(value)
    short = text if len(text) <= DESCRIBE_WIDTH else text[: DESCRIBE_WIDTH - 3] + "..."
    return f"{name} {short}"


class Reader:
    """Reads values out of nested tables, knowing the file it reports errors against."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, key: str, message: str) -> SceneError:
        return SceneError(self.source, key, message)

    def table(
        self, data: Any, path: str, allowed: set[str] | None, *, what: str | None = None
    ) -> Mapping[str, Any]:
        if not isinstance(data, Mapping):
            raise self.fail(path or "<top level>", f"expected a table, got {describe(data)}")
        if allowed is not None:
            for key in data:
                if key not in allowed:
                    where = f" for {what}" if what else ""
                    raise self.fail(
                        join_key(path, key),
                        f"unknown key{where}{suggest(key, allowed)}; expected one of "
                        + ", ".join(sorted(allowed)),
                    )
        return data

    def array(self, t: Mapping[str, Any], key: str) -> list[Any]:
        value = t.get(key, [])
        if not isinstance(value, list):
            raise self.fail(key, f"expected an array of tables ([[{key}]]), got {describe(value)}")
        return value

    def kind(self, data: Any, path: str, kinds: Mapping[str, set[str]]) -> str:
        t = self.table(data, path, None)
        if "type" not in t:
            raise self.fail(f"{path}.type", f"missing; expected one of {', '.join(kinds)}")
        kind = t["type"]
        if not isinstance(kind, str) or kind not in kinds:  # a table or array is no name
            raise self.fail(
                f"{path}.type",
                f"expected one of {', '.join(kinds)}, got {describe(kind)}"
                + (suggest(kind, kinds) if isinstance(kind, str) else ""),
            )
        return str(kind)

    def _get(self, t: Mapping[str, Any], path: str, key: str, required: bool) -> Any:
        if key not in t and required:
            raise self.fail(f"{path}.{key}", "missing; this key is required")
        return t.get(key)

    def string(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: str = "",
        required: bool = False,
    ) -> str:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        if not isinstance(value, str):
            raise self.fail(f"{path}.{key}", f"expected a string, got {describe(value)}")
        return value

    def _finite(self, value: Any, key: str, what: str = "a number") -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"expected {what}, got {describe(value)}")
        try:
            x = float(value)
        except OverflowError:  # an integer past a double's range
            x = math.inf if value > 0 else -math.inf
        if not math.isfinite(x):
            raise self.fail(key, f"expected a finite number, got {value}")
        if abs(x) > MAX_MAGNITUDE:
            raise self.fail(
                key,
                f"expected a number of magnitude at most {MAX_MAGNITUDE:g}, got {x:g} (the "
                "renderers square and cube coordinates; no scene needs more)",
            )
        return x

    def number(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: float = 0.0,
        required: bool = False,
        low: float | None = None,
        above: float | None = None,
        below: float | None = None,
        high: float | None = None,
        why: str = "",
    ) -> float:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        full = f"{path}.{key}"
        x = self._finite(value, full)
        if low is not None and x < low:
            raise self.fail(full, f"expected a number >= {low:g}, got {x:g}")
        if above is not None and x <= above:
            words = "a positive number" if above == 0 else f"a number > {above:g}"
            raise self.fail(full, f"expected {words}, got {x:g}")
        if below is not None and x >= below:
            raise self.fail(full, f"expected a number < {below:g}, got {x:g}")
        if high is not None and x > high:
            raise self.fail(full, f"expected a number <= {high:g}, got {x:g}{why}")
        return x

    def integer(
        self, t: Mapping[str, Any], path: str, key: str, *, default: int, low: int, high: int
    ) -> int:
        value = t.get(key)
        if value is None:
            return default
        full = f"{path}.{key}"
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(full, f"expected an integer, got {describe(value)}")
        if not low <= value <= high:
            raise self.fail(full, f"expected an integer from {low} to {high}, got {value}")
        return value

    def vec3(
        self,
        t: Mapping[str, Any],
        path: str,
        key: str,
        *,
        default: Vec3 = (0.0, 0.0, 0.0),
        required: bool = False,
        nonzero: bool = False,
    ) -> Vec3:
        value = self._get(t, path, key, required)
        if value is None:
            return default
        return self._vector(value, f"{path}.{key}", nonzero=nonzero)

    def _vector(self, value: Any, full: str, *, nonzero: bool = False) -> Vec3:
        if not isinstance(value, list | tuple) or len(value) != 3:  # tuples: dicts from Python
            raise self.fail(full, f"expected an array of three numbers, got {describe(value)}")
        v = tuple(self._finite(x, f"{full}[{i}]") for i, x in enumerate(value))
        if nonzero and not any(v):
            raise self.fail(full, "expected a non-zero vector, got length 0")
        return (v[0], v[1], v[2])

    def boolean(self, t: Mapping[str, Any], path: str, key: str, *, default: bool) -> bool:
        value = t.get(key, default)
        if not isinstance(value, bool):
            raise self.fail(f"{path}.{key}", f"expected true or false, got {describe(value)}")
        return value

    def choice(
        self, t: Mapping[str, Any], path: str, key: str, choices: tuple[str, ...], *, default: str
    ) -> str:
        value = self.string(t, path, key, default=default)
        if value not in choices:
            raise self.fail(
                f"{path}.{key}",
                f"expected one of {', '.join(map(repr, choices))}, got {value!r}"
                + suggest(value, choices),
            )
        return value

    def points(
        self, t: Mapping[str, Any], path: str, key: str, *, count: int | None = None
    ) -> list[Vec3]:
        value = self._get(t, path, key, True)
        full = f"{path}.{key}"
        listed = isinstance(value, list | tuple)  # tuples: a scene dict written in Python
        if not listed or not value or (count is not None and len(value) != count):
            n = f"{count}" if count is not None else "one or more"
            raise self.fail(full, f"expected an array of {n} points, got {describe(value)}")
        return [self._vector(p, f"{full}[{i}]") for i, p in enumerate(value)]

    def color(self, t: Mapping[str, Any], path: str, key: str, *, default: Color) -> Color:
        c = self.vec3(t, path, key, default=default)
        if min(c) < 0:
            raise self.fail(f"{path}.{key}", f"expected three numbers >= 0, got {list(c)}")
        return c
