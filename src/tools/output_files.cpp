#include "output_files.h"

#include <dirent.h>
#include <signal.h>
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

/// The file a path names once its symlinks are followed (at most 40, as the kernel): the
/// path itself when it is none; the target of a dangling one. A relative target is read from
/// the link's directory. Written there, and renamed there, the link stays a link.
std::string followLinks(std::string path) {
  for (int hops = 0; hops < 40; ++hops) {
    struct stat s {};
    if (::lstat(path.c_str(), &s) != 0 || !S_ISLNK(s.st_mode)) return path;
    std::string target(static_cast<std::size_t>(s.st_size > 0 ? s.st_size : 4096) + 1, '\0');
    const ssize_t n = ::readlink(path.c_str(), &target[0], target.size());
    if (n < 0) return path;
    target.resize(static_cast<std::size_t>(n));
    if (target.empty()) return path;
    const auto slash = path.rfind('/');
    path = target.front() == '/' || slash == std::string::npos ? target
                                                               : path.substr(0, slash + 1) + target;
  }
  throw UsageError(path + ": too many levels of symbolic links");
}

/// Removes the temporary files `prefix`<pid> in `dir` left by runs that no longer exist (killed
/// by SIGKILL, or a power cut: no handler could remove them). Returns how many.
int removeLeftovers(const std::string& dir, const std::string& prefix) {
  DIR* d = ::opendir(dir.empty() ? "." : dir.c_str());
  if (d == nullptr) return 0;
  int removed = 0;
  while (const dirent* e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (name.compare(0, prefix.size(), prefix) != 0 || name.size() == prefix.size()) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9) continue;
    const long pid = std::stol(digits);
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // still running
    if (std::remove((dir + name).c_str()) == 0) ++removed;
  }
  ::closedir(d);
  return removed;
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
  {
    const auto slash = path_.rfind('/');
    if ((slash == std::string::npos ? path_ : path_.substr(slash + 1)).empty()) {
      throw UsageError(path_ + ": not a file name");
    }
  }
  // An output that is a symlink (dangling or not) is written where it points: renamed over its
  // own name, the link would be replaced by a regular file.
  path_ = followLinks(path_);
  const auto slash = path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
  const std::string name = slash == std::string::npos ? path_ : path_.substr(slash + 1);
  if (name.empty()) throw UsageError(path_ + ": not a file name");
  const std::string prefix = "." + name + ".partial-";
  leftovers_ = removeLeftovers(dir, prefix);
  temporary_ = dir + prefix + std::to_string(::getpid());
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
