"""Probes (checks of kind (a)): one call of a student's function on chosen inputs, with the
value it must return computed here, independently of the core (closed forms, exact rational or
50-digit decimal arithmetic on the exact binary values of the inputs).

A probe's expected values are a tuple with one entry per value the probe program prints
(lessons/cpp/probe_main.cpp):

- a float: the value must lie within the probe's tolerance of it (an infinity must be met
  exactly);
- None: not checked (the roots of a line that misses, the hit record of no hit);
- ("<=", x): any value up to x (a back-facing N.L, which the solution returns as it is and a
  student may clamp to 0: local_color() skips both).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from decimal import Decimal, localcontext
from fractions import Fraction

Vec = tuple[float, float, float]  # a point or direction, as the checks write them
XYZ = ("x", "y", "z")  # labels of a vector's components in a probe's expected values
RGB = ("r", "g", "b")  # labels of a colour's components
HIDDEN = "after_published"  # a hidden variant's visibility (Gradescope's word)

# The unit roundoff of double, 2^-53.
U = 2.0**-53

Expected = float | None | tuple[str, float]


@dataclass(frozen=True)
class Probe:
    name: str  # a short title, unique in the lesson
    lesson: str
    concept: str  # one of the lesson's concepts in lessons/catalog.py
    function: str  # the function the probe program calls
    inputs: tuple[float, ...]  # in probe_main.cpp's order for the function
    expected: tuple[Expected, ...]
    labels: tuple[str, ...]  # a name for each printed value ("t0", "N.x", ...)
    # |got - expected| <= ulps * U * max(|expected|, scale): `ulps` roundings of the inputs'
    # magnitude `scale` (argued where the probes are made).
    ulps: float = 8
    scale: float = 1.0
    visibility: str = "visible"  # "visible" (public) or "after_published" (hidden variant)
    inputs_text: str = ""  # the inputs as a student reads them
    hint: str = ""  # what a wrong value usually means
    tags: tuple[str, ...] = field(default=())

    def line(self, index: int) -> str:
        """The probe file's line (exact: hexadecimal floats)."""
        return " ".join([str(index), self.function, *(float(x).hex() for x in self.inputs)])

    def tolerance(self, expected: float) -> float:
        return self.ulps * U * max(abs(expected), self.scale)

    def compare(self, got: tuple[float, ...]) -> list[str]:
        """What differs, one line per value (empty: the probe passes)."""
        if len(got) != len(self.expected):
            return [f"the probe printed {len(got)} values, expected {len(self.expected)}"]
        wrong = []
        for label, want, value in zip(self.labels, self.expected, got, strict=True):
            if want is None:
                continue
            if isinstance(want, tuple):
                if not value <= want[1]:
                    wrong.append(f"{label}: expected at most {want[1]:.17g}, got {value:.17g}")
                continue
            if math.isinf(want) or math.isnan(value):
                ok = value == want
            else:
                ok = abs(value - want) <= self.tolerance(want)
            if not ok:
                wrong.append(f"{label}: expected {fmt(want)}, got {fmt(value)}")
        return wrong


def fmt(x: float) -> str:
    if math.isinf(x):
        return "infinity" if x > 0 else "-infinity"
    if math.isnan(x):
        return "NaN"
    return f"{x:.17g}"


def vec_text(v: tuple[float, float, float]) -> str:
    return "(" + ", ".join(f"{x:g}" for x in v) + ")"


def exact(x: float) -> Fraction:
    return Fraction(x)


def dot(a: tuple[float, ...], b: tuple[float, ...]) -> Fraction:
    return sum((Fraction(x) * Fraction(y) for x, y in zip(a, b, strict=True)), Fraction(0))


def sub(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[Fraction, ...]:
    return tuple(Fraction(x) - Fraction(y) for x, y in zip(a, b, strict=True))


def sqrt_fraction(x: Fraction) -> Decimal:
    """sqrt of an exact rational to 50 digits."""
    with localcontext() as context:
        context.prec = 50
        return (Decimal(x.numerator) / Decimal(x.denominator)).sqrt()


def to_float(x: Fraction | Decimal) -> float:
    """The double nearest an exact value (Fraction) or a 50-digit one (Decimal)."""
    return float(x)
