#include "output_files.h"

#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "interrupts.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {

namespace {

std::string directoryOf(const std::string& path) {
  const auto slash = path.rfind('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

/// The absolute path without symlinks, "." or "..": of the file itself when it exists,
/// otherwise of its directory followed by its name.
std::string canonicalPath(const std::string& path) {
  if (char* full = ::realpath(path.c_str(), nullptr)) {
    const std::string text = full;
    std::free(full);
    return text;
  }
  const auto slash = path.rfind('/');
  const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (char* dir = ::realpath(directoryOf(path).c_str(), nullptr)) {
    const std::string text = std::string(dir) + "/" + name;
    std::free(dir);
    return text;
  }
  return path;
}

std::string megabytes(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f MB", double(bytes) / 1e6);
  return text;
}

}  // namespace

void refuseOutputOverInput(const std::string& output, const std::vector<std::string>& inputs) {
  struct stat out {};
  const bool exists = ::stat(output.c_str(), &out) == 0;
  if (exists && S_ISDIR(out.st_mode)) {
    throw UsageError(output + ": is a directory; give the output's file name");
  }
  if (exists && !S_ISREG(out.st_mode)) {
    // The output is written aside and renamed over its name: that would replace a device or a
    // pipe, not write into it.
    throw UsageError(output + ": is not a regular file (a device or a pipe); give a file name");
  }
  for (const std::string& input : inputs) {
    struct stat in {};
    const bool same = exists && ::stat(input.c_str(), &in) == 0
                          ? in.st_dev == out.st_dev && in.st_ino == out.st_ino
                          : canonicalPath(output) == canonicalPath(input);
    if (same) {
      throw UsageError(output + ": is the input " + input +
                       " (the same file); choose another output name");
    }
  }
}

void requireFreeSpace(const std::string& output, std::uint64_t bytes) {
  const std::string dir = directoryOf(output);
  struct statvfs fs {};
  if (::statvfs(dir.c_str(), &fs) != 0) {
    throw ToolError(output + ": cannot write into " + dir + " (" + std::strerror(errno) + ")");
  }
  // f_bavail: the blocks an unprivileged writer may use (root may use a few more).
  const std::uint64_t available = std::uint64_t(fs.f_bavail) * fs.f_frsize;
  if (available < bytes) {
    throw ToolError(output + ": needs about " + megabytes(bytes) + " and its file system has " +
                    megabytes(available) + " free; free some space or write elsewhere");
  }
}

PendingFile::PendingFile(std::string path) : path_(std::move(path)) {
  const auto slash = path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path_ : path_.substr(slash + 1);
  if (name.empty()) throw UsageError(path_ + ": not a file name");
  temporary_ = dir + "." + name + ".partial-" + std::to_string(::getpid());
  slot_ = registerPending(temporary_);
}

PendingFile::~PendingFile() {
  if (!committed_) std::remove(temporary_.c_str());
  unregisterPending(slot_);
}

void PendingFile::commit() {
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throw ToolError(path_ + ": cannot write (" + std::strerror(errno) + ")");
  }
  committed_ = true;
  unregisterPending(slot_);
  slot_ = -1;
}

CsvFile::CsvFile(const std::string& path, const std::string& name) : name_(name), buffer_(1 << 20) {
  file_ = std::fopen(path.c_str(), "w");
  if (!file_) throw ToolError(name + ": cannot write (" + std::strerror(errno) + ")");
  std::setvbuf(file_, buffer_.data(), _IOFBF, buffer_.size());
}

CsvFile::~CsvFile() {
  if (file_) std::fclose(file_);
}

void CsvFile::fail(int error) {
  throw ToolError(name_ + ": write failed (" + std::strerror(error) + ")");
}

void CsvFile::check() {
  // The error flag is set by the write that failed, when the buffer was flushed; errno still
  // holds its reason (no call since could have failed).
  if (std::ferror(file_)) fail(errno);
}

void CsvFile::close() {
  check();
  const int closed = std::fclose(file_);
  const int error = errno;
  file_ = nullptr;
  if (closed != 0) fail(error);
}

}  // namespace tools
}  // namespace attitude_propagator
