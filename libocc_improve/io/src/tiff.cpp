#include "occ_improve/io/tiff.hpp"

#include "occ_improve/errors.hpp"
#include "image_read.hpp"

#include <tiffio.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <vector>

namespace occ_improve {
namespace {

// LZW's 12-bit codes stand for at most 4096 bytes (deflate's limit, ~1032, is lower): a compressed TIFF
// cannot decode to more than this many times its own size.
constexpr std::uint64_t kMaxCompressionRatio = 4096;
// libtiff's own cap on one allocation (strip buffers, tag arrays): above the largest image we accept.
constexpr tmsize_t kMaxLibtiffAllocation = tmsize_t{256} << 20;

// The first error libtiff reports for a file is its cause; later ones follow from it.
int keep_first_error(TIFF*, void* user_data, const char* module, const char* format, va_list args) {
  auto& message = *static_cast<std::string*>(user_data);
  if (message.empty()) {
    char text[512];
    std::vsnprintf(text, sizeof text, format, args);
    message = (module ? std::string(module) + ": " : std::string()) + text;
  }
  return 1;  // handled: libtiff calls no other handler
}
int ignore_warning(TIFF*, void*, const char*, const char*, va_list) { return 1; }

// The per-file handlers above cover everything libtiff reports about an open file; a few early paths still
// go to the process-wide handlers, which by default print to stderr. Those are silenced once.
void silence_global_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(nullptr);
    TIFFSetWarningHandler(nullptr);
  });
}

// An open TIFF with its error message, closed on every way out.
class TiffFile {
public:
  explicit TiffFile(const std::string& path) : path_(path) {
    if (std::unique_ptr<FILE, int (*)(FILE*)>(std::fopen(path.c_str(), "rb"), &std::fclose) == nullptr)
      throw IoError("cannot open TIFF image '" + path + "'");
    silence_global_handlers();
    std::unique_ptr<TIFFOpenOptions, void (*)(TIFFOpenOptions*)> options(TIFFOpenOptionsAlloc(), &TIFFOpenOptionsFree);
    if (!options) throw IoError("libtiff could not be initialised");
    TIFFOpenOptionsSetErrorHandlerExtR(options.get(), &keep_first_error, &message_);
    TIFFOpenOptionsSetWarningHandlerExtR(options.get(), &ignore_warning, nullptr);
    TIFFOpenOptionsSetMaxSingleMemAlloc(options.get(), kMaxLibtiffAllocation);
    tiff_.reset(TIFFOpenExt(path.c_str(), "r", options.get()));
    if (!tiff_) fail("is not a readable TIFF file");
    std::error_code ec;
    file_size_ = std::filesystem::file_size(path, ec);
    if (ec) file_size_ = 0;
  }

  [[noreturn]] void fail(const std::string& problem) const {
    throw FormatError("TIFF image '" + path_ + "' " + problem + (message_.empty() ? "" : " (" + message_ + ")"));
  }

  TIFF* get() const { return tiff_.get(); }

  std::uint16_t field16(ttag_t tag) const {
    std::uint16_t value = 0;
    TIFFGetFieldDefaulted(tiff_.get(), tag, &value);
    return value;
  }
  std::uint32_t field32(ttag_t tag) const {
    std::uint32_t value = 0;
    TIFFGetFieldDefaulted(tiff_.get(), tag, &value);
    return value;
  }

  // Width x height checked against the cap and against the file: `bytes_per_pixel` uncompressed, the
  // compression ratio bound otherwise.
  void require_size(const char* kind, std::uint32_t width, std::uint32_t height, std::uint64_t bytes_per_pixel) const {
    const bool compressed = field16(TIFFTAG_COMPRESSION) != COMPRESSION_NONE;
    const std::uint64_t can_hold = (compressed ? file_size_ * kMaxCompressionRatio : file_size_) / bytes_per_pixel;
    detail::require_image_size(kind, path_, width, height, can_hold);
  }

private:
  struct Close {
    void operator()(TIFF* tiff) const { TIFFClose(tiff); }
  };
  const std::string& path_;
  std::string message_;
  std::unique_ptr<TIFF, Close> tiff_;
  std::uint64_t file_size_ = 0;
};

}  // namespace

DepthImage16 read_tiff_depth16(const std::string& path) {
  const TiffFile file(path);
  TIFF* tiff = file.get();
  const std::uint16_t bits = file.field16(TIFFTAG_BITSPERSAMPLE), samples = file.field16(TIFFTAG_SAMPLESPERPIXEL),
                      format = file.field16(TIFFTAG_SAMPLEFORMAT);
  if (bits != 16 || samples != 1 || format != SAMPLEFORMAT_UINT)
    file.fail("has " + std::to_string(bits) + "-bit samples, " + std::to_string(samples) +
              " per pixel, sample format " + std::to_string(format) +
              ": a depth image must be 16-bit unsigned (sample format 1), 1 sample per pixel");
  if (TIFFIsTiled(tiff)) file.fail("is tiled: only TIFFs in strips are read");
  const std::uint32_t width = file.field32(TIFFTAG_IMAGEWIDTH), height = file.field32(TIFFTAG_IMAGELENGTH);
  file.require_size("depth image", width, height, 2);
  DepthImage16 image{static_cast<int>(width), static_cast<int>(height), {}};
  image.values.resize(std::size_t{width} * height);
  // Rows per strip defaults to "all of them" (2^32 - 1) when the tag is absent.
  const std::uint32_t rows_per_strip = std::clamp<std::uint32_t>(file.field32(TIFFTAG_ROWSPERSTRIP), 1, height);
  for (std::uint32_t row = 0, strip = 0; row < height; row += rows_per_strip, ++strip) {
    const std::uint32_t rows = std::min(rows_per_strip, height - row);
    const tmsize_t bytes = static_cast<tmsize_t>(std::size_t{rows} * width * 2);
    if (TIFFReadEncodedStrip(tiff, strip, image.values.data() + std::size_t{row} * width, bytes) != bytes)
      file.fail("is corrupt or truncated (strip " + std::to_string(strip) + ")");
  }
  return image;
}

Image read_tiff_rgb8(const std::string& path) {
  const TiffFile file(path);
  TIFF* tiff = file.get();
  char why[1024] = "";
  if (!TIFFRGBAImageOK(tiff, why)) file.fail(std::string("cannot be read as colour: ") + why);
  const std::uint32_t width = file.field32(TIFFTAG_IMAGEWIDTH), height = file.field32(TIFFTAG_IMAGELENGTH);
  // The RGBA raster is 4 bytes per pixel whatever the file stores; a file of fewer bytes is compressed.
  file.require_size("colour image", width, height, 1);
  std::vector<std::uint32_t> raster(std::size_t{width} * height);
  if (!TIFFReadRGBAImageOriented(tiff, width, height, raster.data(), ORIENTATION_TOPLEFT, 0))
    file.fail("is corrupt or truncated");
  Image image;
  image.width = static_cast<int>(width);
  image.height = static_cast<int>(height);
  image.channels = 3;
  image.pixels.reserve(raster.size() * 3);
  for (const std::uint32_t p : raster)
    image.pixels.insert(image.pixels.end(), {static_cast<std::uint8_t>(TIFFGetR(p)), static_cast<std::uint8_t>(TIFFGetG(p)),
                                             static_cast<std::uint8_t>(TIFFGetB(p))});
  return image;
}

}  // namespace occ_improve
