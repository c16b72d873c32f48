// Writing small files (reports, sidecars) with the same guarantee as the mesh writers.
#pragma once

#include <string>

#include "particlemesh/core/export.h"

namespace particlemesh {

/// Write `contents` to `path` through a temporary file in the same folder and a rename, so
/// `path` is either the complete new file or untouched. @throws Error(IoError).
PM_EXPORT void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace particlemesh
