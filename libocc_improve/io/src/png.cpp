#include "occ_improve/io/png.hpp"

#include "occ_improve/io/atomic_file.hpp"
#include "occ_improve/errors.hpp"

#include <png.h>

#include <cstdio>
#include <new>
#include <ostream>
#include <string>

namespace occ_improve {
namespace {

// What the libpng callbacks share with encode_png. The message is a fixed buffer: the error callback
// runs inside libpng and must neither allocate (it could throw through C frames) nor return.
struct EncodeState {
  std::vector<std::uint8_t> bytes;
  char message[256] = "";
};

void keep_message_and_jump(png_structp png, png_const_charp message) {
  auto* state = static_cast<EncodeState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof state->message, "%s", message);
  png_longjmp(png, 1);
}
// libpng would print warnings to stderr; a library stays silent (and writing raises none we could act on).
void ignore_warning(png_structp, png_const_charp) {}

void append_bytes(png_structp png, png_bytep data, png_size_t length) {
  auto* state = static_cast<EncodeState*>(png_get_io_ptr(png));
  bool out_of_memory = false;
  try {
    state->bytes.insert(state->bytes.end(), data, data + length);
  } catch (const std::bad_alloc&) {
    out_of_memory = true;
  }
  // Outside the catch block: the jump must not leave an exception in flight.
  if (out_of_memory) png_error(png, "out of memory");
}
void flush_nothing(png_structp) {}

bool is_big_endian() {
  const std::uint16_t probe = 1;
  return *reinterpret_cast<const std::uint8_t*>(&probe) == 0;
}

// Frees libpng's write and info structs on every way out, exceptions included.
struct PngWriter {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngWriter() { png_destroy_write_struct(&png, &info); }
};

// The PNG header fields of an image.
struct PngLayout {
  int width, height, bit_depth, colour_type;
};

// Every libpng call that may fail, in a function that owns no C++ object: an error's longjmp back to the
// setjmp skips no destructor. Returns false on a libpng error (the message is in the error pointer's state).
bool run_libpng(png_structp png, png_infop info, EncodeState* state, const PngLayout& layout, png_bytep* rows,
                int compression_level) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_write_fn(png, state, &append_bytes, &flush_nothing);
  png_set_IHDR(png, info, static_cast<png_uint_32>(layout.width), static_cast<png_uint_32>(layout.height),
               layout.bit_depth, layout.colour_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_compression_level(png, compression_level);
  png_write_info(png, info);
  // Our 16-bit samples are in host order; PNG's are big-endian.
  if (layout.bit_depth == 16 && !is_big_endian()) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  return true;
}

// The encoding shared by 8-bit and 16-bit images: `pixels` holds height rows of row_bytes bytes.
std::vector<std::uint8_t> encode_rows(const PngLayout& layout, const std::uint8_t* pixels, std::size_t row_bytes,
                                      int compression_level) {
  detail::require_parameter(compression_level >= 0 && compression_level <= 9, "compression_level",
                            compression_level, "in [0, 9]");
  // libpng takes non-const row pointers but only reads them when writing.
  std::vector<png_bytep> rows(static_cast<std::size_t>(layout.height));
  for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = const_cast<png_bytep>(pixels + y * row_bytes);

  EncodeState state;
  PngWriter writer;
  writer.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &state, &keep_message_and_jump, &ignore_warning);
  writer.info = writer.png ? png_create_info_struct(writer.png) : nullptr;
  if (!writer.png || !writer.info) throw IoError("libpng could not be initialised to encode a PNG");
  if (!run_libpng(writer.png, writer.info, &state, layout, rows.data(), compression_level))
    throw IoError(std::string("libpng failed to encode a PNG: ") + state.message);
  return std::move(state.bytes);
}

void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  write_file_atomically(path, "PNG image", [&](std::ostream& out) {
    return static_cast<bool>(out.write(reinterpret_cast<const char*>(bytes.data()),
                                       static_cast<std::streamsize>(bytes.size())));
  });
}

void require_encodable(const Image& image) {
  if (image.width <= 0 || image.height <= 0 || (image.channels != 1 && image.channels != 3) ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) *
                                 static_cast<std::size_t>(image.channels))
    throw InvalidInput("image of " + std::to_string(image.width) + " x " + std::to_string(image.height) + " x " +
                       std::to_string(image.channels) + " holds " + std::to_string(image.pixels.size()) +
                       " bytes (need width, height > 0 and 1 or 3 channels)");
}

}  // namespace

std::vector<std::uint8_t> encode_png(const Image& image, int compression_level) {
  require_encodable(image);
  const PngLayout layout{image.width, image.height, 8, image.channels == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB};
  return encode_rows(layout, image.pixels.data(),
                     static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.channels),
                     compression_level);
}

void write_png(const std::string& path, const Image& image) { write_bytes(path, encode_png(image)); }

std::vector<std::uint8_t> encode_png(const Image16& image, int compression_level) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height))
    throw InvalidInput("16-bit image of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " holds " + std::to_string(image.pixels.size()) + " values (need width, height > 0)");
  const PngLayout layout{image.width, image.height, 16, PNG_COLOR_TYPE_GRAY};
  return encode_rows(layout, reinterpret_cast<const std::uint8_t*>(image.pixels.data()),
                     static_cast<std::size_t>(image.width) * sizeof(std::uint16_t), compression_level);
}

void write_png(const std::string& path, const Image16& image) { write_bytes(path, encode_png(image)); }

}  // namespace occ_improve
