// Status codes and the one exception type of the C++ API.
//
// The C++ API reports failure by throwing particlemesh::Error; the C ABI (particlemesh.h)
// turns it into a pm_status and a message. The numeric values are shared with pm_status and
// never change meaning.
#pragma once

#include "particlemesh/core/config.h"

#include <stdexcept>
#include <string>

#include "particlemesh/core/export.h"

namespace PM_NAMESPACE {

enum class Status : int {
  Ok = 0,
  InvalidArgument = 1,  ///< a parameter is out of range or a pointer/size is wrong
  InvalidInput = 2,     ///< the data is unusable (NaN coordinate, empty cloud, ...)
  IoError = 3,          ///< a file could not be opened, read or written
  FormatError = 4,      ///< a file was read but its contents are malformed
  OutOfMemory = 5,
  Cancelled = 6,        ///< the progress callback asked to stop
  LimitExceeded = 7,    ///< a resource limit (neighbours per point, triangles, ...) was hit
  Internal = 8,         ///< a bug: an invariant of the library did not hold
};

/// Short, stable name of a status ("invalid argument", ...).
PM_EXPORT const char* status_name(Status status) noexcept;

/// The exception thrown by every function of the C++ API on failure.
/// what() is a one-line message naming what was wrong (argument, file, point index).
class PM_EXPORT Error : public std::runtime_error {
 public:
  Error(Status status, const std::string& message) : std::runtime_error(message), status_(status) {}
  Status status() const noexcept { return status_; }

 private:
  Status status_;
};

}  // namespace particlemesh
