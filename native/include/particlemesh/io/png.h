// PNG images through libpng (Debian's libpng16), for the renderer and its tests.
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <string>
#include <vector>

#include "particlemesh/core/export.h"
#include "particlemesh/io/output_file.h"

namespace PM_NAMESPACE {

/// An 8-bit RGB image, rows top to bottom, pixels left to right, 3 bytes per pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgb;  ///< width * height * 3 bytes

  uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (size_t(y) * size_t(width) + size_t(x)); }
  const uint8_t* pixel(int x, int y) const { return rgb.data() + 3 * (size_t(y) * size_t(width) + size_t(x)); }
};

/// Write an 8-bit RGB PNG through an OutputFile (complete or untouched; a device or FIFO
/// written straight through).
/// @throws Error(InvalidArgument) an empty image or a pixel buffer of the wrong size;
///         Error(IoError) the file cannot be written.
PM_EXPORT void write_png(const Image& image, const std::string& path);

/// Write the PNG's bytes into `out` (the caller commits it).
PM_EXPORT void write_png(const Image& image, OutputFile& out);

/// Read a PNG of any colour type and depth as 8-bit RGB (alpha composited on black).
/// @throws Error(IoError) the file cannot be opened; Error(FormatError) it is not a PNG.
PM_EXPORT Image read_png(const std::string& path);

}  // namespace particlemesh
