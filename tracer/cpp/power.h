// x^n for the Phong highlight, max(R.L, 0)^shininess, written once for one ray (double) and for
// a packet of rays (Lanes, 12_packet.h), so that both compute the same bits.
//
// std::pow cannot be vectorised, and one call per lane cost the packet tracer about a tenth of
// its time. This is the textbook route, x^n = exp(n ln x), in double precision:
//   ln x:  x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s), s = (m - 1)/(m + 1),
//          |s| <= 0.172, so the odd series of atanh to s^23 leaves a relative error below 1e-18;
//   exp z: z = k ln 2 + r, |r| <= ln(2)/2, exp(r) by its Taylor series to r^14 (error < 1e-17),
//          then times 2^k built from the exponent bits.
// ln 2 is split into a head with zeros in its low bits and a tail (Cody and Waite), so k ln 2 is
// subtracted without rounding error. The one error that grows is ln x's rounding (2^-53
// relative), multiplied by n: the result's relative error is about |n ln x| 2^-53, at most
// ~2e-13 where the result is still above 2^-1022 (tests/tracer/test_stiff.py checks 5e-13 against
// libm's pow), far below the 8e-6 that any comparison here can see. Only 0 < x <= 1 and n > 0
// occur (a cosine and a positive exponent); results below 2^-1022 are flushed to 0.
#pragma once

#include <cstdint>
#include <cstring>

namespace rt {

// Rays per packet (12_packet.h): 8 doubles fill one AVX-512 register (two AVX2 registers, four
// SSE2 ones: the compiler splits a wider vector, so the code is the same on every x86-64).
constexpr int rays_per_packet = 8;

typedef double Lanes __attribute__((vector_size(rays_per_packet * sizeof(double))));
typedef int64_t Mask
    __attribute__((vector_size(rays_per_packet * sizeof(int64_t)))); // lane true: all ones

template <class To, class From> inline To bit_cast(const From &from) {
    static_assert(sizeof(To) == sizeof(From));
    To to;
    std::memcpy(&to, &from, sizeof to);
    return to;
}

inline int64_t bits(double x) { return bit_cast<int64_t>(x); }
inline Mask bits(Lanes x) { return bit_cast<Mask>(x); }
inline double select(bool m, double a, double b) { return m ? a : b; }
inline Lanes select(Mask m, Lanes a, Lanes b) { return m ? a : b; }

template <class T> inline T power(T x, T n) {
    using I = decltype(bits(x));
    constexpr double ln2_hi = 0x1.62e42fee00000p-1; // ln 2 to 32 bits: k ln2_hi is exact
    constexpr double ln2_lo = 0x1.a39ef35793c76p-33;
    constexpr double sqrt_half = 0x1.6a09e667f3bcdp-1;
    constexpr double inv_ln2 = 0x1.71547652b82fep0; // 1 / ln 2

    // ln x. The exponent e and the mantissa m in [1, 2), then moved to [sqrt(1/2), sqrt(2)).
    // (An IEEE-754 double: 52 mantissa bits, above them 11 exponent bits (0x7ff) biased by 1023.)
    I xb = bits(x);
    I e = ((xb >> 52) & 0x7ff) - 1023;
    T m = bit_cast<T>((xb & ((int64_t(1) << 52) - 1)) | (int64_t(1023) << 52));
    auto high = m > 2 * sqrt_half;
    m = select(high, m * 0.5, m);
    e = e + (high ? I{} + 1 : I{});
    T s = (m - 1) / (m + 1), s2 = s * s;
    T series = T{} + 1.0 / 23;
    for (int k = 21; k >= 1; k -= 2) series = series * s2 + 1.0 / k;
    T ed;
    if constexpr (sizeof(T) == sizeof(double)) ed = T(e);
    else ed = __builtin_convertvector(e, Lanes);
    T z = n * (ed * ln2_hi + (2 * s * series + ed * ln2_lo)); // n ln x, <= 0
    // Below 2^-1100 the result is 0 whatever the rounding below; z is set to 0 there so that k
    // stays a small integer (the rounding trick needs |z / ln 2| < 2^51; a shininess of 1e300
    // gives z near -1e300).
    const auto underflow = z < -1100 * (ln2_hi + ln2_lo);
    z = select(underflow, T{} + 0.0, z);

    // exp z. k = round(z / ln 2) by the 1.5 2^52 trick (round to nearest, no library call).
    constexpr double shifter = 0x1.8p52;
    T kd = (z * inv_ln2 + shifter) - shifter;
    T r = (z - kd * ln2_hi) - kd * ln2_lo;
    T taylor = T{} + 1.0 / 87178291200.0; // 1/14!
    double factorial = 87178291200.0;
    for (int k = 14; k >= 1; --k) {
        factorial /= k;
        taylor = taylor * r + 1.0 / factorial;
    }
    I ki = bits(kd + shifter) - bits(T{} + shifter);
    // 2^k from its biased exponent k + 1023, for k >= -1022; below that the result is flushed
    // to 0, and the exponent is held at 1 so the shift never meets a negative number (undefined
    // behaviour in C++17).
    const auto tiny = ki < -1022;
    const I biased = tiny ? I{} + 1 : ki + 1023;
    T scale = bit_cast<T>(biased << 52);
    return select(underflow | tiny, T{} + 0.0, taylor * scale);
}

} // namespace rt
