// x^n for the Phong highlight, max(R.L, 0)^shininess, written once for one ray (double) and for
// a packet of rays (Lanes, 12_packet.h), so that both compute the same bits.
//
// std::pow cannot be vectorised, and one call per lane cost the packet tracer about a tenth of
// its time. A whole exponent from 1 to 1024 is raised by repeated squaring (power_by_squaring()
// below); any other goes the textbook route, x^n = exp(n ln x), in double precision:
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

// Rays per packet (12_packet.h, 22_mesh_packets.h): as many doubles as fill the widest vector
// register the build may use: 8 with AVX-512, 4 with AVX or AVX2, 2 with SSE2 alone. A vector
// wider than the machine's registers is split by the compiler, but not everything splits:
// with 8 lanes on AVX2, GCC 12 compiled each comparison of two vectors of doubles (a Mask)
// lane by lane, eight scalar compares, branches and stores read back as one vector, and Ex 25
// at 1920x1024 took 735 ms on one Zen 4 thread, 2.1x the one-ray tracer's 344 ms; with 4
// lanes, 97 ms (the bunny's primary packets 602 against 76 ms; -march=x86-64-v3 builds, issue
// 12). The lanes' arithmetic is the same at every width, so each lane's bits are too.
#if defined(__AVX512F__)
constexpr int rays_per_packet = 8;
#elif defined(__AVX__)
constexpr int rays_per_packet = 4;
#else
constexpr int rays_per_packet = 2;
#endif

typedef double Lanes __attribute__((vector_size(rays_per_packet * sizeof(double))));
typedef int64_t Mask
    __attribute__((vector_size(rays_per_packet * sizeof(int64_t)))); // lane true: all ones

template <class To, class From> inline To bit_cast(const From &from) {
    static_assert(sizeof(To) == sizeof(From));
    To to;
    std::memcpy(&to, &from, sizeof to);
    return to;
}

// A scalar in every lane of a vector V, by one broadcast. Not V{} + v: 0 + v is not v where v is
// -0 (it is +0), so the compiler must add before it broadcasts, a scalar add per splat, 4% of
// the instructions of Ex 25's packet tracer (callgrind, AVX2 build, issue 12) and a step more
// on every path through a splat value. v - 0 is v for every v (-0 - 0 = -0), so the compiler
// drops the subtraction and broadcasts v itself, which is also what the one-ray code uses.
template <class V, class S> inline V broadcast(S v) { return v - V{}; }

inline int64_t bits(double x) { return bit_cast<int64_t>(x); }
inline Mask bits(Lanes x) { return bit_cast<Mask>(x); }
inline double select(bool m, double a, double b) { return m ? a : b; }
inline Lanes select(Mask m, Lanes a, Lanes b) { return m ? a : b; }

// Whether some lane of a mask is true, or every lane is (a bool for the one ray). Reductions
// without an early exit, which the compiler keeps in vector registers (a loop that returns at
// the first true lane took each lane out of the register one by one: 12_packet.h lane_bits()).
inline bool any_lane(bool m) { return m; }
inline bool all_lanes(bool m) { return m; }
inline bool any_lane(Mask m) {
    int64_t r = 0;
    for (int k = 0; k < rays_per_packet; ++k) r |= m[k];
    return r != 0;
}
inline bool all_lanes(Mask m) {
    int64_t r = -1;
    for (int k = 0; k < rays_per_packet; ++k) r &= m[k];
    return r != 0;
}

// x^n for a whole n from 1 to max_whole_exponent, by repeated squaring: x^60 = x^32 x^16 x^8
// x^4, five squarings and three products instead of the ~75 operations of exp(n ln x) below
// (Ex 25's spheres have shininess 60: 1.03x on its render, issue 12). Error: x^(2^j) after j
// squarings carries 2^j - 1 roundings (each squaring doubles the count it is handed and adds
// one), and the product of the powers of n's m set bits adds m - 1 more (1 times the first is
// exact): n - 1 roundings in all, a relative error within gamma(n - 1) = (n - 1) u / (1 - (n -
// 1) u), u = 2^-53, at most 1.1e-13 for n <= 1024, no more than the route below allows
// (tests/tracer/test_stiff.py checks the bound against exact powers). n's bits are taken lowest
// first and a lane whose bits have run out keeps its product (a select, not a branch), so each
// lane computes what the one-ray code computes for it, however many squarings the packet's
// largest n asks for. x <= 1, so every factor of x^n is at least x^n: where x^n is a normal
// double nothing underflowed on the way, and below 2^-1022 it is flushed to 0 as below.
constexpr double max_whole_exponent = 1024;
// A product below 2^-1022 flushed to 0, as every route of power() flushes it.
template <class T> inline T flush_tiny(T product) {
    return select(product < 0x1p-1022, T{} + 0.0, product);
}
template <class T> inline T power_by_squaring(T x, T n) {
    using I = decltype(bits(x));
    I k;
    if constexpr (sizeof(T) == sizeof(double)) k = I(n);
    else k = __builtin_convertvector(n, I);
    T product = T{} + 1.0, square = x;
    int64_t bits_left = 0; // the bits of every lane's n, for the loop's count
    if constexpr (sizeof(T) == sizeof(double)) bits_left = k;
    else
        for (int l = 0; l < rays_per_packet; ++l) bits_left |= k[l];
    for (; bits_left != 0; bits_left >>= 1, k >>= 1) {
        product = select((k & 1) != 0, product * square, product);
        square = square * square;
    }
    return flush_tiny(product);
}

// n as power_by_squaring() takes it where it is a whole number from 1 to max_whole_exponent
// (power()'s test, for one exponent), else 0.
inline int whole_exponent(double n) {
    return n >= 1 && n <= max_whole_exponent && n == double(int(n)) ? int(n) : 0;
}

// power_by_squaring() for an exponent that every lane shares, given as a plain integer n (1 to
// max_whole_exponent): a packet whose rays met one material takes its shininess so
// (12_packet.h). The same products in the same order as power_by_squaring() makes in a lane
// whose exponent is n (the first, 1 times a power of x, exact either way), so the same bits;
// without its selects, its vector of the exponent's bits and its shifts, a dozen vector
// instructions a bit. Ex 25 1.038x [1.010-1.070] on one Xeon thread and 1.037x [1.022-1.043] on
// two (seven alternating rounds, the same image; issue 12); on the Zen 4 an earlier form of it
// measured 0.998x (reference/speed-log.md).
template <class T> inline T power_whole(T x, int n) {
    T product = T{} + 1.0, square = x;
    for (;;) {
        if (n & 1) product = product * square;
        n >>= 1;
        if (n == 0) break;
        square = square * square;
    }
    return flush_tiny(product);
}

template <class T> inline T power(T x, T n) {
    using I = decltype(bits(x));
    // A whole exponent (Phong's usual 10, 60, 100) by squaring, in every lane that has one; the
    // route below for the others.
    const auto in_range = (n >= 1) & (n <= max_whole_exponent); // false for NaN
    const T n_or_1 = select(in_range, n, T{} + 1.0); // converts to an integer without overflow
    T whole_part;
    if constexpr (sizeof(T) == sizeof(double)) whole_part = T(I(n_or_1));
    else whole_part = __builtin_convertvector(__builtin_convertvector(n_or_1, I), T);
    const auto whole = in_range & (whole_part == n_or_1);
    if (all_lanes(whole)) return power_by_squaring(x, n);
    const T by_squaring = any_lane(whole) ? power_by_squaring(x, n_or_1) : x;
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
    return select(whole, by_squaring, select(underflow | tiny, T{} + 0.0, taylor * scale));
}

} // namespace rt
