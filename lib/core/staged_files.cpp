// Staged outputs (staged_files.h).
#include "core/staged_files.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace rs {

std::string temporaryPathFor(const std::string& path) {
    std::filesystem::path p(path);
    return (p.parent_path() / ("." + p.filename().string() + ".tmp" + std::to_string(getpid()))).string();
}

void commitTemporary(const std::string& tmp, const std::string& path) {
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::string why = ec.message();
        std::filesystem::remove(tmp, ec);
        throw Error(ErrorKind::Io, path + ": cannot write: " + why);
    }
}

void writeFileTo(const std::string& file, const std::string& path, const std::string& contents) {
    std::ofstream f(file, std::ios::binary);
    if (!f) throw Error(ErrorKind::Io, path + ": cannot write (directory missing or not writable)");
    f.write(contents.data(), std::streamsize(contents.size()));
    f.close();
    if (!f) {
        std::error_code ec;
        std::filesystem::remove(file, ec);
        throw Error(ErrorKind::Io, path + ": write failed");
    }
}

StagedFiles::~StagedFiles() {
    std::error_code ec;
    for (const auto& f : files_) std::filesystem::remove(f.first, ec);
}

std::string StagedFiles::stage(const std::string& path) {
    files_.emplace_back(temporaryPathFor(path), path);
    return files_.back().first;
}

void StagedFiles::commit() {
    // Renames are atomic one by one; if one fails, the files already renamed are removed
    // again, so the set appears whole or not at all.
    size_t done = 0;
    try {
        for (; done < files_.size(); ++done) commitTemporary(files_[done].first, files_[done].second);
    } catch (...) {
        std::error_code ec;
        for (size_t i = 0; i < done; ++i) std::filesystem::remove(files_[i].second, ec);
        throw;
    }
    files_.clear();
}

}  // namespace rs
