"""The methods on tori (study/methods.py dispatches here).

- The textbook's torus: the ray's quartic as Suffern prints it ("Ray Tracing from the Ground
  Up", 2007, section 19.5, the torus around z here), solved in closed form by Schwarze's
  SolveQuartic (Jochen Schwarze, "Cubic and Quartic Roots", Graphics Gems I, 1990, pp. 404-407:
  Ferrari's resolvent cubic by Cardano, two quadratics), as teaching tracers copy it, Suffern's
  book among them; vectorised over the rays, in float64 or float32 throughout.
- POV-Ray, ``torus { R, r sturm }`` and without ``sturm``: it traces nothing but its camera's
  rays, so it applies to cases whose rays are a PinholeCamera's pixel rays (study/shapes.py,
  study/families_torus.py pixel_rays()): a width x height image, no antialiasing, the torus
  white (ambient 1, diffuse 0, no lights) on black, a 16-bit PNG read back: a pixel is a hit
  where it is above one half. Only the decision (the first hit or not) is measured: an image
  carries no t, so its t comes back as 1 where it hits, a placeholder, and its rows' t_error
  metrics mean nothing; its time per ray includes the process' start-up."""

from __future__ import annotations

import functools
import re
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import numpy.typing as npt

from study.shapes import Torus

Array = npt.NDArray[np.float64]

#: The IsZero() threshold as Suffern's copy of Schwarze's code sets it (his Maths.h): 1e-90,
#: where Graphics Gems printed 1e-9, an absolute threshold that misjudges every small torus
#: (its coefficients go as R^4). In float32 it rounds to 0: IsZero() is then never true.
EQN_EPS = 1e-90


def _is_zero(x: np.ndarray) -> np.ndarray:
    return (x > -EQN_EPS) & (x < EQN_EPS)


def _solve_cubic_first(c0: np.ndarray, c1: np.ndarray, c2: np.ndarray, dt: type) -> np.ndarray:
    """Schwarze's SolveCubic on x^3 + c2 x^2 + c1 x + c0, its first solution s[0] (the one
    SolveQuartic takes), vectorised: each branch computed, the printed one chosen."""
    a, b, c = c2, c1, c0
    sq_a = a * a
    third = dt(1.0 / 3)
    p = third * (-third * sq_a + b)
    q = dt(0.5) * (dt(2.0 / 27) * a * sq_a - third * a * b + c)
    cb_p = p * p * p
    d = q * q + cb_p
    # D == 0: a triple (q == 0) or a single and a double solution: s[0] = 2 cbrt(-q).
    s_zero = np.where(_is_zero(q), dt(0), 2 * np.cbrt(-q))
    # D < 0, casus irreducibilis: s[0] = 2 sqrt(-p) cos(acos(-q / sqrt(-cb_p)) / 3).
    phi = third * np.arccos(-q / np.sqrt(-cb_p))
    s_three = 2 * np.sqrt(-p) * np.cos(phi)
    # D > 0: one real solution, u + v.
    sqrt_d = np.sqrt(d)
    s_one = np.cbrt(sqrt_d - q) - np.cbrt(sqrt_d + q)
    s = np.where(_is_zero(d), s_zero, np.where(d < 0, s_three, s_one))
    return s - third * a


def _solve_quadric(c0: np.ndarray, c1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Schwarze's SolveQuadric on x^2 + c1 x + c0: (s0, s1), nan where absent."""
    p = c1 / 2
    d = p * p - c0
    sq = np.sqrt(np.where(d > 0, d, 0))
    s0 = np.where(_is_zero(d), -p, np.where(d < 0, np.nan, sq - p))
    s1 = np.where(_is_zero(d) | (d < 0), np.nan, -sq - p)
    return s0, s1


def solve_quartic(c: list[np.ndarray], dt: type) -> list[np.ndarray]:
    """Schwarze's SolveQuartic on c[4] x^4 + ... + c[0]: four arrays of roots, nan where absent."""
    a, b, cc, d = c[3] / c[4], c[2] / c[4], c[1] / c[4], c[0] / c[4]
    sq_a = a * a
    p = dt(-3.0 / 8) * sq_a + b
    q = dt(1.0 / 8) * sq_a * a - dt(0.5) * a * b + cc
    r = dt(-3.0 / 256) * sq_a * sq_a + dt(1.0 / 16) * sq_a * b - dt(0.25) * a * cc + d
    nan = np.full_like(a, np.nan)
    # r == 0: y (y^3 + p y + q) = 0; Schwarze takes all of the cubic's solutions, here its first
    # and 0 (the other two matter only for a ray through the torus' axis point exactly).
    y_r0 = _solve_cubic_first(q, p, np.zeros_like(a), dt)
    # The resolvent cubic z^3 - p/2 z^2 - r z + (r p / 2 - q^2 / 8), its first real solution.
    z = _solve_cubic_first(dt(0.5) * r * p - dt(1.0 / 8) * q * q, -r, dt(-0.5) * p, dt)
    u = z * z - r
    v = 2 * z - p
    bad = (~_is_zero(u) & (u < 0)) | (~_is_zero(v) & (v < 0))
    u = np.where(_is_zero(u), 0, np.sqrt(np.where(u > 0, u, 0)))
    v = np.where(_is_zero(v), 0, np.sqrt(np.where(v > 0, v, 0)))
    sv = np.where(q < 0, -v, v)
    s0, s1 = _solve_quadric(z - u, sv)
    s2, s3 = _solve_quadric(z + u, -sv)
    roots = [np.where(bad, nan, s) for s in (s0, s1, s2, s3)]
    zero_r = _is_zero(r)
    roots = [np.where(zero_r, y_r0, roots[0]), np.where(zero_r, 0, roots[1]),
             np.where(zero_r, nan, roots[2]), np.where(zero_r, nan, roots[3])]  # fmt: skip
    sub = dt(0.25) * a
    return [x - sub for x in roots]


def textbook_trace(dtype: type) -> object:
    from study.methods import Traced

    def trace(shape: Torus, o_in: Array, d_in: Array) -> Traced:
        dt = dtype
        c = np.array(shape.center, dtype=dt)
        o, d = o_in.astype(dt) - c, d_in.astype(dt)
        big_r, r = dt(shape.major_radius), dt(shape.minor_radius)
        with np.errstate(all="ignore"):
            dd = np.sum(d * d, axis=1)
            e = np.sum(o * o, axis=1) - big_r * big_r - r * r
            f = np.sum(o * d, axis=1)
            four_a2 = dt(4) * big_r * big_r
            coeffs = [e * e - four_a2 * (r * r - o[:, 2] * o[:, 2]),
                      dt(4) * dd * e * 0 + dt(4) * f * e + dt(2) * four_a2 * o[:, 2] * d[:, 2],
                      dt(2) * dd * e + dt(4) * f * f + four_a2 * d[:, 2] * d[:, 2],
                      dt(4) * dd * f, dd * dd]  # fmt: skip
            roots = solve_quartic(coeffs, dt)
            ts = np.stack([np.where(x > 0, x, np.inf) for x in roots])
            ts = np.where(np.isnan(ts), np.inf, ts)
            t = ts.min(axis=0)
            hit = np.isfinite(t)
            p = o + t[:, None] * d
            # The gradient of the implicit function, as the textbook's normal.
            g = np.sum(p * p, axis=1) - big_r * big_r - r * r
            n = 4 * p * g[:, None] + np.c_[np.zeros((len(p), 2)), 8 * big_r * big_r * p[:, 2]]
            n = n / np.linalg.norm(n, axis=1)[:, None]
            p = p + c
        return Traced(hit, t.astype(np.float64), p.astype(np.float64), None,
                      n.astype(np.float64))  # fmt: skip

    return trace


# ---------------------------------------------------------------------------------- POV-Ray


@functools.lru_cache(maxsize=1)
def povray_version() -> str:
    """The version POV-Ray prints (``povray --version``: "POV-Ray 3.7.0.10.unofficial")."""
    from reference.povray import povray_executable

    done = subprocess.run([povray_executable(), "--version"], capture_output=True, text=True,
                          check=False)  # fmt: skip
    m = re.search(r"POV-Ray (\S+)", done.stdout + done.stderr)
    return f"POV-Ray {m.group(1)}" if m else "POV-Ray unknown"


def _num(x: float) -> str:
    return repr(float(x))


def _vec(v: tuple[float, ...]) -> str:
    return "<" + ", ".join(_num(x) for x in v) + ">"


def povray_sdl(shape: Torus, sturm: bool) -> str:
    """The scene: the camera's vectors as given (no look_at, no angle: POV-Ray computes
    nothing from them), the torus turned from POV-Ray's y axis to our z exactly (a matrix of
    0 and 1, as converters/povray.py does) and moved to its centre."""
    cam = shape.camera
    assert cam is not None
    cx, cy, cz = shape.center
    solver = " sturm" if sturm else ""
    return "\n".join([
        "#version 3.7;",
        "global_settings { assumed_gamma 1.0 ambient_light <1, 1, 1> }",
        "background { rgb <0, 0, 0> }",
        f"camera {{ perspective location {_vec(cam.location)} direction {_vec(cam.direction)}"
        f" right {_vec(cam.right)} up {_vec(cam.up)} }}",
        f"torus {{ {_num(shape.major_radius)}, {_num(shape.minor_radius)}{solver}"
        " pigment { rgb <1, 1, 1> } finish { ambient 1 diffuse 0 }"
        f" matrix <1, 0, 0, 0, 0, 1, 0, -1, 0, {_num(cx)}, {_num(cy)}, {_num(cz)}> }}",
        "",
    ])  # fmt: skip


def povray_hits(shape: Torus, sturm: bool) -> npt.NDArray[np.bool_]:
    """POV-Ray's hit (True) or miss per pixel, row by row from the top."""
    from reference.povray import PovrayError, povray_executable, read_png16

    cam = shape.camera
    assert cam is not None
    with tempfile.TemporaryDirectory(prefix="rtlab-study-povray-") as tmp:
        sdl, out = Path(tmp) / "torus.pov", Path(tmp) / "torus.png"
        sdl.write_text(povray_sdl(shape, sturm))
        cmd = [povray_executable(), f"+I{sdl}", f"+O{out}", f"+W{cam.width}", f"+H{cam.height}",
               "-A", "+FN16", "File_Gamma=1.0", "-D", "-P", "+WT1", "-V"]  # fmt: skip
        done = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if done.returncode != 0 or not out.exists():
            raise PovrayError(f"povray failed (exit {done.returncode}) on {sdl}:\n"
                              f"{done.stderr[-2000:]}")  # fmt: skip
        image = read_png16(out)
    return (image[..., 0] > 0.5).reshape(-1)


def povray_trace(sturm: bool) -> object:
    from study.methods import Traced

    def trace(shape: Torus, o: Array, d: Array) -> Traced:
        cam = shape.camera
        if cam is None:
            raise ValueError("POV-Ray traces only its camera's rays: the shape has no camera")
        n = len(o)
        # Fewer rays than pixels: the metrics' warm-up call on the first two (its answer is thrown
        # away; rendering there would only double the cost). Else the whole image, start-up
        # included in its time (about 0.7 s a process).
        whole = n == cam.width * cam.height
        hits = povray_hits(shape, sturm) if whole else np.zeros(n, dtype=bool)
        t = np.where(hits, 1.0, np.inf)  # POV-Ray's image carries no t: decisions only
        p = np.where(hits[:, None], o + d, np.inf)
        return Traced(hits.copy(), t, p, None, np.zeros((n, 3)))

    return trace
