#include "core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace sweepmap {
namespace {

std::string errnoText() { return std::strerror(errno); }

std::string parentDir(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

void fsyncPath(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error("cannot open " + path + ": " + errnoText());
  const int rc = ::fsync(fd);
  const std::string err = rc != 0 ? errnoText() : std::string();
  ::close(fd);
  if (rc != 0) throw std::runtime_error("cannot fsync " + path + ": " + err);
}

}  // namespace

std::string tmpPathFor(const std::string& path) { return path + ".tmp"; }

void commitTmpFile(const std::string& tmp_path, const std::string& path) {
  try {
    fsyncPath(tmp_path, O_RDONLY);
    if (std::rename(tmp_path.c_str(), path.c_str()) != 0) {
      throw std::runtime_error("cannot rename " + tmp_path + " to " + path + ": " + errnoText());
    }
  } catch (const std::exception& e) {
    std::remove(tmp_path.c_str());
    throw std::runtime_error("cannot save " + path + ": " + e.what());
  }
  // The data is safe; syncing the directory makes the rename itself durable. Some file
  // systems refuse fsync on a directory: that is not worth failing the save for.
  try {
    fsyncPath(parentDir(path), O_RDONLY | O_DIRECTORY);
  } catch (const std::exception&) {
  }
}

void writeFileAtomic(const std::string& path, std::string_view bytes) {
  const std::string tmp = tmpPathFor(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    throw std::runtime_error("cannot save " + path + ": cannot create " + tmp + ": " + errnoText());
  const char* data = bytes.data();
  size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, data, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string err = errnoText();
      ::close(fd);
      std::remove(tmp.c_str());
      throw std::runtime_error("cannot save " + path + ": write failed: " + err);
    }
    data += n;
    left -= static_cast<size_t>(n);
  }
  if (::close(fd) != 0) {
    const std::string err = errnoText();
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot save " + path + ": close failed: " + err);
  }
  commitTmpFile(tmp, path);
}

}  // namespace sweepmap
