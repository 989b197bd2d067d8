// Outputs written whole or not at all: each file is written under a temporary name beside it
// and renamed into place together with the others of its run (docs/design.md §10).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace rs {

// Writes `contents` to `file` as is (the caller stages it); throws Error(Io) naming `path`.
void writeFileTo(const std::string& file, const std::string& path, const std::string& contents);
// The temporary name used for an atomic write of `path`, in the same directory.
std::string temporaryPathFor(const std::string& path);
// Renames tmp to path; on failure removes tmp and throws Error(Io) naming path.
void commitTemporary(const std::string& tmp, const std::string& path);

// Several outputs that appear together or not at all: each is written under its temporary
// name; commit() renames them all; files not committed are removed on destruction.
class StagedFiles {
public:
    ~StagedFiles();
    std::string stage(const std::string& path);  // returns the temporary name to write
    void commit();

private:
    std::vector<std::pair<std::string, std::string>> files_;  // temporary, final
};

}  // namespace rs
