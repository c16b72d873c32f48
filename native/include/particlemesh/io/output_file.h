// Writing files safely. Every writer of particlemesh (meshes, clouds, images, reports)
// writes through OutputFile:
//
//  - A regular file (new or existing) is written under a temporary name in the same folder
//    and renamed onto its name only when complete, so it is either the complete new file or
//    untouched. The temporary is created exclusively (O_CREAT | O_EXCL | O_NOFOLLOW, a random
//    name such as ".pm3k9x2q7dwa.ply", short enough for any legal file name): a link planted in
//    the folder is never followed, and no other file is ever overwritten.
//  - A file that is replaced keeps its permissions (and its owner, where the process may set
//    it). A regular file with several hard links is rewritten in place once the complete new
//    contents are ready, so every name sees them (renaming would detach this name).
//  - Anything that is not a regular file - a device (/dev/null), a FIFO, a socket,
//    /dev/stdout, /dev/stderr, /dev/fd/N - is written straight through: it is never
//    replaced by a file.
//  - A symbolic link at the path is kept: the file it points to is written (a dangling link
//    creates its target).
//
// Programs that handle signals (the CLI) call remove_unfinished_outputs() from their
// handlers, so that a run killed by SIGTERM, SIGHUP, ... leaves no temporary file.
#pragma once

#include "particlemesh/core/config.h"

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "particlemesh/core/export.h"

namespace PM_NAMESPACE {

/// Check, before any work, that `path` can be written: its folder exists and may be written
/// in, it is not a folder, an existing file there is writable (a file without any write
/// permission bit is refused whoever runs the program: write protection is respected), its
/// name is not too long. Devices and FIFOs only need to be writable.
/// @throws Error(InvalidArgument) naming the path and the problem.
PM_EXPORT void check_output_path(const std::string& path);

/// Whether `a` and `b` name the same file: through links, "..", another spelling. Existing
/// files are compared by device and inode; a path that does not exist yet by its resolved
/// folder and name.
PM_EXPORT bool same_file(const std::string& a, const std::string& b);

/// Whether `path` is written straight through (not a regular file, nor a new one): a
/// device, a FIFO, a socket, /dev/stdout, /dev/stderr, /dev/fd/N.
PM_EXPORT bool is_stream_output(const std::string& path);

class PM_EXPORT OutputFile {
 public:
  /// Creates the temporary file (or opens the device / FIFO / standard stream).
  /// @throws Error(IoError) naming `path`: a missing folder, no permission, a folder there.
  explicit OutputFile(const std::string& path);
  /// Removes the temporary file unless commit() succeeded.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// The path as given.
  const std::string& path() const;
  /// Whether this output is written straight through (see is_stream_output).
  bool streams() const;

  /// Append bytes (buffered). @throws Error(IoError) naming the path and the reason (No
  /// space left on device, File too large, ...).
  void write(const void* data, size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }

  /// For a library that writes by file name (PCL): closes our handle and returns the path
  /// to write to - the temporary, or the target itself for a stream. Nothing may have been
  /// written through write() before, nor after.
  std::string path_for_external_writer();

  /// Flush and close. @throws Error(IoError).
  void finish();
  /// Put the finished file in place (finish() first if not done). A stream: nothing to do.
  /// @throws Error(IoError).
  void commit();

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// Removes the temporary files of every OutputFile of the process that is not committed.
/// Async-signal-safe: meant for a program's signal handlers, before it exits.
PM_EXPORT void remove_unfinished_outputs() noexcept;

}  // namespace particlemesh
