// The one error type of the library. Only cli/ catches it; the message is one line that
// names the file and object the problem was found in.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace rs {

// OtherRank: another rank of a distributed render failed and said why (lib/ranks.h).
enum class ErrorKind { Io, Scene, Config, Gpu, Embree, Internal, Interrupted, OtherRank };

class Error : public std::runtime_error {
public:
    Error(ErrorKind kind, const std::string& message)
        : std::runtime_error(message), kind_(kind) {}
    ErrorKind kind() const { return kind_; }

private:
    ErrorKind kind_;
};

// Broken invariants are bugs, not user errors: abort with the place.
#define RS_CHECK(cond)                                                              \
    do {                                                                            \
        if (!(cond)) {                                                              \
            std::fprintf(stderr, "raysplat: internal check failed: %s (%s:%d)\n",  \
                         #cond, __FILE__, __LINE__);                                \
            std::abort();                                                           \
        }                                                                           \
    } while (0)

// The same for invariants tested inside hot loops: checked in builds without NDEBUG (the
// sanitizer build, debug builds), compiled out of release builds. `cond` is not evaluated there.
#ifndef NDEBUG
#define RS_DCHECK(cond) RS_CHECK(cond)
#else
#define RS_DCHECK(cond) \
    do {                \
        (void)sizeof(cond); \
    } while (0)
#endif

}  // namespace rs
