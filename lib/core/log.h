// How the library talks to whoever runs it: a log sink for messages and a progress
// interface for long work. The CLI implements both (progress bars on a TTY, plain lines
// otherwise, nothing with --quiet); tests use the silent defaults.
#pragma once

#include <cstdint>
#include <string>

namespace rs {

class Reporter {
public:
    virtual ~Reporter() = default;
    virtual void info(const std::string&) {}
    virtual void warn(const std::string&) {}
    // A stage begins `total` units of work (e.g. "rows", "photons"); advance() may be called
    // from any thread; end() once when the stage is done.
    virtual void begin(const std::string& /*stage*/, int64_t /*total*/, const char* /*unit*/) {}
    virtual void advance(int64_t /*units*/) {}
    virtual void end() {}
    // A walkthrough's frame `frame` begins, `left` frames of the run after it, about
    // `secondsLeft` seconds for them all with it (< 0: not known yet). What follows is that frame's.
    virtual void frame(int /*frame*/, int /*left*/, double /*secondsLeft*/) {}
};

// A reporter that says nothing; the default of every stage.
Reporter& silentReporter();

}  // namespace rs
