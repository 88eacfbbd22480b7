#include "occ_improve/io/png.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/atomic_file.hpp"
#include "image_read.hpp"

#include <png.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <vector>

namespace occ_improve {
namespace {

// libpng reports errors through a callback that must not return: keep the message, jump back.
void png_error_to_string(png_structp png, png_const_charp message) {
  *static_cast<std::string*>(png_get_error_ptr(png)) = message;
  png_longjmp(png, 1);
}
void png_ignore_warning(png_structp, png_const_charp) {}

// Frees libpng's read and info structs on every way out, exceptions included.
struct PngReader {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngReader() { png_destroy_read_struct(&png, &info, nullptr); }
};

}  // namespace

DepthImage16 detail::read_grey_png(const std::string& path, const std::string& what, bool accept_8bit) {
  throw_if_folder(path, what);
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError("cannot open " + what + " '" + path + "'");
  unsigned char signature[8];
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
    throw FormatError("'" + path + "' is not a PNG file");
  std::error_code ec;
  const std::uint64_t file_size = std::filesystem::file_size(path, ec);
  std::string png_message;
  PngReader reader;
  reader.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &png_message, &png_error_to_string, &png_ignore_warning);
  reader.info = reader.png ? png_create_info_struct(reader.png) : nullptr;
  if (!reader.png || !reader.info) throw IoError("libpng could not be initialised");
  png_structp png = reader.png;
  png_infop info = reader.info;
  DepthImage16 image;
  std::vector<std::uint8_t> narrow;  // 8-bit samples, widened after reading
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) throw FormatError("'" + path + "' is a corrupt or truncated PNG (" + png_message + ")");
  png_init_io(png, file.get());
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  const int bit_depth = png_get_bit_depth(png, info), colour = png_get_color_type(png, info);
  if ((bit_depth != 16 && !accept_8bit) || colour != PNG_COLOR_TYPE_GRAY) {
    std::ostringstream m;
    m << "'" << path << "' is a " << bit_depth << "-bit PNG of colour type " << colour << ": a " << what
      << " must be " << (accept_8bit ? "8-bit or 16-bit" : "16-bit") << " single-channel (grey)";
    throw FormatError(m.str());
  }
  // Deflate expands at most ~1032-fold: a file cannot hold more pixels of bit_depth bits than that. (At 2
  // bytes a pixel whatever the depth, a compact 8-bit or 1-bit mask, a square on black, was refused.)
  detail::require_image_size(what, path, png_get_image_width(png, info), png_get_image_height(png, info),
                             ec ? kMaxDepthImagePixels : file_size * 1032 * 8 / static_cast<std::uint64_t>(bit_depth));
  if (bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (bit_depth == 16) png_set_swap(png);  // PNG is big-endian; we read host-order uint16
  image.width = static_cast<int>(png_get_image_width(png, info));
  image.height = static_cast<int>(png_get_image_height(png, info));
  const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  image.values.resize(pixels);
  if (bit_depth < 16) narrow.resize(pixels);
  rows.resize(static_cast<std::size_t>(image.height));
  for (int v = 0; v < image.height; ++v) {
    const std::size_t offset = static_cast<std::size_t>(v) * static_cast<std::size_t>(image.width);
    rows[static_cast<std::size_t>(v)] =
        bit_depth == 16 ? reinterpret_cast<png_bytep>(image.values.data() + offset) : narrow.data() + offset;
  }
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  if (bit_depth < 16) std::copy(narrow.begin(), narrow.end(), image.values.begin());
  return image;
}

PixelMask read_mask_png(const std::string& path) {
  const DepthImage16 image = detail::read_grey_png(path, "mask", true);
  PixelMask mask;
  mask.width = image.width;
  mask.height = image.height;
  mask.valid.resize(image.values.size());
  for (std::size_t i = 0; i < image.values.size(); ++i) mask.valid[i] = image.values[i] != 0;
  return mask;
}

}  // namespace occ_improve
