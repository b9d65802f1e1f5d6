#pragma once
/// @file
/// The GDAL plumbing shared by the readers (gdal_io.hpp) and the writers (map_geotiff.hpp):
/// drivers registered once, GDAL's messages collected into exceptions, datasets closed by RAII,
/// rasters opened with one clear error each, strips sized for GDAL's block cache.

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <filesystem>
#include <iomanip>
#include <locale>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

namespace adaptseg::gdal::detail {

inline void register_drivers() {
  static const bool registered = [] {
    GDALAllRegister();
    return true;
  }();
  (void)registered;
}

/// GDAL's messages are collected into our exceptions, not printed: a scope with the quiet handler.
class QuietErrors {
 public:
  QuietErrors() { CPLPushErrorHandler(CPLQuietErrorHandler); }
  ~QuietErrors() { CPLPopErrorHandler(); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;
};

inline std::string last_error() {
  const char* m = CPLGetLastErrorMsg();
  return (m != nullptr && *m != '\0') ? std::string(m) : std::string("no message from GDAL");
}

struct DatasetCloser {
  void operator()(GDALDataset* d) const noexcept { GDALClose(GDALDataset::ToHandle(d)); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

/// A number for a message: shortest round-trip form ("0.05", "1e-17"), not std::to_string's "0.000000".
inline std::string num(double v) {
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s << std::setprecision(10) << v;
  return s.str();
}

[[noreturn]] inline void fail(const std::filesystem::path& file, const std::string& what) {
  throw std::invalid_argument(file.string() + ": " + what);
}

inline Dataset open(const std::filesystem::path& file) {
  register_drivers();
  if (!std::filesystem::is_regular_file(file)) fail(file, "file not found");
  const QuietErrors quiet;
  CPLErrorReset();
  Dataset d(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!d) fail(file, "GDAL cannot read it as a raster (" + last_error() + ")");
  if (d->GetRasterXSize() <= 0 || d->GetRasterYSize() <= 0 || d->GetRasterCount() <= 0)
    fail(file, "the raster is empty");
  return d;
}

/// True if the dataset carries a geotransform (its own or from a world file).
inline bool has_geotransform(GDALDataset& d) {
  std::array<double, 6> gt{};
  const QuietErrors quiet;
  return d.GetGeoTransform(gt.data()) == CE_None;
}

/// Rows per strip of ~`strip_bytes` for a band whose blocks are `block_h` rows high and whose
/// rows take `row_bytes` in memory: whole blocks, at least one block row.
inline int strip_rows(GDALRasterBand& band, std::size_t row_bytes, std::size_t strip_bytes) {
  int block_w = 0, block_h = 0;
  band.GetBlockSize(&block_w, &block_h);
  const int rows_wanted = static_cast<int>(std::max<std::size_t>(1, strip_bytes / std::max<std::size_t>(1, row_bytes)));
  return std::max(1, block_h) * std::max(1, rows_wanted / std::max(1, block_h));
}

}  // namespace adaptseg::gdal::detail
