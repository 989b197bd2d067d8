// The command's two ways of telling its progress (core/log.h's Reporter): for people, a bar on a
// terminal and plain lines otherwise (nothing with --quiet); for programs (--progress json), one
// JSON object a line on stderr, as the Blender add-on reads them.
#pragma once

#include <memory>
#include <string>

#include "core/log.h"

namespace rs::cli {

// The library names settings in backticks (`spp`); on the command line they are flags, spelt
// the same with two dashes (the output file: -o).
std::string withFlags(const std::string& message);

std::unique_ptr<Reporter> makeReporter(bool quiet, bool json);

// The last JSON line of a finished command: {"event": "done", "output": …, "seconds": …}.
void reportDone(bool json, const std::string& output, double seconds);

}  // namespace rs::cli
