// Internal: write-to-temporary-then-rename, so a failed write never leaves a file that
// looks complete under the requested name.
#pragma once

#include <filesystem>
#include <string>

namespace particlemesh::detail {

class AtomicFile {
 public:
  /// Picks a temporary path next to `target`, keeping its extension (OpenMesh chooses the
  /// writer by extension).
  explicit AtomicFile(const std::string& target);
  ~AtomicFile();  // removes the temporary file unless commit() succeeded
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& temp_path() const { return temp_; }
  /// Rename the temporary file onto the target. @throws Error(IoError).
  void commit();

 private:
  std::string target_;
  std::string temp_;
  bool committed_ = false;
};

}  // namespace particlemesh::detail
