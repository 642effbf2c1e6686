// The tools' outputs: never over an input, never past a full disk, and under their names only
// when complete.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace attitude_propagator {
namespace tools {

/// Throws UsageError when `output` is one of `inputs` under any spelling: the same device and
/// inode when it exists (a symlink, a hard link, "./in.bag"), the same canonical path
/// otherwise; or when it is a directory, a device or a pipe (the output is renamed over its
/// name at the end, which would replace them).
void refuseOutputOverInput(const std::string& output, const std::vector<std::string>& inputs);

/// Throws ToolError when the file system that holds `output` has fewer than `bytes` available
/// (statvfs of its directory), saying how much it needs and has.
void requireFreeSpace(const std::string& output, std::uint64_t bytes);

/// An output written under a temporary name in the same directory and renamed to its own
/// name by commit(): a failed or interrupted run leaves nothing under the name, and the
/// temporary file is removed (by the destructor, or by the signal handler on a second signal).
/// An output that is a symlink, dangling or not, is written where it points (the link stays).
/// Temporary files of the same output left by runs no longer running (SIGKILL, which no handler
/// sees) are removed when the next one starts (leftovers()).
class PendingFile {
 public:
  explicit PendingFile(std::string path);
  ~PendingFile();  // removes the temporary file unless committed
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;
  const std::string& temporary() const { return temporary_; }
  /// The file written: the output's name, its symlinks followed.
  const std::string& path() const { return path_; }
  /// Temporary files of this output from runs no longer running, removed at the start.
  int leftovers() const { return leftovers_; }
  void commit();

 private:
  std::string path_;
  std::string temporary_;
  bool committed_ = false;
  int leftovers_ = 0;
  int slot_ = -1;  // in the signal handler's list of files to remove
};

/// A FILE* with a large buffer, closed by the destructor. Errors name `name`, the user's
/// output (the file written may be its temporary name).
class CsvFile {
 public:
  CsvFile(const std::string& path, const std::string& name);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  std::FILE* get() { return file_; }
  /// Throws ToolError as soon as a write has failed (a full disk stops the run at once).
  void check();
  /// Throws ToolError when anything failed to reach the disk.
  void close();

 private:
  [[noreturn]] void fail(int error);
  std::string name_;
  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
};

}  // namespace tools
}  // namespace attitude_propagator
