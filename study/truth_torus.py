"""The truth for tori (study/truth.py dispatches here), from the scene description and the ray.

Route 1, exact. Along o + t d, with f = o - c, the torus (x^2 + y^2 + z^2 + R^2 - r^2)^2 =
4 R^2 (x^2 + y^2) is a quartic Q(t) whose coefficients are polynomials in the inputs. Every
double is an integer over a power of two, so with the positions (centre, radii, origin) over one
power and the direction over another, t = tau 2^e turns Q into a quartic in tau with integer
coefficients: no rounding anywhere. Its real roots in (0, tmax) are counted with Sturm's theorem
(Sturm 1835; Basu, Pollack and Roy, "Algorithms in Real Algebraic Geometry", 2.2.2) on the
square-free part (pseudo-remainders with a positive multiplier keep every sign), the first one
isolated by bisection on those counts, narrowed by exact bisection, then polished by Newton's
method in mpmath to DIGITS digits and checked: the exact sign of Q changes across the result's
last digits, so the root lies there.

Route 2, independent: Ferrari's closed form in mpmath complex arithmetic at 2 DIGITS digits
(the resolvent cubic by Cardano), the smallest positive root whose imaginary part vanishes at
that precision. Near a double root (a tangent ray) Ferrari's imaginary parts are the square root
of the working precision: there the two routes' decisions may differ, and route 1 stands.

Conditioning: a ray is undecidable when a one-ulp move of its six components flips the exact
decision: truth.PERTURBATIONS and, for rays whose tube distance at a critical point of Q is
within 1000 ulps of zero (in double: cheap), the two moves along the gradient of Q there, which
change its value there most (Q's local minimum moves with the ray to first order as Q does at a
fixed t: the envelope theorem). Rays farther from the boundary than 1000 ulps cannot be flipped
by a one-ulp move and skip the exact moves."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from fractions import Fraction

import mpmath
import numpy as np
import numpy.typing as npt

from study.shapes import Torus

Poly = list[int]  # coefficients, highest degree first


def _integers(values: list[float]) -> tuple[list[int], int]:
    """Doubles as integers over one common power of two: (numerators, denominator)."""
    ratios = [float(v).as_integer_ratio() for v in values]
    big = max(den for _, den in ratios)
    return [num * (big // den) for num, den in ratios], big


def quartic(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike) -> tuple[Poly, Fraction]:
    """Q in tau with integer coefficients (highest first) and the scale: t = tau * scale."""
    oa, da = np.asarray(o, dtype=np.float64), np.asarray(d, dtype=np.float64)
    pos, sp = _integers([*tor.center, tor.major_radius, tor.minor_radius, *oa])
    dirs, sd = _integers(list(da))
    return _quartic_of(pos, sp, dirs, sd)


def _rationals(values: list[Fraction]) -> tuple[list[int], int]:
    """Rationals as integers over one common denominator (their least common multiple): for
    doubles the largest of their powers of two, as _integers() has it."""
    big = 1
    for v in values:
        big = math.lcm(big, v.denominator)
    return [v.numerator * (big // v.denominator) for v in values], big


def quartic_exact(tor: Torus, o: Sequence[Fraction],
                  d: Sequence[Fraction]) -> tuple[Poly, Fraction]:  # fmt: skip
    """quartic() for a ray given as exact rationals (a world ray taken into a transformed
    torus' own coordinates by the exact inverse of its matrix: study/truth_placed.py)."""
    pos, sp = _rationals([*(Fraction(float(x)) for x in tor.center),
                          Fraction(tor.major_radius), Fraction(tor.minor_radius), *o])  # fmt: skip
    dirs, sd = _rationals(list(d))
    return _quartic_of(pos, sp, dirs, sd)


def _quartic_of(pos: list[int], sp: int, dirs: list[int], sd: int) -> tuple[Poly, Fraction]:
    """The quartic from the centre, radii and origin as integers over sp (pos) and the direction
    over sd (dirs)."""
    c, big_r, r, oo = pos[0:3], pos[3], pos[4], pos[5:8]
    f = [oo[k] - c[k] for k in range(3)]
    dd = dirs
    g0 = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] + big_r * big_r - r * r
    g1 = 2 * (f[0] * dd[0] + f[1] * dd[1] + f[2] * dd[2])
    g2 = dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2]
    h0 = f[0] * f[0] + f[1] * f[1]
    h1 = 2 * (f[0] * dd[0] + f[1] * dd[1])
    h2 = dd[0] * dd[0] + dd[1] * dd[1]
    k = 4 * big_r * big_r
    q = [g2 * g2, 2 * g1 * g2, g1 * g1 + 2 * g0 * g2 - k * h2, 2 * g0 * g1 - k * h1,
         g0 * g0 - k * h0]  # fmt: skip
    # o - c + t d = (f + tau D) / sp with t d = t D / sd: tau = t sp / sd.
    return q, Fraction(sd, sp)


def _trim(p: Poly) -> Poly:
    i = 0
    while i < len(p) - 1 and p[i] == 0:
        i += 1
    return p[i:]


def _primitive(p: Poly) -> Poly:
    g = 0
    for x in p:
        g = math.gcd(g, x)
    return [x // g for x in p] if g > 1 else p


def _prem(a: Poly, b: Poly) -> Poly:
    """The remainder of |lc(b)|^k a divided by b (a positive multiple of a mod b)."""
    r = list(a)
    lb = b[0]
    sign = 1 if lb > 0 else -1
    while len(r) >= len(b) and any(r):
        r0 = r[0]
        r = [abs(lb) * x for x in r]
        for i, y in enumerate(b):
            r[i] -= sign * r0 * y
        r = r[1:]
    return _trim(r) if r else [0]


def _pquo(a: Poly, b: Poly) -> Poly:
    """A positive multiple of a / b where b divides a exactly."""
    r, out = list(a), []
    lb = b[0]
    while len(r) >= len(b):
        out = [x * lb for x in out] + [r[0]]
        r0 = r[0]
        r = [lb * x for x in r]
        for i, y in enumerate(b):
            r[i] -= r0 * y
        r = r[1:]
    return _primitive(out if lb > 0 or len(out) % 2 == 0 else [-x for x in out])


def _derivative(p: Poly) -> Poly:
    n = len(p) - 1
    return [c * (n - i) for i, c in enumerate(p[:-1])]


def sturm(p: Poly) -> list[Poly]:
    seq = [_primitive(p), _primitive(_derivative(p))]
    while len(seq[-1]) > 1:
        r = _prem(seq[-2], seq[-1])
        if r == [0]:
            break
        seq.append(_primitive([-x for x in r]))
    return seq


def sign_at(p: Poly, x: Fraction) -> int:
    """The exact sign of p(x)."""
    num, den = x.numerator, x.denominator
    total, dpow = 0, 1
    total = p[0]  # Horner on den^n p(num / den) (den > 0: the same sign)
    for c in p[1:]:
        dpow *= den
        total = total * num + c * dpow
    return (total > 0) - (total < 0)


def _changes(signs: list[int]) -> int:
    s = [x for x in signs if x != 0]
    return sum(1 for a, b in itertools.pairwise(s) if a != b)


def _v(seq: list[Poly], x: Fraction) -> int:
    return _changes([sign_at(p, x) for p in seq])


def _v_inf(seq: list[Poly]) -> int:
    return _changes([(p[0] > 0) - (p[0] < 0) for p in seq])


def _square_free(q: Poly) -> tuple[Poly, list[Poly]]:
    """The square-free part of q with no root at 0, and its Sturm sequence."""
    q = _trim(q)
    while len(q) > 1 and q[-1] == 0:  # a root at tau = 0: not in (0, tmax)
        q = q[:-1]
    seq = sturm(q)
    if len(seq[-1]) > 1:  # gcd(q, q') has roots: divide them out
        q = _pquo(q, seq[-1])
        seq = sturm(q)
    return q, seq


def _count(seq: list[Poly], lo: Fraction, hi: Fraction | None) -> int:
    """Distinct roots in (lo, hi] (hi None: infinity), lo and hi not roots of seq[0]."""
    return _v(seq, lo) - (_v_inf(seq) if hi is None else _v(seq, hi))


def decide(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike, tmax: float = math.inf) -> bool:
    """Whether the ray meets the torus at some t in (0, tmax), exactly."""
    q, scale = quartic(tor, o, d)
    s, seq = _square_free(q)
    top = None if tmax == math.inf else Fraction(tmax) / scale
    n = _count(seq, Fraction(0), top)
    if top is not None and sign_at(s, top) == 0:
        n -= 1  # a root at tmax itself is not in the open interval
    return n > 0


def first_root(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike,
               tmax: float = math.inf, digits: int = 120) -> tuple[bool, object]:  # fmt: skip
    """Route 1: (hit, t as an mpmath number good to ``digits`` digits) or (False, None)."""
    return _first_root_of(*quartic(tor, o, d), tmax, digits)


def first_root_exact(tor: Torus, o: Sequence[Fraction], d: Sequence[Fraction],
                     tmax: float = math.inf, digits: int = 120) -> tuple[bool, object]:  # fmt: skip
    """first_root() for a ray given as exact rationals (quartic_exact())."""
    return _first_root_of(*quartic_exact(tor, o, d), tmax, digits)


def _first_root_of(q: Poly, scale: Fraction, tmax: float, digits: int) -> tuple[bool, object]:
    s, seq = _square_free(q)
    top = None if tmax == math.inf else Fraction(tmax) / scale
    zero = Fraction(0)
    if _count(seq, zero, top) - (top is not None and sign_at(s, top) == 0) <= 0:
        return False, None
    guess = _guess(s)
    bracket = _near(seq, guess) if guess is not None else None
    if bracket is not None:
        lo, hi = bracket
    else:
        # The first root's scale: the smallest power of two 2^k with a root in (0, 2^k].
        k = 0
        if _count(seq, zero, Fraction(1)) > 0:
            while _count(seq, zero, Fraction(1, 2 ** (-k + 1))) > 0:
                k -= 1
        else:
            while _count(seq, zero, Fraction(2**k)) == 0:
                k += 1
        hi = Fraction(2) ** k
        lo = hi / 2
    # (lo, hi] holds the first root and no root lies in (0, lo]: bisect until it holds one.
    while _count(seq, lo, hi) > 1:
        mid = (lo + hi) / 2
        if _count(seq, lo, mid) > 0:
            hi = mid
        else:
            lo = mid
    root = _mpf(hi) if sign_at(s, hi) == 0 else _refine(s, lo, hi, digits, guess)
    t = root * _mpf(scale)
    if top is not None and not t < tmax:
        return False, None
    return True, t


def _guess(s: Poly) -> float | None:
    """A double approximation of the first positive root (numpy's companion matrix on the exact
    coefficients rounded once): only a starting point, every use of it is checked exactly."""
    lead = Fraction(s[0])
    with np.errstate(all="ignore"):
        c = np.array([float(Fraction(x) / lead) for x in s])
        if not np.all(np.isfinite(c)):
            return None
        z = np.roots(c)
    real = sorted(x.real for x in z if x.real > 0 and abs(x.imag) <= 1e-6 * abs(x))
    return float(real[0]) if real else None


def _near(seq: list[Poly], guess: float) -> tuple[Fraction, Fraction] | None:
    """(lo, hi] around the guess with no root in (0, lo] and one at least in (lo, hi], if a
    relative width of 1e-12 .. 1e-3 finds one."""
    for w in (1e-12, 1e-9, 1e-6, 1e-3):
        lo, hi = Fraction(guess * (1 - w)), Fraction(guess * (1 + w))
        if lo > 0 and _count(seq, Fraction(0), lo) == 0 and _count(seq, lo, hi) > 0:
            return lo, hi
    return None


def _mpf(x: Fraction) -> mpmath.mpf:
    return mpmath.mpf(x.numerator) / x.denominator


def _as_fraction(x: mpmath.mpf) -> Fraction:
    man, exp = mpmath.mpf(x).man_exp
    return Fraction(man) * Fraction(2) ** exp


def _newton(s: Poly, x0: mpmath.mpf, digits: int) -> mpmath.mpf:
    """Newton's method from x0 on the fixed-point grid x = m / 2^e, m of about digits + 20
    digits, in integers: s and s' at x are exact (den^n s(m / den), Horner), the step is
    rounded to the grid. No floating-point rounding to cancel: the integer coefficients' terms
    cancel by many digits near a close pair of roots (a grazing ray), mpmath's would not."""
    bits = int((digits + 20) * 3.33)
    e = bits - int(mpmath.floor(mpmath.log(abs(x0), 2)))
    m = int(mpmath.nint(mpmath.ldexp(x0, e)))
    den = 1 << e
    n = len(s) - 1
    ds = [c * (n - i) for i, c in enumerate(s[:-1])]
    for _ in range(60):
        v, dpow = s[0], 1
        for c in s[1:]:
            dpow *= den
            v = v * m + c * dpow  # den^n s(m / den)
        dv, dpow = ds[0], 1
        for c in ds[1:]:
            dpow *= den
            dv = dv * m + c * dpow  # den^(n - 1) s'(m / den)
        if dv == 0:
            break
        step = (2 * v + dv) // (2 * dv) if dv > 0 else -((2 * v - dv) // (-2 * dv))
        m -= step  # the step in units of 1 / den, rounded: s / s' = (v / dv) / den
        if abs(step) <= 1:
            break
    with mpmath.workdps(digits + 40):
        return mpmath.ldexp(mpmath.mpf(m), -e)


def _bracketed(s: Poly, x: mpmath.mpf, lo: Fraction, hi: Fraction, s_lo: int,
               digits: int) -> bool:  # fmt: skip
    """Whether s changes sign, exactly, across x +- |x| 10^-digits within (lo, hi)."""
    with mpmath.workdps(digits + 20):
        width = abs(x) * mpmath.mpf(10) ** (-digits)
        a, b = _as_fraction(x - width), _as_fraction(x + width)
    return lo <= a and b <= hi and sign_at(s, a) == s_lo and sign_at(s, b) == -s_lo


def _refine(s: Poly, lo: Fraction, hi: Fraction, digits: int,
            guess: float | None = None) -> mpmath.mpf:  # fmt: skip
    """The simple root of s in (lo, hi) (s changes sign there), to ``digits`` digits: Newton's
    method in mpmath from the guess, or after exact bisection to 50 bits, then an exact check
    of the sign change across the result; bisection all the way where that check fails."""
    s_lo = sign_at(s, lo)
    if guess is not None and lo < Fraction(guess) < hi:
        x = _newton(s, mpmath.mpf(guess), digits)
        if _bracketed(s, x, lo, hi, s_lo, digits):
            return x
    for _ in range(50):
        mid = (lo + hi) / 2
        sm = sign_at(s, mid)
        if sm == 0:
            return _mpf(mid)
        if sm == s_lo:
            lo = mid
        else:
            hi = mid
    x = _newton(s, _mpf((lo + hi) / 2), digits)
    if _bracketed(s, x, lo, hi, s_lo, digits):
        return x
    while hi - lo > abs(hi) * Fraction(1, 10**digits):  # pragma: no cover (Newton failed)
        mid = (lo + hi) / 2
        if sign_at(s, mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return _mpf((lo + hi) / 2)


# ------------------------------------------------------------------------------------ route 2


def _cbrt(z: mpmath.mpc) -> mpmath.mpc:
    return mpmath.mpf(0) if z == 0 else mpmath.root(z, 3)


def ferrari(coeffs: list) -> list:
    """The four complex roots of a x^4 + b x^3 + c x^2 + d x + e (Ferrari 1545, the depressed
    quartic and its resolvent cubic by Cardano), in the current mpmath precision."""
    a, b, c, d, e = (mpmath.mpc(x) for x in coeffs)
    b, c, d, e = b / a, c / a, d / a, e / a
    # x = y - b/4: y^4 + p y^2 + q y + r = 0.
    p = c - 3 * b**2 / 8
    q = d - b * c / 2 + b**3 / 8
    r = e - b * d / 4 + b**2 * c / 16 - 3 * b**4 / 256
    shift = -b / 4
    if q == 0:  # biquadratic
        w = mpmath.sqrt(p * p - 4 * r)
        ys = [s1 * mpmath.sqrt((-p + s2 * w) / 2) for s1 in (1, -1) for s2 in (1, -1)]
        return [y + shift for y in ys]
    # Resolvent: m with (y^2 + p/2 + m)^2 = 2m (y - q / (4m))^2: 8m^3 + 8p m^2 + (2p^2 - 8r) m
    # - q^2 = 0, a root m != 0 by Cardano on the depressed cubic m = u - p/3.
    a2, a1, a0 = p, (p * p / 4 - r), -q * q / 8
    pp = a1 - a2 * a2 / 3
    qq = 2 * a2**3 / 27 - a2 * a1 / 3 + a0
    disc = mpmath.sqrt(qq * qq / 4 + pp**3 / 27)
    u = _cbrt(-qq / 2 + disc)
    if u == 0:
        u = _cbrt(-qq / 2 - disc)
    m = u - pp / (3 * u) - a2 / 3 if u != 0 else -a2 / 3
    s = mpmath.sqrt(2 * m)
    roots = []
    for sg in (1, -1):
        # y^2 + p/2 + m = sg s (y - q / (2 s^2)) ... y^2 - sg s y + (p/2 + m + sg q / (2 s)).
        cc = p / 2 + m + sg * q / (2 * s)
        w = mpmath.sqrt(s * s - 4 * cc)
        roots += [(sg * s + w) / 2 + shift, (sg * s - w) / 2 + shift]
    return roots


def route2(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike, tmax: float = math.inf,
           digits: int = 120) -> tuple[bool, object, mpmath.mpf]:  # fmt: skip
    """(hit, t, margin): margin is the smallest |imaginary part| of a root relative to its
    size (0 for a real root): near 0 the decision is route 1's to make."""
    with mpmath.workdps(2 * digits):
        c = [mpmath.mpf(float(x)) for x in tor.center]
        oo = [mpmath.mpf(float(x)) - ci for x, ci in zip(np.asarray(o), c, strict=True)]
        dd = [mpmath.mpf(float(x)) for x in np.asarray(d)]
        return route2_mp(tor, oo, dd, tmax, digits)


def route2_mp(tor: Torus, oo: list, dd: list, tmax: float = math.inf,
              digits: int = 120) -> tuple[bool, object, mpmath.mpf]:  # fmt: skip
    """route2() for a ray given in mpmath numbers, its origin relative to the centre (a world
    ray taken into a transformed torus' coordinates in mpmath: study/truth_placed.py)."""
    with mpmath.workdps(2 * digits):
        big_r, r = mpmath.mpf(tor.major_radius), mpmath.mpf(tor.minor_radius)
        # |p|^2 + R^2 - r^2 = g2 t^2 + g1 t + g0 and x^2 + y^2 = h2 t^2 + h1 t + h0.
        g2 = mpmath.fsum(x * x for x in dd)
        g1 = 2 * mpmath.fsum(x * y for x, y in zip(oo, dd, strict=True))
        g0 = mpmath.fsum(x * x for x in oo) + big_r**2 - r**2
        h2, h1 = dd[0] ** 2 + dd[1] ** 2, 2 * (oo[0] * dd[0] + oo[1] * dd[1])
        h0 = oo[0] ** 2 + oo[1] ** 2
        k = 4 * big_r**2
        coeffs = [g2 * g2, 2 * g1 * g2, g1 * g1 + 2 * g0 * g2 - k * h2, 2 * g0 * g1 - k * h1,
                  g0 * g0 - k * h0]  # fmt: skip
        roots = ferrari(coeffs)
        tiny = mpmath.mpf(10) ** (-digits)
        real = sorted(z.real for z in roots if abs(z.imag) <= tiny * (abs(z) + tiny))
        margin = min(abs(z.imag) / (abs(z) + tiny) for z in roots)
        for t in real:
            if t > 0:
                return (True, +t, margin) if t < tmax else (False, None, margin)
        return False, None, margin


# ------------------------------------------------------------------------------ conditioning


def _near_critical(tor: Torus, o: np.ndarray, d: np.ndarray) -> list[float]:
    """The t > 0 of Q's critical points (and t = 0) where the tube distance, in double, is
    within 1000 ulps of the ray's coordinates of zero."""
    c = np.array(tor.center)
    f = o - c
    big_r, r = tor.major_radius, tor.minor_radius
    g2, g1, g0 = d @ d, 2 * f @ d, f @ f + big_r**2 - r**2
    h2, h1 = d[0] ** 2 + d[1] ** 2, 2 * (f[0] * d[0] + f[1] * d[1])
    k = 4 * big_r**2
    dq = [4 * g2 * g2, 3 * 2 * g1 * g2, 2 * (g1 * g1 + 2 * g0 * g2 - k * h2), 2 * g0 * g1 - k * h1]
    with np.errstate(all="ignore"):
        ts = [0.0] + [float(z.real) for z in np.roots(dq) if z.real > 0]
    out = []
    for t in ts:
        p = f + t * d
        rho = math.hypot(p[0], p[1])
        e = math.hypot(rho - big_r, p[2]) - r
        size = np.abs(f).max() + abs(t) * np.abs(d).max() + big_r
        if not abs(e) > 1000 * np.spacing(size):
            out.append(t)
    return out


def _gradient_moves(tor: Torus, o: np.ndarray, d: np.ndarray, ts: list[float]) -> list[tuple]:
    f = o - np.array(tor.center)
    big_r, r = tor.major_radius, tor.minor_radius
    moves = []
    for t in ts:
        p = f + t * d
        s = p @ p + big_r**2 - r**2
        grad = 4 * s * p - 8 * big_r**2 * np.array([p[0], p[1], 0.0])  # dQ/dp
        g = np.concatenate([grad, t * grad])  # dQ/do, dQ/dd at fixed t
        up = tuple(1 if x >= 0 else -1 for x in g)
        moves += [up, tuple(-x for x in up)]
    return moves


def undecidable(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike, hit: bool,
                tmax: float = math.inf) -> bool:  # fmt: skip
    from study.truth import PERTURBATIONS, perturbed

    oa, da = np.asarray(o, dtype=np.float64), np.asarray(d, dtype=np.float64)
    near = _near_critical(tor, oa, da)
    if not near:
        return False
    for signs in (*PERTURBATIONS, *_gradient_moves(tor, oa, da, near)):
        po, pd = perturbed(oa, da, signs)
        if decide(tor, po, pd, tmax) != hit:
            return True
    return False


def separation(tor: Torus, o: npt.ArrayLike, d: npt.ArrayLike, t: object) -> float:
    """|cos| of the angle between the ray and the tube's normal at the true hit: the sphere's
    half chord over the radius (truth.Truth.separation) for the tube. Near 0 the ray grazes
    and t is ill-conditioned. A label, not a truth: double precision is enough (rho - R is
    known to a few ulps of R, the normal's direction to those over r)."""
    dd = np.asarray(d, dtype=np.float64)
    p = np.asarray(o, dtype=np.float64) + float(t) * dd - np.array(tor.center)  # type: ignore[arg-type]
    rho = math.hypot(p[0], p[1])
    if rho == 0:
        return 0.0
    k = 1 - tor.major_radius / rho
    n = np.array([p[0] * k, p[1] * k, p[2]])
    nn = float(np.linalg.norm(n) * np.linalg.norm(dd))
    return abs(float(n @ dd)) / nn if nn > 0 else 0.0


def side(tor: Torus, p: npt.ArrayLike) -> int:
    """+1 outside the tube, -1 inside, 0 on it: the sign of Q at p, exactly."""
    pa = np.asarray(p, dtype=np.float64)
    pos, _ = _integers([*tor.center, tor.major_radius, tor.minor_radius, *pa])
    c, big_r, r, q = pos[0:3], pos[3], pos[4], pos[5:8]
    f = [q[k] - c[k] for k in range(3)]
    g = f[0] ** 2 + f[1] ** 2 + f[2] ** 2 + big_r**2 - r**2
    v = g * g - 4 * big_r**2 * (f[0] ** 2 + f[1] ** 2)
    return (v > 0) - (v < 0)


def side_exact(tor: Torus, p: Sequence[Fraction]) -> int:
    """side() for a point given as exact rationals."""
    c = [Fraction(float(x)) for x in tor.center]
    big_r, r = Fraction(tor.major_radius), Fraction(tor.minor_radius)
    f = [p[k] - c[k] for k in range(3)]
    g = f[0] ** 2 + f[1] ** 2 + f[2] ** 2 + big_r**2 - r**2
    v = g * g - 4 * big_r**2 * (f[0] ** 2 + f[1] ** 2)
    return (v > 0) - (v < 0)
