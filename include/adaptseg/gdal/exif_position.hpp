#pragma once
/// @file
/// Where a camera says it took a picture: the GPS position in its EXIF tags (GPSLatitude,
/// GPSLongitude with their N/S and E/W references; GPSAltitude with GPSAltitudeRef, above or
/// below sea level), as GDAL's JPEG and TIFF drivers read them. Survey cameras with their own
/// GNSS receiver (often an RTK one) tag each picture so; the live loop may fuse an image at that
/// position instead of the vehicle's at the trigger (docs/flying.md). CMake target adaptseg::gdal.

#include <adaptseg/gdal/gdal_io.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <locale>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// A picture's EXIF GPS position.
struct ExifPosition {
  double latitude_deg = 0.0;   ///< north positive
  double longitude_deg = 0.0;  ///< east positive
  /// Height above mean sea level [m] (GPSAltitude, negative for GPSAltitudeRef 1); empty where
  /// the picture has no altitude.
  std::optional<double> altitude_msl_m;
};

namespace detail {

/// GDAL's rendering of EXIF rationals, "(25) (12) (3.6)", as numbers.
/// @throws std::invalid_argument naming `tag` for anything else.
inline std::vector<double> exif_rationals(const std::filesystem::path& file, const char* tag, const std::string& text) {
  std::vector<double> out;
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  char open = 0, close = 0;
  double v = 0.0;
  while (is >> open) {
    if (open != '(' || !(is >> v) || !(is >> close) || close != ')' || !std::isfinite(v))
      throw std::invalid_argument(file.string() + ": EXIF " + tag + " '" + text + "' is not a list of numbers");
    out.push_back(v);
  }
  return out;
}

}  // namespace detail

/// The EXIF GPS position of the picture in `file`, or nothing if it has no GPS latitude and
/// longitude (or no EXIF at all).
/// @throws std::invalid_argument (naming the file) for a file GDAL cannot read, and for GPS tags
///         that are present but malformed (a reference other than N/S or E/W, degrees beyond
///         range, minutes or seconds not below 60).
[[nodiscard]] inline std::optional<ExifPosition> read_exif_position(const std::filesystem::path& file) {
  const gdal::detail::Dataset d = gdal::detail::open(file);
  const auto item = [&](const char* name) -> std::optional<std::string> {
    const char* v = d->GetMetadataItem(name);
    if (v == nullptr) return std::nullopt;
    return std::string(v);
  };
  const auto lat_text = item("EXIF_GPSLatitude"), lon_text = item("EXIF_GPSLongitude");
  if (!lat_text || !lon_text) return std::nullopt;
  // Degrees, minutes, seconds (one, two or three of them) and a hemisphere.
  const auto angle = [&](const char* tag, const std::string& text, const char* ref_tag, char positive, char negative,
                         double limit) {
    const std::vector<double> dms = detail::exif_rationals(file, tag, text);
    if (dms.empty() || dms.size() > 3 || dms[0] < 0.0 || (dms.size() > 1 && !(dms[1] >= 0.0 && dms[1] < 60.0)) ||
        (dms.size() > 2 && !(dms[2] >= 0.0 && dms[2] < 60.0)))
      throw std::invalid_argument(file.string() + ": EXIF " + tag + " '" + text +
                                  "' is not degrees, minutes and seconds");
    const double deg = dms[0] + (dms.size() > 1 ? dms[1] / 60.0 : 0.0) + (dms.size() > 2 ? dms[2] / 3600.0 : 0.0);
    const std::string ref = item(ref_tag).value_or("");
    if (ref.empty() || (ref[0] != positive && ref[0] != negative))
      throw std::invalid_argument(file.string() + ": EXIF " + ref_tag + " '" + ref + "' is neither " + positive +
                                  " nor " + negative);
    if (deg > limit)
      throw std::invalid_argument(file.string() + ": EXIF " + tag + " " + gdal::detail::num(deg) + " deg is beyond " +
                                  gdal::detail::num(limit));
    return ref[0] == positive ? deg : -deg;
  };
  ExifPosition p;
  p.latitude_deg = angle("EXIF_GPSLatitude", *lat_text, "EXIF_GPSLatitudeRef", 'N', 'S', 90.0);
  p.longitude_deg = angle("EXIF_GPSLongitude", *lon_text, "EXIF_GPSLongitudeRef", 'E', 'W', 180.0);
  if (const auto alt = item("EXIF_GPSAltitude")) {
    const std::vector<double> a = detail::exif_rationals(file, "EXIF_GPSAltitude", *alt);
    if (a.size() != 1)
      throw std::invalid_argument(file.string() + ": EXIF GPSAltitude '" + *alt + "' is not one number");
    // GPSAltitudeRef: a byte, 0 above sea level, 1 below (GDAL writes it "0x00" or "0x01").
    const std::string ref = item("EXIF_GPSAltitudeRef").value_or("0x00");
    const bool below = ref == "0x01" || ref == "1";
    if (!below && ref != "0x00" && ref != "0")
      throw std::invalid_argument(file.string() + ": EXIF GPSAltitudeRef '" + ref + "' is neither 0 nor 1");
    p.altitude_msl_m = below ? -a[0] : a[0];
  }
  return p;
}

}  // namespace adaptseg
