// The constants every file shares, defined once.
#pragma once

#include <limits>

namespace rt {

// A ray parameter, a distance or an interval's end that nothing reaches: IEEE-754's infinity,
// which compares greater than every finite double and survives min() and max().
constexpr double infinity = std::numeric_limits<double>::infinity();

// The double nearest pi: 21 significant digits, more than the 17 that single out a double.
// (std::numbers::pi is C++20; M_PI is POSIX, not standard C++.)
constexpr double pi = 3.14159265358979323846;

} // namespace rt
