// PNG through libpng's simplified API (png_image_*, libpng >= 1.6): no setjmp/longjmp, errors
// come back as a message in png_image.
#include "particlemesh/io/png.h"

#include <png.h>

#include <cstring>
#include <fstream>
#include <memory>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE {

void write_png(const Image& image, const std::string& path) {
  OutputFile out(path);
  write_png(image, out);
  out.commit();
}

void write_png(const Image& image, OutputFile& out) {
  const std::string& path = out.path();
  if (image.width <= 0 || image.height <= 0)
    throw Error(Status::InvalidArgument, "cannot write an empty image (" + std::to_string(image.width) + " x " +
                                             std::to_string(image.height) + ") to " + path);
  if (image.rgb.size() != size_t(image.width) * size_t(image.height) * 3)
    throw Error(Status::InvalidArgument, "image pixel buffer has " + std::to_string(image.rgb.size()) +
                                             " bytes, expected width x height x 3");
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(image.width);
  png.height = png_uint_32(image.height);
  png.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.rgb.data(), 0, nullptr))
    throw Error(Status::IoError, std::string("cannot encode PNG for ") + path + ": " + png.message);
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, image.rgb.data(), 0, nullptr))
    throw Error(Status::IoError, std::string("cannot encode PNG for ") + path + ": " + png.message);
  bytes.resize(size);
  out.write(bytes);
}

Image read_png(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw Error(Status::IoError, "cannot open " + path);
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&png, bytes.data(), bytes.size()))
    throw Error(Status::FormatError, path + " is not a readable PNG: " + png.message);
  png.format = PNG_FORMAT_RGB;
  Image img;
  img.width = int(png.width);
  img.height = int(png.height);
  img.rgb.resize(PNG_IMAGE_SIZE(png));
  const png_color black{0, 0, 0};
  if (!png_image_finish_read(&png, &black, img.rgb.data(), 0, nullptr)) {
    png_image_free(&png);
    throw Error(Status::FormatError, path + " is not a readable PNG: " + png.message);
  }
  return img;
}

}  // namespace particlemesh
