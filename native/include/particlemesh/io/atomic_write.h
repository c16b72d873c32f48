// Writing small files (reports, sidecars) with the same guarantees as the mesh writers.
#pragma once

#include "particlemesh/core/config.h"

#include <string>

#include "particlemesh/core/export.h"

namespace PM_NAMESPACE {

/// Write `contents` to `path` through an OutputFile (see particlemesh/io/output_file.h): a
/// regular file is either the complete new file or untouched; a device or FIFO is written
/// straight through. @throws Error(IoError).
PM_EXPORT void write_file_atomically(const std::string& path, const std::string& contents);

}  // namespace particlemesh
