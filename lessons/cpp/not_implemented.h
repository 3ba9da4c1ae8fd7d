// What a stub of a student tree calls (rtlab lesson student): the function is not written yet.
// It never returns a value that could be taken for an answer: it throws rt::NotImplemented,
// which the Python extension reports as a RuntimeError naming the lesson and the function.
// Thrown in one of the render's worker threads, where nothing catches it, it would end the
// process through std::terminate (SIGABRT, a crash); the handler below turns that into a
// message on stderr and exit status 86, which the grader reads as "not implemented".
#pragma once

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>

namespace rt {

// The exit status of a process ended by a stub that no one caught.
constexpr int not_implemented_status = 86;

struct NotImplemented : std::logic_error {
    NotImplemented(const std::string &lesson, const std::string &function)
        : std::logic_error("not implemented: " + function + " (lesson " + lesson +
                           "): write it between its BEGIN SOLUTION and END SOLUTION lines") {}
};

namespace detail {
inline std::terminate_handler previous_terminate = nullptr;

[[noreturn]] inline void on_terminate() {
    if (std::exception_ptr e = std::current_exception()) {
        try {
            std::rethrow_exception(e);
        } catch (const NotImplemented &error) {
            std::fprintf(stderr, "rtlab: %s\n", error.what());
            std::fflush(stderr);
            std::_Exit(not_implemented_status);
        } catch (...) {
        }
    }
    if (previous_terminate) previous_terminate();
    std::abort();
}

// Installed once, when the program (or the extension) loads.
inline const bool terminate_installed = [] {
    previous_terminate = std::set_terminate(on_terminate);
    return true;
}();
} // namespace detail

// The parameters are passed on only so that a stub leaves none unused (-Wextra).
template <class... Args>
[[noreturn]] inline void not_implemented(const char *lesson, const char *function,
                                         const Args &...) {
    throw NotImplemented(lesson, function);
}

} // namespace rt
