#pragma once
// Small TIFFs for the tests and the fuzz seeds, written with libtiff: `samples` x `bits` per pixel in
// strips of `rows_per_strip` rows, the pixel bytes row after row.
#include <tiffio.h>

#include <cstdint>
#include <string>
#include <vector>

namespace occ_improve::test {

/// False when libtiff refused to open or write the file.
inline bool write_tiff(const std::string& path, std::uint32_t width, std::uint32_t height, std::uint16_t bits,
                       std::uint16_t samples, const std::vector<std::uint8_t>& bytes, std::uint32_t rows_per_strip,
                       std::uint16_t compression = COMPRESSION_NONE) {
  TIFF* tiff = TIFFOpen(path.c_str(), "w");
  if (!tiff) return false;
  TIFFSetField(tiff, TIFFTAG_IMAGEWIDTH, width);
  TIFFSetField(tiff, TIFFTAG_IMAGELENGTH, height);
  TIFFSetField(tiff, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(tiff, TIFFTAG_SAMPLESPERPIXEL, samples);
  TIFFSetField(tiff, TIFFTAG_SAMPLEFORMAT, SAMPLEFORMAT_UINT);
  TIFFSetField(tiff, TIFFTAG_PHOTOMETRIC, samples == 3 ? PHOTOMETRIC_RGB : PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tiff, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(tiff, TIFFTAG_ROWSPERSTRIP, rows_per_strip);
  TIFFSetField(tiff, TIFFTAG_COMPRESSION, compression);
  const std::size_t row_bytes = std::size_t{width} * samples * bits / 8;
  bool written = bytes.size() >= row_bytes * height;
  for (std::uint32_t row = 0; written && row < height; ++row)
    written = TIFFWriteScanline(tiff, const_cast<std::uint8_t*>(bytes.data()) + row * row_bytes, row, 0) == 1;
  TIFFClose(tiff);
  return written;
}

}  // namespace occ_improve::test
