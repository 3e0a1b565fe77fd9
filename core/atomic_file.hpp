// Atomic file replacement for outputs other processes or users may read while we write:
// data goes to `path + ".tmp"` in the same directory, is flushed to disk, then renamed
// over `path` (rename(2) is atomic within one file system). A reader sees either the
// old file or the complete new one, never a torn one.
#pragma once

#include <string>
#include <string_view>

namespace sweepmap {

// The temporary name used for `path`: same directory, so the rename cannot cross devices.
std::string tmpPathFor(const std::string& path);

// fsync()s `tmp_path`, renames it to `path`, and fsync()s the directory. On failure removes
// `tmp_path` and throws std::runtime_error naming `path`.
void commitTmpFile(const std::string& tmp_path, const std::string& path);

// Writes `bytes` to tmpPathFor(path), then commitTmpFile(). Throws std::runtime_error
// naming `path` on failure, leaving no temporary file behind.
void writeFileAtomic(const std::string& path, std::string_view bytes);

}  // namespace sweepmap
