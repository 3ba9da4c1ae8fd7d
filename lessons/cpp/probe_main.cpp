// The probe program of the grader (lessons/grader.py): it calls a submission's functions on the
// inputs of a probe file and prints what they return, one probe at a time, so that the grader
// (which never loads student code) compares them with values it computed on its own.
//
//   probe PROBES.txt TOKEN FIRST
//
// Each line of PROBES.txt is "index function arg...", the arguments as hexadecimal floats
// (exact). Probes from index FIRST on are run; before each the program prints
// "TOKEN begin index" and after it "TOKEN result index value...", values as %a (exact), flushed
// at once, so that a crash or a hang names the probe that was running and the grader can go on
// from the next one. A stub (rt::NotImplemented) is caught and reported per probe.
// The probes themselves are in lessons/cpp/probe.h (what they share) and each graded lesson's
// each lesson folder's probes.h (RT_PROBE(function) { ... }), placed before this file.
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "not_implemented.h"

using namespace rt;

namespace {

std::string run(const std::string &function, probe::Args &a) {
    auto found = probe::table().find(function);
    return found == probe::table().end() ? " unknown" : found->second(a);
}

} // namespace

int main(int argc, char **argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: probe PROBES.txt TOKEN FIRST\n");
        return 2;
    }
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    const std::string token = argv[2];
    const long first = std::strtol(argv[3], nullptr, 10);
    std::ifstream file(argv[1]);
    std::string line;
    while (std::getline(file, line)) {
        std::istringstream fields(line);
        long index = -1;
        std::string function, word;
        fields >> index >> function;
        if (index < first) continue;
        probe::Args a;
        while (fields >> word) a.v.push_back(std::strtod(word.c_str(), nullptr));
        std::printf("\n%s begin %ld\n", token.c_str(), index);
        std::fflush(stdout);
        std::string result;
        try {
            result = run(function, a);
        } catch (const NotImplemented &error) {
            std::printf("\n%s not_implemented %ld %s\n", token.c_str(), index, error.what());
            std::fflush(stdout);
            continue;
        } catch (const std::exception &error) {
            std::printf("\n%s exception %ld %s\n", token.c_str(), index, error.what());
            std::fflush(stdout);
            continue;
        }
        std::printf("\n%s result %ld%s\n", token.c_str(), index, result.c_str());
        std::fflush(stdout);
    }
    return 0;
}
