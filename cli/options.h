// The command line's options: the flag parser, the help text, and the render and voxelize
// commands' flags read into a RenderConfig. Nothing here touches a file: the parser is fuzzed
// on its own (tests/fuzz, target cli).
#pragma once

#include <array>
#include <charconv>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "config.h"
#include "core/error.h"

namespace rs::cli {

struct Option {
    std::string name;  // "--spp"
    std::string arg;   // "N", or "" for a switch
    std::string help;
    std::function<void(const std::string&)> set;
    std::string shortName = "";  // "-o", or none
};

template <class T>
T parseNumber(const std::string& flag, const std::string& s) {
    T v{};
    const char* end = s.data() + s.size();
    auto [p, ec] = std::from_chars(s.data(), end, v);
    if (ec != std::errc() || p != end || s.empty())
        throw Error(ErrorKind::Config, flag + ": '" + s + "' is not a valid number");
    return v;
}

float parseFloat(const std::string& flag, const std::string& s);
// A count as digits, or as a whole number written with an exponent or a k, M or G suffix
// (1e6, 2M, 500k, 2.5M).
double parseCountValue(const std::string& flag, const std::string& s, double most);
template <class T>
T parseCount(const std::string& flag, const std::string& s) {
    T v{};
    const char* end = s.data() + s.size();
    auto [p, ec] = std::from_chars(s.data(), end, v);
    if (ec == std::errc() && p == end && !s.empty()) return v;
    return T(parseCountValue(flag, s, double(std::numeric_limits<T>::max())));
}
// "8G", "512M", "64k" or bytes → bytes (binary units).
uint64_t parseSize(const std::string& flag, const std::string& s);
// "24" or "1-48" (--frames): a walkthrough's first and last frame.
void parseFrames(const std::string& v, RenderConfig& cfg);
// "a,b,c" → three numbers.
void parseTriple(const std::string& flag, const std::string& s, std::array<float, 3>& out);

class Command {
public:
    Command(std::string usage, std::string summary) : usage_(std::move(usage)), summary_(std::move(summary)) {}
    void add(Option o) { options_.push_back(std::move(o)); }
    // Returns the positional arguments from argv[first] on; sets helpShown (and prints the help)
    // for -h or --help.
    std::vector<std::string> parse(int argc, char** argv, int first, bool& helpShown);
    void printHelp() const;

private:
    const Option* find(const std::string& name) const;
    std::string usage_, summary_;
    std::vector<Option> options_;
};

// `raysplat render …` and `raysplat voxelize …` (argv[1] is the command): the settings,
// validated, or an Error(Config) naming the flag.
struct Arguments {
    RenderConfig cfg;
    bool quiet = false;
    bool json = false;      // --progress json: progress and messages as JSON lines on stderr
    bool help = false;      // --help was given and printed: nothing else to do
    bool defaults = false;  // render --defaults: print the defaults as JSON, nothing else
};
Arguments parseRender(int argc, char** argv);
Arguments parseVoxelize(int argc, char** argv);

}  // namespace rs::cli
