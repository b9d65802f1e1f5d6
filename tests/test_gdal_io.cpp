// GeoTIFF fields and georeferenced maps (adaptseg::gdal): a bundled tile written to GeoTIFF by
// gdal_translate's own code (GDALTranslate) under a UTM georeference, loaded back, its frame
// checked against GDAL's transformation of the CRS, its map written and read back by GDAL.
#include <adaptseg/gdal/elevation_model.hpp>
#include <adaptseg/gdal/exif_position.hpp>
#include <adaptseg/gdal/gdal_io.hpp>
#include <adaptseg/gdal/site_fence.hpp>
#include <adaptseg/gdal/site_lawnmower.hpp>
#include <adaptseg/gdal/site_plan.hpp>
#include <adaptseg/gdal/survey_site.hpp>

#include "test_support.hpp"

#include <doctest/doctest.h>
#include <gdal_utils.h>
#include <ogr_geometry.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace adaptseg;

namespace {

const fs::path kTile = fs::path(ADAPTSEG_EXAMPLES_DIR) / "data" / "dubai-tile-6";
// Somewhere in Dubai, UTM zone 40N (EPSG:32640): the field origin (bottom-left corner).
constexpr double kE0 = 329000.0;
constexpr double kN0 = 2787000.0;

/// This process's scratch directory, removed at exit.
const fs::path& scratch() {
  static const test::TempDir dir;
  return dir.path();
}

/// gdal_translate SRC DST ARGS... through GDAL's library entry point.
void translate(const fs::path& src, const fs::path& dst, std::vector<std::string> args) {
  gdal::detail::register_drivers();
  gdal::detail::Dataset in(GDALDataset::Open(src.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  REQUIRE(in);
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  GDALTranslateOptions* opt = GDALTranslateOptionsNew(argv.data(), nullptr);
  REQUIRE(opt != nullptr);
  int usage_error = 0;
  GDALDatasetH out = GDALTranslate(dst.c_str(), GDALDataset::ToHandle(in.get()), opt, &usage_error);
  GDALTranslateOptionsFree(opt);
  REQUIRE(out != nullptr);
  GDALClose(out);
}

std::string f2s(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

/// `-a_ullr` of a north-up grid of `w` x `h` pixels of `px` metres with its bottom-left at (e0, n0).
std::vector<std::string> ullr(double e0, double n0, int w, int h, double px, double py) {
  return {"-a_ullr", f2s(e0), f2s(n0 + h * py), f2s(e0 + w * px), f2s(n0)};
}

/// A field directory: tile 6's field.yaml without gsd_cm (and with `extra` lines), its labels
/// and image written to GeoTIFF under `srs` on the grid of `px` x `py` metre pixels.
fs::path geotiff_field(const std::string& name, const std::string& srs = "EPSG:32640", double px = 0.05,
                       double py = 0.05, const std::string& extra = "") {
  const fs::path dir = scratch() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  const Field png = Field::load(kTile);
  const auto grid = ullr(kE0, kN0, png.width_px(), png.height_px(), px, py);
  std::vector<std::string> args{"-of", "GTiff", "-a_srs", srs};
  args.insert(args.end(), grid.begin(), grid.end());
  translate(kTile / "labels.png", dir / "labels.tif", args);
  translate(kTile / "image.jpg", dir / "image.tif", args);
  std::ifstream in(kTile / "field.yaml");
  std::ofstream out(dir / "field.yaml");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("gsd_cm:", 0) == 0) continue;
    if (line.rfind("labels:", 0) == 0) line = "labels: labels.tif";
    if (line.rfind("image:", 0) == 0) line = "image: image.tif";
    out << line << '\n';
  }
  out << extra;
  return dir;
}

/// WGS84 of CRS coordinates through GDAL/PROJ: the reference, not our code.
GeoPoint gdal_wgs84(const std::string& srs_text, double e, double n) {
  OGRSpatialReference src, dst;
  src.SetFromUserInput(srs_text.c_str());
  src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  dst.SetWellKnownGeogCS("WGS84");
  dst.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformation* ct = OGRCreateCoordinateTransformation(&src, &dst);
  REQUIRE(ct != nullptr);
  double x = e, y = n;
  REQUIRE(ct->Transform(1, &x, &y));
  OGRCoordinateTransformation::DestroyCT(ct);
  return {y, x, 0.0};
}

double metres_apart(const GeoPoint& a, const GeoPoint& b) {
  double s = 0, a1 = 0, a2 = 0;
  GeographicLib::Geodesic::WGS84().Inverse(a.latitude_deg, a.longitude_deg, b.latitude_deg, b.longitude_deg, s, a1, a2);
  return s;
}

}  // namespace

TEST_CASE("a bundled tile as UTM GeoTIFFs: same labels and image, GSD and frame from the raster") {
  const fs::path dir = geotiff_field("utm");
  const Field png = Field::load(kTile);
  const Field tif = gdal::load_field(dir);
  CHECK(tif.gsd_cm() == doctest::Approx(5.0).epsilon(1e-9));
  // Field::load (no GDAL) cannot know the GSD, and says where to look.
  CHECK_THROWS_WITH_AS((void)Field::load(dir), doctest::Contains("missing key 'gsd_cm' (a field whose rasters carry"),
                       std::invalid_argument);
  REQUIRE(tif.labels().size() == png.labels().size());
  CHECK(cv::countNonZero(tif.labels() != png.labels()) == 0);  // byte-identical
  REQUIRE(tif.has_image());
  // The JPEG is decoded by GDAL here, by OpenCV there: the same pixels to a grey level or two.
  cv::Mat diff;
  cv::absdiff(tif.image(), png.image(), diff);
  CHECK(cv::mean(diff.reshape(1))[0] < 0.5);
  REQUIRE(tif.crs());
  CHECK(tif.crs()->origin_easting_m == doctest::Approx(kE0));
  CHECK(tif.crs()->origin_northing_m == doctest::Approx(kN0));
  OGRSpatialReference utm;
  utm.importFromEPSG(32640);
  OGRSpatialReference got;
  got.importFromWkt(tif.crs()->wkt.c_str());
  CHECK(got.IsSame(&utm));
  // One geo-reference model: the field's GeoReference against GDAL's own transformation.
  REQUIRE(tif.geo());
  CHECK(tif.geo()->scale == doctest::Approx(0.9996).epsilon(1e-3));
  const GeoReference geo(tif);
  const Area a = tif.area();
  double worst = 0.0;
  for (double fx : {0.0, 0.25, 0.5, 1.0})
    for (double fy : {0.0, 0.6, 1.0}) {
      const double x = fx * a.width_m(), y = fy * a.height_m();
      worst = std::max(worst, metres_apart(geo.to_wgs84({x, y, 0.0}), gdal_wgs84("EPSG:32640", kE0 + x, kN0 + y)));
    }
  CHECK(worst < 0.0005);  // 0.5 mm over a 129 x 126 m field (without the grid scale: 4 mm)
  // A region keeps its ground: its origin moves in the CRS as in the frame.
  const Field part = tif.sub_field({0.5, 0.0, 1.0, 0.5});
  REQUIRE(part.crs());
  const double dx = static_cast<int>(std::lround(0.5 * tif.width_px())) * 0.05;
  const double dy = (tif.height_px() - static_cast<int>(std::lround(0.5 * tif.height_px()))) * 0.05;
  CHECK(part.crs()->origin_easting_m == doctest::Approx(kE0 + dx));
  CHECK(part.crs()->origin_northing_m == doctest::Approx(kN0 + dy));
  CHECK(metres_apart(GeoReference(part).to_wgs84({1.0, 2.0, 0.0}), geo.to_wgs84({1.0 + dx, 2.0 + dy, 0.0})) < 1e-6);
}

TEST_CASE("a raster read in strips equals the raster read at once") {
  const fs::path dir = geotiff_field("strips");
  for (const char* name : {"image.tif", "labels.tif"}) {
    CAPTURE(name);
    gdal::detail::Dataset d = gdal::detail::open(dir / name);
    const std::vector<int> bands = d->GetRasterCount() >= 3 ? std::vector<int>{3, 2, 1} : std::vector<int>{1};
    const cv::Mat whole = gdal::detail::read_interleaved(*d, dir / name, bands);
    const cv::Mat strips = gdal::detail::read_interleaved(*d, dir / name, bands, 50'000);  // ~6-20 rows a strip
    REQUIRE(whole.size() == strips.size());
    cv::Mat diff;
    cv::absdiff(whole, strips, diff);
    CHECK(cv::countNonZero(diff.reshape(1)) == 0);
  }
}

TEST_CASE("a PNG field loads through gdal::load_field exactly as through Field::load") {
  const Field a = Field::load(kTile);
  const Field b = gdal::load_field(kTile);
  CHECK(cv::countNonZero(a.labels() != b.labels()) == 0);
  cv::Mat diff;
  cv::absdiff(a.image(), b.image(), diff);
  CHECK(cv::countNonZero(diff.reshape(1)) == 0);
  CHECK(a.gsd_cm() == b.gsd_cm());
  CHECK_FALSE(b.crs());
  CHECK_FALSE(b.geo());
}

TEST_CASE("labels as class colours with nodata, and field.yaml's gsd_cm and geo: checked against the raster") {
  const fs::path dir = geotiff_field("colours");
  const Field ref = gdal::load_field(dir);
  // Colour labels: each class's colour, and nodata (0, 0, 0) where the ignore label was.
  const Field png = Field::load(kTile);
  cv::Mat rgb(png.labels().size(), CV_8UC3, cv::Scalar(0, 0, 0));
  for (int r = 0; r < rgb.rows; ++r)
    for (int c = 0; c < rgb.cols; ++c) {
      const int v = png.labels().at<std::uint8_t>(r, c);
      if (v < png.num_classes()) {
        const auto& col = png.classes()[static_cast<std::size_t>(v)].color_rgb;
        rgb.at<cv::Vec3b>(r, c) = {col[2], col[1], col[0]};  // BGR for imwrite
      }
    }
  rgb.at<cv::Vec3b>(0, 0) = {0, 0, 0};  // at least one unlabelled pixel
  const fs::path colour_png = dir / "labels_rgb.png";
  REQUIRE(cv::imwrite(colour_png.string(), rgb));
  const auto grid = ullr(kE0, kN0, rgb.cols, rgb.rows, 0.05, 0.05);
  std::vector<std::string> args{"-of", "GTiff", "-a_srs", "EPSG:32640", "-a_nodata", "0"};
  args.insert(args.end(), grid.begin(), grid.end());
  translate(colour_png, dir / "labels.tif", args);
  const Field colour = gdal::load_field(dir);
  cv::Mat expected = png.labels().clone();
  expected.at<std::uint8_t>(0, 0) = 255;
  CHECK(cv::countNonZero(colour.labels() != expected) == 0);

  // Without nodata an unknown colour is one error naming it and the fix.
  translate(colour_png, dir / "labels.tif", [&] {
    std::vector<std::string> a{"-of", "GTiff", "-a_srs", "EPSG:32640"};
    a.insert(a.end(), grid.begin(), grid.end());
    return a;
  }());
  CHECK_THROWS_WITH_AS((void)gdal::load_field(dir),
                       doctest::Contains("colour (0, 0, 0) at row 0, col 0 is no class colour"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("no nodata value"), std::invalid_argument);
  translate(kTile / "labels.png", dir / "labels.tif", [&] {
    std::vector<std::string> a{"-of", "GTiff", "-a_srs", "EPSG:32640"};
    a.insert(a.end(), grid.begin(), grid.end());
    return a;
  }());

  // gsd_cm and geo: may be given, and must agree.
  std::ofstream(dir / "field.yaml", std::ios::app) << "gsd_cm: 5.0\n";
  CHECK(gdal::load_field(dir).gsd_cm() == doctest::Approx(5.0));
  const GeoPoint origin = GeoReference(ref).to_wgs84({0.0, 0.0, 0.0});
  const auto with_geo = [&](double lat, double heading) {
    const fs::path d2 =
        geotiff_field("colours_geo", "EPSG:32640", 0.05, 0.05,
                      "geo: {latitude_deg: " + f2s(lat) + ", longitude_deg: " + f2s(origin.longitude_deg) +
                          ", altitude_m: 12.5, heading_deg: " + f2s(heading) + "}\n");
    return gdal::load_field(d2);
  };
  const Field agreed = with_geo(origin.latitude_deg, ref.geo()->heading_deg);
  CHECK(agreed.geo()->altitude_m == 12.5);
  // A field 3000 m above the ellipsoid: the model's tangent plane lies there, and still agrees
  // with GDAL's transformation of the grid (without the height, 4 cm off at the corners).
  const fs::path high = geotiff_field("colours_high", "EPSG:32640", 0.05, 0.05,
                                      "geo: {latitude_deg: " + f2s(origin.latitude_deg) +
                                          ", longitude_deg: " + f2s(origin.longitude_deg) +
                                          ", altitude_m: 3000, heading_deg: " + f2s(ref.geo()->heading_deg) + "}\n");
  const Field up = gdal::load_field(high);
  const GeoReference up_geo(up);
  double worst_high = 0.0;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, std::pair{up.area().width_m(), up.area().height_m()},
                             std::pair{up.area().width_m(), 0.0}}) {
    const GeoPoint g = gdal_wgs84("EPSG:32640", kE0 + x, kN0 + y);
    worst_high = std::max(worst_high, metres_apart(up_geo.to_wgs84({x, y, 0.0}), g));
  }
  CHECK(worst_high < 0.0005);
  CHECK_THROWS_WITH_AS((void)with_geo(origin.latitude_deg + 1e-4, ref.geo()->heading_deg),
                       doctest::Contains("geo: disagrees with 'labels.tif'"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)with_geo(origin.latitude_deg, ref.geo()->heading_deg + 1.0), doctest::Contains("heading"),
                       std::invalid_argument);
  const fs::path d3 = geotiff_field("gsd", "EPSG:32640", 0.05, 0.05, "gsd_cm: 4.0\n");
  CHECK_THROWS_WITH_AS((void)gdal::load_field(d3), doctest::Contains("gsd_cm 4 disagrees with 'labels.tif'"),
                       std::invalid_argument);
}

TEST_CASE("bad GeoTIFF fields: one clear error each") {
  SUBCASE("geographic CRS in degrees") {
    const fs::path dir = scratch() / "geographic";
    fs::remove_all(dir);
    fs::create_directories(dir);
    translate(kTile / "labels.png", dir / "labels.tif",
              {"-of", "GTiff", "-a_srs", "EPSG:4326", "-a_ullr", "55.1", "25.2", "55.101", "25.199"});
    fs::copy_file(geotiff_field("geographic_yaml") / "field.yaml", dir / "field.yaml");
    std::ofstream(dir / "image.tif") << "";  // never read: the labels fail first
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("geographic CRS (coordinates in degrees)"),
                         std::invalid_argument);
    // The hint names the field's own UTM zone (55.1 E: zone 40 north), not another.
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("EPSG:32640 (UTM zone 40N, the field's)"),
                         std::invalid_argument);
  }
  SUBCASE("a field without a labelled pixel") {
    const fs::path dir = geotiff_field("empty");
    const Field png = Field::load(kTile);
    cv::imwrite((dir / "empty.png").string(), cv::Mat(png.labels().size(), CV_8UC3, cv::Scalar(0, 0, 0)));
    translate(dir / "empty.png", dir / "labels.tif", [&] {
      std::vector<std::string> a{"-of", "GTiff", "-a_srs", "EPSG:32640", "-a_nodata", "0"};
      const auto g = ullr(kE0, kN0, png.width_px(), png.height_px(), 0.05, 0.05);
      a.insert(a.end(), g.begin(), g.end());
      return a;
    }());
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("the field has no valid pixel"),
                         std::invalid_argument);
  }
  SUBCASE("non-square pixels") {
    CHECK_THROWS_WITH_AS((void)gdal::load_field(geotiff_field("nonsquare", "EPSG:32640", 0.05, 0.06)),
                         doctest::Contains("non-square pixels"), std::invalid_argument);
  }
  SUBCASE("image and labels on different grids") {
    const fs::path dir = geotiff_field("mismatch");
    const Field png = Field::load(kTile);
    const auto shifted = ullr(kE0 + 1.0, kN0, png.width_px(), png.height_px(), 0.05, 0.05);
    std::vector<std::string> args{"-of", "GTiff", "-a_srs", "EPSG:32640"};
    args.insert(args.end(), shifted.begin(), shifted.end());
    translate(kTile / "image.jpg", dir / "image.tif", args);
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("are not on the same grid"),
                         std::invalid_argument);
    // ... or in different CRSs.
    const auto grid = ullr(kE0, kN0, png.width_px(), png.height_px(), 0.05, 0.05);
    std::vector<std::string> args2{"-of", "GTiff", "-a_srs", "EPSG:32639"};
    args2.insert(args2.end(), grid.begin(), grid.end());
    translate(kTile / "image.jpg", dir / "image.tif", args2);
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("differ in CRS"), std::invalid_argument);
  }
  SUBCASE("labels without nodata holding a value that is no class") {
    const fs::path dir = geotiff_field("nodata");
    cv::Mat l = Field::load(kTile).labels().clone();
    l.at<std::uint8_t>(3, 4) = 7;
    REQUIRE(cv::imwrite((dir / "bad.png").string(), l));
    const auto grid = ullr(kE0, kN0, l.cols, l.rows, 0.05, 0.05);
    std::vector<std::string> args{"-of", "GTiff", "-a_srs", "EPSG:32640"};
    args.insert(args.end(), grid.begin(), grid.end());
    translate(dir / "bad.png", dir / "labels.tif", args);
    CHECK_THROWS_WITH_AS(
        (void)gdal::load_field(dir),
        doctest::Contains("value 7 at row 3, col 4 is no class index (0..4), not the ignore label 255, "
                          "and the band has no nodata value"),
        std::invalid_argument);
    // Declared as nodata, it is unlabelled.
    args.insert(args.end(), {"-a_nodata", "7"});
    translate(dir / "bad.png", dir / "labels.tif", args);
    CHECK(gdal::load_field(dir).labels().at<std::uint8_t>(3, 4) == 255);
  }
  SUBCASE("a truncated TIFF") {
    const fs::path dir = geotiff_field("truncated");
    const auto size = fs::file_size(dir / "labels.tif");
    fs::resize_file(dir / "labels.tif", size / 2);
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("labels.tif: "), std::invalid_argument);
    fs::resize_file(dir / "labels.tif", 100);
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("labels.tif: GDAL cannot read it as a raster"),
                         std::invalid_argument);
  }
  SUBCASE("a rotated geotransform") {
    const fs::path dir = geotiff_field("rotated");
    gdal::detail::Dataset d(GDALDataset::Open((dir / "labels.tif").c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE));
    REQUIRE(d);
    double gt[6] = {kE0, 0.05 * 0.8, 0.05 * 0.6, kN0 + 100.0, 0.05 * 0.6, -0.05 * 0.8};
    REQUIRE(d->SetGeoTransform(gt) == CE_None);
    d.reset();
    CHECK_THROWS_WITH_AS((void)gdal::load_field(dir), doctest::Contains("only north-up rasters are supported"),
                         std::invalid_argument);
  }
}

TEST_CASE("an orthomosaic's alpha band and nodata are no data: not field, black for the backend") {
  // Tile 6's image as RGBA (OpenDroneMap's orthomosaics): a transparent strip of white pixels.
  const fs::path dir = geotiff_field("rgba");
  const Field png = Field::load(kTile);
  cv::Mat bgra;
  cv::cvtColor(png.image(), bgra, cv::COLOR_BGR2BGRA);
  const cv::Rect strip(0, 0, 300, png.height_px());
  bgra(strip).setTo(cv::Scalar(255, 255, 255, 0));
  cv::imwrite((dir / "rgba.png").string(), bgra);
  std::vector<std::string> args{"-of", "GTiff", "-a_srs", "EPSG:32640", "-colorinterp_4", "alpha"};
  const auto grid = ullr(kE0, kN0, png.width_px(), png.height_px(), 0.05, 0.05);
  args.insert(args.end(), grid.begin(), grid.end());
  translate(dir / "rgba.png", dir / "image.tif", args);
  const Field f = gdal::load_field(dir);
  CHECK(cv::countNonZero(f.valid_mask()(strip)) == 0);
  CHECK(cv::countNonZero(f.labels()(strip) != f.ignore_label()) == 0);
  cv::Mat black;
  cv::inRange(f.image()(strip), cv::Scalar(0, 0, 0), cv::Scalar(0, 0, 0), black);
  CHECK(cv::countNonZero(black) == strip.area());
  // Elsewhere the field as the PNG's.
  const cv::Rect rest(300, 0, png.width_px() - 300, png.height_px());
  CHECK(cv::countNonZero(f.labels()(rest) != png.labels()(rest)) == 0);
  CHECK(cv::norm(f.image()(rest), png.image()(rest), cv::NORM_INF) == 0.0);
  // An RGB image whose bands declare nodata (255, 255, 255): the same.
  cv::Mat bgr = png.image().clone();
  bgr(strip).setTo(cv::Scalar(255, 255, 255));
  cv::imwrite((dir / "white.png").string(), bgr);
  std::vector<std::string> args2{"-of", "GTiff", "-a_srs", "EPSG:32640", "-a_nodata", "255"};
  args2.insert(args2.end(), grid.begin(), grid.end());
  translate(dir / "white.png", dir / "image.tif", args2);
  const Field g = gdal::load_field(dir);
  CHECK(cv::countNonZero(g.valid_mask()(strip)) == 0);
}

TEST_CASE("map.tif and map_gsd.tif: the field's grid and CRS, classes as colours and names, nodata where unobserved") {
  const Field field = gdal::load_field(geotiff_field("map"));
  cv::Mat labels = field.labels().clone();
  labels(cv::Rect(0, 0, 50, 40)).setTo(field.ignore_label());
  cv::Mat gsd(field.labels().size(), CV_32F, cv::Scalar(5.0f));
  gsd(cv::Rect(0, 0, 50, 40)).setTo(std::numeric_limits<float>::infinity());
  const fs::path map = scratch() / "map_out" / "map.tif";
  fs::create_directories(map.parent_path());
  gdal::write_map_geotiff(map, field, labels);
  gdal::write_gsd_geotiff(map.parent_path() / "map_gsd.tif", field, gsd);

  gdal::detail::Dataset d(GDALDataset::Open(map.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  REQUIRE(d);
  double gt[6];
  REQUIRE(d->GetGeoTransform(gt) == CE_None);
  CHECK(gt[0] == doctest::Approx(kE0));
  CHECK(gt[3] == doctest::Approx(kN0 + field.height_px() * 0.05));
  CHECK(gt[1] == doctest::Approx(0.05));
  CHECK(gt[5] == doctest::Approx(-0.05));
  OGRSpatialReference utm;
  utm.importFromEPSG(32640);
  CHECK(d->GetSpatialRef()->IsSame(&utm));
  GDALRasterBand* band = d->GetRasterBand(1);
  int has = 0;
  CHECK(band->GetNoDataValue(&has) == 255.0);
  CHECK(has);
  REQUIRE(band->GetColorTable() != nullptr);
  const GDALColorEntry* veg = band->GetColorTable()->GetColorEntry(3);
  CHECK(veg->c1 == 254);
  CHECK(veg->c2 == 221);
  CHECK(veg->c3 == 58);
  char** names = band->GetCategoryNames();
  REQUIRE(names != nullptr);
  CHECK(std::string(names[3]) == "vegetation");
  // The classes only: five names (the ignore label is nodata, not a class); a TIFF palette
  // has 256 entries whatever is written, those after the classes transparent black.
  CHECK(CSLCount(names) == field.num_classes());
  const GDALColorEntry* after = band->GetColorTable()->GetColorEntry(field.num_classes());
  CHECK((after == nullptr || (after->c1 == 0 && after->c2 == 0 && after->c3 == 0)));
  cv::Mat back(labels.size(), CV_8UC1);
  REQUIRE(band->RasterIO(GF_Read, 0, 0, back.cols, back.rows, back.data, back.cols, back.rows, GDT_Byte, 0, 0) ==
          CE_None);
  CHECK(cv::countNonZero(back != labels) == 0);

  gdal::detail::Dataset g(
      GDALDataset::Open((map.parent_path() / "map_gsd.tif").c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  REQUIRE(g);
  cv::Mat gsd_back(gsd.size(), CV_32F);
  REQUIRE(g->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, gsd.cols, gsd.rows, gsd_back.data, gsd.cols, gsd.rows,
                                        GDT_Float32, 0, 0) == CE_None);
  CHECK(gsd_back.at<float>(0, 0) == 0.0f);
  CHECK(gsd_back.at<float>(100, 100) == 5.0f);
  CHECK(g->GetRasterBand(1)->GetNoDataValue(&has) == 0.0);
}

TEST_CASE("a geo: field's map.tif: every pixel where GeoReference puts it") {
  const Field field = Field::load(kTile).with_geo(FieldGeo{25.2, 55.3, 4.0, 237.5, 10.0, -20.0});
  const fs::path map = scratch() / "geo_map.tif";
  gdal::write_map_geotiff(map, field, field.labels());
  gdal::detail::Dataset d(GDALDataset::Open(map.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  REQUIRE(d);
  double gt[6];
  REQUIRE(d->GetGeoTransform(gt) == CE_None);
  char* wkt = nullptr;
  d->GetSpatialRef()->exportToWkt(&wkt);
  const std::string srs = wkt;
  CPLFree(wkt);
  const GeoReference geo(field);
  const double g = field.gsd_cm() / 100.0;
  double worst = 0.0;
  for (const auto& [col, row] : {std::pair{0, 0}, std::pair{field.width_px(), 0}, std::pair{0, field.height_px()},
                                 std::pair{field.width_px(), field.height_px()}, std::pair{1000, 700}}) {
    const double e = gt[0] + col * gt[1] + row * gt[2], n = gt[3] + col * gt[4] + row * gt[5];
    const GeoPoint ours = geo.to_wgs84({col * g, (field.height_px() - row) * g, 0.0});
    worst = std::max(worst, metres_apart(ours, gdal_wgs84(srs, e, n)));
  }
  CHECK(worst < 0.001);
}

namespace {

/// A GeoJSON FeatureCollection of one polygon per ring list, (longitude, latitude) pairs.
std::string geojson_polygon(const std::vector<std::vector<GeoPoint>>& rings) {
  std::ostringstream s;
  s.precision(12);
  s << R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, )"
    << R"("geometry": {"type": "Polygon", "coordinates": [)";
  for (std::size_t r = 0; r < rings.size(); ++r) {
    s << (r ? ", [" : "[");
    for (std::size_t i = 0; i <= rings[r].size(); ++i) {
      const GeoPoint& g = rings[r][i % rings[r].size()];  // closed: the first point again
      s << (i ? ", [" : "[") << g.longitude_deg << ", " << g.latitude_deg << "]";
    }
    s << "]";
  }
  s << "]}}]}\n";
  return s.str();
}

void write_file(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

}  // namespace

TEST_CASE("a site from a GeoJSON polygon: its frame along the longer side, a plan inside it that sees all of it") {
  // An L of 240 m by 100 m (an 80 m square bitten out of a corner) whose long side runs 30 deg
  // north of east, in Dubai, through GeographicLib's tangent plane.
  const GeographicLib::LocalCartesian plane(25.2, 55.3, 10.0);
  const double a = 30.0 * std::numbers::pi / 180.0;
  const std::vector<Eigen::Vector2d> local{{0, 0}, {240, 0}, {240, 20}, {160, 20}, {160, 100}, {0, 100}};
  std::vector<GeoPoint> ring;
  for (const auto& q : local) {
    double lat = 0, lon = 0, h = 0;
    plane.Reverse(std::cos(a) * q.x() - std::sin(a) * q.y(), std::sin(a) * q.x() + std::cos(a) * q.y(), 0.0, lat, lon,
                  h);
    ring.push_back({lat, lon, 10.0});
  }
  const fs::path file = scratch() / "l_site.geojson";
  write_file(file, geojson_polygon({ring}));
  const SurveySite site = load_survey_site(file, 10.0, 10.0);
  CHECK(site.name == "l_site");
  CHECK(site.area.area.width_m() == doctest::Approx(240.0).epsilon(0.002));
  CHECK(site.area.area.height_m() == doctest::Approx(100.0).epsilon(0.002));
  // +x along the long side: at compass bearing 60 deg (or its opposite).
  CHECK(std::remainder(site.geo.heading_deg - 60.0, 180.0) ==
        doctest::Approx(0.0).epsilon(0.01));  // the two tangent planes: meridians converge
  // The frame is a georeference: every corner back where the file put it.
  const GeoReference geo(site.geo);
  REQUIRE(site.rings.size() == 1);
  REQUIRE(site.rings[0].size() == ring.size() + 1);
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Eigen::Vector2d& q = site.rings[0][i];
    CHECK(metres_apart(geo.to_wgs84(Eigen::Vector3d(q.x(), q.y(), 0.0)), ring[i]) < 0.01);
  }
  // The frame as a geo: section (anchored at its origin): the same frame to a millimetre.
  const GeoReference as_section(site.origin_geo());
  for (const auto& q : site.rings[0])
    CHECK(metres_apart(as_section.to_wgs84(Eigen::Vector3d(q.x(), q.y(), 0.0)),
                       geo.to_wgs84(Eigen::Vector3d(q.x(), q.y(), 0.0))) < 0.001);
  // The mask is the L: 240 x 100 - 80 x 80 m^2 at 10 cm/px, to a pixel along the outline.
  CHECK(cv::countNonZero(site.area.valid_mask) * 0.01 == doctest::Approx(240.0 * 100.0 - 80.0 * 80.0).epsilon(0.01));

  // At 15 cm/px (72 m x 54 m footprints), the grid centred: every waypoint inside the L by the
  // default margin (2 m; the cells whose centre lies outside moved in), the bitten-out corner's
  // cells skipped, and every pixel of the site under a footprint.
  const CameraModel camera;
  const std::vector<Waypoint> plan = plan_site_survey(site, camera, 15.0);
  REQUIRE(!plan.empty());
  double x0 = 1e9, y0 = 1e9;
  cv::Mat seen(site.area.valid_mask.size(), CV_8UC1, cv::Scalar(0));
  for (const auto& w : plan) {
    CHECK(w.position.z() == doctest::Approx(camera.altitude_m(15.0)));
    x0 = std::min(x0, w.footprint.x_min_m);
    y0 = std::min(y0, w.footprint.y_min_m);
    CHECK(w.position.x() > 0.0);
    CHECK(w.position.x() < site.area.area.width_m());
    CHECK(w.position.y() > 0.0);
    CHECK(w.position.y() < site.area.area.height_m());
    CHECK(site.contains(Eigen::Vector2d(w.position.x(), w.position.y()), 2.0));
    seen(raster_rect(w.footprint, 10.0, seen.rows) & cv::Rect(0, 0, seen.cols, seen.rows)).setTo(255);
  }
  const LawnmowerPlanner planner(camera);
  const std::size_t full =
      planner.plan(planner.centred_grid(site.area.area, 15.0), 15.0, Eigen::Vector2d(x0, y0)).size();
  CHECK(plan.size() < full);
  CHECK(cv::countNonZero(site.area.valid_mask & ~seen) == 0);
}

TEST_CASE("a site from an orthomosaic without labels: the outline of its pixels with data") {
  // Tile 6's image as RGBA, a transparent strip on the left: the site is the rest.
  const fs::path dir = geotiff_field("site_rgba");
  const Field png = Field::load(kTile);
  cv::Mat bgra;
  cv::cvtColor(png.image(), bgra, cv::COLOR_BGR2BGRA);
  bgra(cv::Rect(0, 0, 300, png.height_px())).setTo(cv::Scalar(255, 255, 255, 0));
  cv::imwrite((dir / "rgba.png").string(), bgra);
  std::vector<std::string> args{"-of", "GTiff", "-a_srs", "EPSG:32640", "-colorinterp_4", "alpha"};
  const auto grid = ullr(kE0, kN0, png.width_px(), png.height_px(), 0.05, 0.05);
  args.insert(args.end(), grid.begin(), grid.end());
  translate(dir / "rgba.png", dir / "ortho.tif", args);
  const SurveySite site = load_survey_site(dir / "ortho.tif", 10.0);
  const double w = (png.width_px() - 300) * 0.05, h = png.height_px() * 0.05;
  // The frame follows the longer side; UTM's grid north is not true north, hence the tolerance.
  const double longer = std::max(w, h), shorter = std::min(w, h);
  CHECK(site.area.area.width_m() == doctest::Approx(longer).epsilon(0.01));
  CHECK(site.area.area.height_m() == doctest::Approx(shorter).epsilon(0.01));
  CHECK(cv::countNonZero(site.area.valid_mask) * 0.01 == doctest::Approx(w * h).epsilon(0.02));
  // The corner of the data nearest the UTM origin, through GDAL, is a corner of the site.
  const GeoPoint corner = gdal_wgs84("EPSG:32640", kE0 + 300 * 0.05, kN0);
  const GeoReference geo(site.geo);
  double nearest = 1e9;
  for (const auto& c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(site.area.area.width_m(), 0, 0),
                        Eigen::Vector3d(0, site.area.area.height_m(), 0),
                        Eigen::Vector3d(site.area.area.width_m(), site.area.area.height_m(), 0)})
    nearest = std::min(nearest, metres_apart(geo.to_wgs84(c), corner));
  CHECK(nearest < 0.5);
}

TEST_CASE("bad survey areas: one clear error each, naming the file") {
  const auto error_of = [](const fs::path& f) {
    try {
      (void)load_survey_site(f);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(error_of(scratch() / "nowhere.geojson").find("nowhere.geojson': file not found") != std::string::npos);
  write_file(scratch() / "text.geojson", "not a vector file\n");
  CHECK(error_of(scratch() / "text.geojson").find("neither a vector file nor a raster") != std::string::npos);
  write_file(scratch() / "points.geojson",
             R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, )"
             R"("geometry": {"type": "Point", "coordinates": [55.3, 25.2]}}]})");
  CHECK(error_of(scratch() / "points.geojson").find("no polygon") != std::string::npos);
  // A polygon of two distinct points (a line there and back).
  write_file(scratch() / "flat.geojson", geojson_polygon({{{25.2, 55.3, 0}, {25.2001, 55.3001, 0}, {25.2, 55.3, 0}}}));
  CHECK(error_of(scratch() / "flat.geojson").find("flat.geojson': the area covers no pixel") != std::string::npos);
  // Coordinates that are not longitude, latitude (a projected CRS without its declaration).
  write_file(scratch() / "metres.geojson",
             geojson_polygon({{{2787000, 329000, 0}, {2787000, 329100, 0}, {2787100, 329100, 0}}}));
  CHECK(error_of(scratch() / "metres.geojson").find("out of range") != std::string::npos);
}

namespace {

/// `local` east, north [m] about (lat0, lon0), turned by `angle_deg` counter-clockwise, in WGS84.
std::vector<GeoPoint> wgs84_ring(double lat0, double lon0, const std::vector<Eigen::Vector2d>& local,
                                 double angle_deg = 0.0) {
  const GeographicLib::LocalCartesian plane(lat0, lon0, 0.0);
  const double a = angle_deg * std::numbers::pi / 180.0;
  std::vector<GeoPoint> ring;
  for (const auto& q : local) {
    double lat = 0, lon = 0, h = 0;
    plane.Reverse(std::cos(a) * q.x() - std::sin(a) * q.y(), std::sin(a) * q.x() + std::cos(a) * q.y(), 0.0, lat, lon,
                  h);
    ring.push_back({lat, lon, 0.0});
  }
  return ring;
}

/// The site's polygon in its own frame, as GDAL's geometry: an independent judge of "inside".
std::unique_ptr<OGRPolygon> frame_polygon(const SurveySite& site) {
  auto poly = std::make_unique<OGRPolygon>();
  for (const auto& r : site.rings) {
    OGRLinearRing ring;
    for (const auto& v : r) ring.addPoint(v.x(), v.y());
    ring.closeRings();
    poly->addRing(&ring);
  }
  return poly;
}

/// The L-shaped site of the GeoJSON test near Dubai (240 m by 100 m, long side at bearing 60).
const std::vector<Eigen::Vector2d> kL{{0, 0}, {240, 0}, {240, 20}, {160, 20}, {160, 100}, {0, 100}};

/// An irregular 5 ha site near Zurich with a 50 m square hole.
const std::vector<Eigen::Vector2d> kOuter{{0, 0}, {250, -30}, {290, 110}, {170, 200}, {30, 170}, {-30, 80}};
const std::vector<Eigen::Vector2d> kHole{{100, 60}, {150, 60}, {150, 110}, {100, 110}};

SurveySite hole_site() {
  const fs::path file = scratch() / "hole_site.geojson";
  write_file(file, geojson_polygon({wgs84_ring(47.4, 8.5, kOuter), wgs84_ring(47.4, 8.5, kHole)}));
  return load_survey_site(file, 10.0);
}

/// Easting, northing [m] of a WGS84 point in `srs` (through GDAL).
std::pair<double, double> projected(const std::string& srs_text, const GeoPoint& g) {
  OGRSpatialReference src, dst;
  src.SetWellKnownGeogCS("WGS84");
  src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  dst.SetFromUserInput(srs_text.c_str());
  dst.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRCoordinateTransformation* ct = OGRCreateCoordinateTransformation(&src, &dst);
  REQUIRE(ct != nullptr);
  double x = g.longitude_deg, y = g.latitude_deg;
  REQUIRE(ct->Transform(1, &x, &y));
  OGRCoordinateTransformation::DestroyCT(ct);
  return {x, y};
}

/// A Float32 DEM GeoTIFF in `srs` with its top-left at (e0, n1), `w` x `h` pixels of `px` m, z(e, n).
template <typename Z>
void write_dem(const fs::path& file, const std::string& srs_text, double e0, double n1, int w, int h, double px, Z z) {
  gdal::detail::register_drivers();
  GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
  REQUIRE(gtiff != nullptr);
  gdal::detail::Dataset d(gtiff->Create(file.c_str(), w, h, 1, GDT_Float32, nullptr));
  REQUIRE(d);
  double gt[6] = {e0, px, 0.0, n1, 0.0, -px};
  d->SetGeoTransform(gt);
  OGRSpatialReference srs;
  srs.SetFromUserInput(srs_text.c_str());
  d->SetSpatialRef(&srs);
  std::vector<float> values(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      values[static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c)] =
          static_cast<float>(z(e0 + (c + 0.5) * px, n1 - (r + 0.5) * px));
  REQUIRE(d->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, w, h, values.data(), w, h, GDT_Float32, 0, 0) == CE_None);
}

}  // namespace

TEST_CASE("a site with a hole: every waypoint inside its polygon and out of its hole by the margin") {
  const SurveySite site = hole_site();
  REQUIRE(site.rings.size() == 2);
  CHECK(site.holes == std::vector<bool>{false, true});
  CHECK(site.area_m2() == doctest::Approx(50450.0).epsilon(0.002));  // 52,950 less the hole's 2,500
  const auto poly = frame_polygon(site);
  const std::unique_ptr<OGRGeometry> edges(poly->Boundary());
  const CameraModel camera;
  // The grid alone, as adaptseg_plan laid it before: centres in the hole and beyond the edges.
  const LawnmowerPlanner planner(camera);
  std::size_t outside_before = 0;
  for (const auto& w : planner.plan(planner.centred_grid(site.area.area, 15.0), 15.0)) {
    const OGRPoint p(w.position.x(), w.position.y());
    outside_before += poly->Contains(&p) ? 0 : 1;
  }
  CHECK(outside_before > 4);
  const SiteSurvey survey = survey_site(site, camera, 15.0);
  REQUIRE(survey.waypoints.size() > 15);
  CHECK(survey.moved > 0);
  for (const auto& w : survey.waypoints) {
    CAPTURE(w.position.transpose());
    const OGRPoint p(w.position.x(), w.position.y());
    CHECK(poly->Contains(&p));
    CHECK(edges->Distance(&p) >= 2.0 - 1e-9);  // the default inside margin
    CHECK(site.contains(w.position.head<2>(), 2.0));
    // A moved footprint moved with its waypoint: still centred on it.
    CHECK(w.footprint.centre().x() == doctest::Approx(w.position.x()));
    CHECK(w.footprint.centre().y() == doctest::Approx(w.position.y()));
  }
  // What moving them cost: under 2 % of the site left under no footprint, reported.
  CHECK(survey.site_m2 == doctest::Approx(site.area_m2()).epsilon(0.01));
  CHECK(survey.uncovered_m2 < 0.02 * survey.site_m2);
  CHECK(survey.coverage() > 0.98);
  // A wider margin keeps them farther in.
  SiteSurveyOptions wide;
  wide.inside_margin_m = 6.0;
  for (const auto& w : survey_site(site, camera, 15.0, wide).waypoints) {
    const OGRPoint p(w.position.x(), w.position.y());
    CHECK(edges->Distance(&p) >= 6.0 - 1e-9);
  }
}

TEST_CASE("plan_site: the take-off point on the site, the polygon as the geofence, every leg inside it") {
  const SurveySite site = hole_site();
  const GeoPoint home = wgs84_ring(47.4, 8.5, {{20, 80}})[0];
  SitePlanOptions options;
  options.gsd_cm = 15.0;
  options.home = home;
  const SitePlan plan = plan_site(site, options);
  CHECK(plan.home_given);
  CHECK(metres_apart(plan.home, home) < 0.01);
  // The fence: the outline included, the hole excluded, both as the file gave them.
  REQUIRE(plan.geofence.size() == 2);
  CHECK(plan.geofence[0].inclusion);
  CHECK_FALSE(plan.geofence[1].inclusion);
  CHECK(plan.geofence[0].vertices.size() == kOuter.size());
  CHECK(plan.geofence[1].vertices.size() == kHole.size());
  const auto outer = wgs84_ring(47.4, 8.5, kOuter);
  for (std::size_t i = 0; i < outer.size(); ++i) CHECK(metres_apart(plan.geofence[0].vertices[i], outer[i]) < 0.01);
  // Every leg flown, the take-off's and the return's included, inside the polygon and out of the
  // hole (GDAL's judgement), half the margin from its edges; some bend around the hole.
  const auto poly = frame_polygon(site);
  const std::unique_ptr<OGRGeometry> edges(poly->Boundary());
  REQUIRE(plan.routes.size() == 1);
  std::vector<Eigen::Vector2d> flown{plan.home_xy};
  std::size_t images = 0;
  for (const RoutePoint& r : plan.routes[0]) {
    flown.push_back(r.position.head<2>());
    if (r.image) CHECK(*r.image == images++);
  }
  flown.push_back(plan.home_xy);
  CHECK(images == plan.survey.waypoints.size());
  CHECK(plan.via_points > 0);
  CHECK(plan.routes[0].size() == images + plan.via_points);
  for (std::size_t k = 1; k < flown.size(); ++k) {
    CAPTURE(k);
    OGRLineString leg;
    leg.addPoint(flown[k - 1].x(), flown[k - 1].y());
    leg.addPoint(flown[k].x(), flown[k].y());
    CHECK(poly->Contains(&leg));
    CHECK(edges->Distance(&leg) >= 1.0 - 1e-6);
  }
  // The lawnmower starts at the end of the site nearer home.
  CHECK((plan.survey.waypoints.front().position.head<2>() - plan.home_xy).norm() <
        (plan.survey.waypoints.back().position.head<2>() - plan.home_xy).norm());
  // The mission file: take-off at home, the via points without an image, the fence.
  const ExportPath path = plan.sortie_path(0, site);
  CHECK(path.home == plan.home);
  CHECK(path.geofence.size() == 2);
  const auto items = mission_items(path);
  CHECK(items.front().params[4] == home.latitude_deg);
  CHECK(items.size() == 3 + 2 * images + plan.via_points);
  // A take-off point in the hole, or beyond the outline, is refused.
  options.home = wgs84_ring(47.4, 8.5, {{125, 85}})[0];
  CHECK_THROWS_WITH_AS((void)plan_site(site, options),
                       doctest::Contains("m off the site (outside its outline or in a hole)"), std::invalid_argument);
  options.home = wgs84_ring(47.4, 8.5, {{300, 0}})[0];
  CHECK_THROWS_WITH_AS((void)plan_site(site, options), doctest::Contains("m off the site"), std::invalid_argument);
}

TEST_CASE("plan_site: a DEM with a 20 m slope keeps the GSD within 5 %, altitudes relative to home") {
  const fs::path file = scratch() / "l_dem_site.geojson";
  write_file(file, geojson_polygon({wgs84_ring(25.2, 55.3, kL, 30.0)}));
  const SurveySite site = load_survey_site(file, 10.0, 10.0);
  // The site's extent in UTM 40N; the ground rises 20 m from its west end to its east end.
  double e_min = 1e12, e_max = -1e12, n_min = 1e12, n_max = -1e12;
  for (const auto& g : wgs84_ring(25.2, 55.3, kL, 30.0)) {
    const auto [e, n] = projected("EPSG:32640", g);
    e_min = std::min(e_min, e), e_max = std::max(e_max, e), n_min = std::min(n_min, n), n_max = std::max(n_max, n);
  }
  const auto slope = [&](double rise_m) {
    return [=](double e, double) { return 100.0 + rise_m * (e - e_min) / (e_max - e_min); };
  };
  const auto ground = slope(20.0);
  const fs::path dem_file = scratch() / "slope_dem.tif";
  const double px = 5.0;
  const int w = static_cast<int>((e_max - e_min + 400.0) / px), h = static_cast<int>((n_max - n_min + 400.0) / px);
  write_dem(dem_file, "EPSG:32640", e_min - 200.0, n_max + 200.0, w, h, px, ground);
  const ElevationModel dem(dem_file);
  const GeoPoint probe = wgs84_ring(25.2, 55.3, {{100, 50}}, 30.0)[0];
  const auto [pe, pn] = projected("EPSG:32640", probe);
  REQUIRE(dem.elevation_m(probe.latitude_deg, probe.longitude_deg));
  CHECK(*dem.elevation_m(probe.latitude_deg, probe.longitude_deg) == doctest::Approx(ground(pe, pn)).epsilon(1e-6));
  CHECK_FALSE(dem.elevation_m(26.0, 55.3));

  SitePlanOptions options;
  options.gsd_cm = 10.0;  // 55 m above the ground
  const SitePlan plan = plan_site(site, options, &dem);
  REQUIRE(plan.terrain);
  const CameraModel camera;
  const GeoReference frame(site.geo);
  const auto ground_at = [&](double x, double y) {
    const auto [e, n] = projected("EPSG:32640", frame.to_wgs84({x, y, 0.0}));
    return ground(e, n);
  };
  const double home_ground = ground_at(plan.home_xy.x(), plan.home_xy.y());
  CHECK(plan.terrain->home_ground_m == doctest::Approx(home_ground).epsilon(1e-6));
  double low = 1e9, high = -1e9;
  for (const auto& wp : plan.survey.waypoints) {
    CAPTURE(wp.position.transpose());
    // Above its own ground, at the centre and at the footprint's corners: the GSD within 5 %.
    const double above = wp.position.z() + home_ground - ground_at(wp.position.x(), wp.position.y());
    CHECK(std::abs(camera.gsd_cm(above) / 10.0 - 1.0) < 0.01);
    for (const auto& c : {Eigen::Vector2d(wp.footprint.x_min_m, wp.footprint.y_min_m),
                          Eigen::Vector2d(wp.footprint.x_max_m, wp.footprint.y_max_m),
                          Eigen::Vector2d(wp.footprint.x_min_m, wp.footprint.y_max_m),
                          Eigen::Vector2d(wp.footprint.x_max_m, wp.footprint.y_min_m)})
      CHECK(std::abs(camera.gsd_cm(wp.position.z() + home_ground - ground_at(c.x(), c.y())) / 10.0 - 1.0) < 0.05);
    low = std::min(low, wp.position.z()), high = std::max(high, wp.position.z());
  }
  CHECK(high - low > 12.0);  // the altitudes above home follow the slope
  // The same waypoints flown flat at 55 m above home would miss the GSD by more than 5 % somewhere.
  double worst_flat = 0.0;
  for (const auto& wp : plan.survey.waypoints)
    worst_flat = std::max(
        worst_flat,
        std::abs(camera.gsd_cm(55.0 + home_ground - ground_at(wp.position.x(), wp.position.y())) / 10.0 - 1.0));
  CHECK(worst_flat > 0.05);
  // The ground rises above home: the return altitude must clear it.
  bool rises = false;
  for (const auto& warning : plan.warnings) rises = rises || warning.find("rises") != std::string::npos;
  CHECK(rises);
  // A slope steep enough that a footprint's highest ground comes within the minimum altitude: refused.
  const fs::path steep_file = scratch() / "steep_dem.tif";
  write_dem(steep_file, "EPSG:32640", e_min - 200.0, n_max + 200.0, w, h, px, slope(200.0));
  const ElevationModel steep(steep_file);
  options.min_altitude_m = 45.0;
  CHECK_THROWS_WITH_AS(
      (void)plan_site(site, options, &steep),
      doctest::Contains("m above the highest ground under its footprint (DEM), below the minimum altitude 45.0 m"),
      std::invalid_argument);
  // A DEM elsewhere: no elevation, named.
  const fs::path far_file = scratch() / "far_dem.tif";
  write_dem(far_file, "EPSG:32640", e_min + 50'000.0, n_max + 200.0, 20, 20, px, ground);
  const ElevationModel far(far_file);
  options.min_altitude_m = 10.0;
  CHECK_THROWS_WITH_AS((void)plan_site(site, options, &far),
                       doctest::Contains("has no elevation at the take-off point"), std::invalid_argument);
}

TEST_CASE("plan_site: swapped latitude and longitude are named, never planned silently") {
  const auto ring = wgs84_ring(25.2, 55.3, kL, 30.0);
  std::vector<GeoPoint> swapped;
  for (const auto& g : ring) swapped.push_back({g.longitude_deg, g.latitude_deg, 0.0});  // written [lat, lon]
  const fs::path file = scratch() / "swapped.geojson";
  write_file(file, geojson_polygon({swapped}));
  const SurveySite site = load_survey_site(file, 10.0);  // a valid place: near 55.3 N, 25.2 E
  CHECK(site.centre().latitude_deg == doctest::Approx(55.3).epsilon(0.001));
  SitePlanOptions options;
  options.gsd_cm = 10.0;
  options.home = wgs84_ring(25.2, 55.3, {{40, 50}}, 30.0)[0];  // where the site really is
  CHECK_THROWS_WITH_AS((void)plan_site(site, options), doctest::Contains("swapped, it would lie on the site"),
                       std::invalid_argument);
  // Against a DEM of the real place, too.
  const auto [e, n] = projected("EPSG:32640", GeoPoint{25.2, 55.3, 0.0});
  const fs::path dem_file = scratch() / "dubai_dem.tif";
  write_dem(dem_file, "EPSG:32640", e - 500.0, n + 500.0, 100, 100, 10.0, [](double, double) { return 5.0; });
  const ElevationModel dem(dem_file);
  options.home.reset();
  CHECK_THROWS_WITH_AS((void)plan_site(site, options, &dem), doctest::Contains("swapped, the site would lie on it"),
                       std::invalid_argument);
  // A latitude beyond 90 that would be a longitude: Sydney written [lat, lon].
  write_file(scratch() / "sydney.geojson",
             R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, )"
             R"("geometry": {"type": "Polygon", "coordinates": [[[-33.90, 151.20], [-33.90, 151.21], )"
             R"([-33.91, 151.21], [-33.90, 151.20]]]}}]})");
  CHECK_THROWS_WITH_AS((void)load_survey_site(scratch() / "sydney.geojson"),
                       doctest::Contains("are latitude and longitude swapped? GeoJSON and KML list longitude first"),
                       std::invalid_argument);
}

TEST_CASE("plan_site: sorties from the take-off point fit the flight-time limit and resume where the last stopped") {
  const fs::path file = scratch() / "l_sortie_site.geojson";
  write_file(file, geojson_polygon({wgs84_ring(25.2, 55.3, kL, 30.0)}));
  const SurveySite site = load_survey_site(file, 10.0);
  SitePlanOptions options;
  options.gsd_cm = 5.0;  // 27.5 m, 24 x 18 m footprints
  options.home = wgs84_ring(25.2, 55.3, {{5, 50}}, 30.0)[0];
  options.max_flight_s = 300.0;  // the L's far end alone: 4 min from home and back
  const SitePlan plan = plan_site(site, options);
  REQUIRE(plan.sorties.size() >= 3);
  const TimingModel timing;
  std::size_t next = 0;
  for (std::size_t k = 0; k < plan.sorties.size(); ++k) {
    CAPTURE(k);
    const Sortie& s = plan.sorties[k];
    CHECK(s.first == next);
    next = s.end;
    // The route flown, timed apart: up at home, through every point (holds at the images), back and down.
    const auto& route = plan.routes[k];
    const Eigen::Vector3d home(plan.home_xy.x(), plan.home_xy.y(), 0.0);
    Eigen::Vector3d at(home.x(), home.y(), route.front().position.z());
    double t = timing.segment_time_s(home, at);
    std::size_t images = 0;
    for (const RoutePoint& r : route) {
      t += timing.segment_time_s(at, r.position) + (r.image ? 1.0 : 0.0);
      at = r.position;
      if (r.image) CHECK(*r.image == s.first + images++);
    }
    const Eigen::Vector3d above(home.x(), home.y(), at.z());
    t += timing.segment_time_s(at, above) + timing.segment_time_s(above, home);
    CHECK(images == s.size());
    CHECK(t == doctest::Approx(s.flight_s));
    CHECK(t <= 300.0);
    CHECK(mission_items(plan.sortie_path(k, site)).size() <= 500);
  }
  CHECK(next == plan.survey.waypoints.size());
  options.max_flight_s = 20.0;
  CHECK_THROWS_WITH_AS((void)plan_site(site, options), doctest::Contains("alone takes"), std::invalid_argument);
}

TEST_CASE("plan_site: refusals and warnings, each one line with its numbers") {
  const fs::path file = scratch() / "l_sanity_site.geojson";
  write_file(file, geojson_polygon({wgs84_ring(25.2, 55.3, kL, 30.0)}));
  const SurveySite site = load_survey_site(file, 10.0);
  SitePlanOptions options;
  options.gsd_cm = 0.5;
  CHECK_THROWS_WITH_AS(
      (void)plan_site(site, options),
      doctest::Contains("the survey would fly 2.75 m above the ground at 0.50 cm/px, below the minimum "
                        "altitude 10.0 m: with this camera fly at least 1.82 cm/px"),
      std::invalid_argument);
  options.gsd_cm = 10.0;
  CHECK(plan_site(site, options).warnings.empty());
  // 12 km^2 at 20 cm/px: the area, the waypoints and the hours are each named; the one file
  // would hold more items than PX4 stores.
  const fs::path big = scratch() / "big_site.geojson";
  write_file(big, geojson_polygon({wgs84_ring(25.2, 55.3, {{0, 0}, {4000, 0}, {4000, 3000}, {0, 3000}})}));
  const SurveySite wide = load_survey_site(big, 100.0);
  options.gsd_cm = 20.0;
  const SitePlan plan = plan_site(wide, options);
  const auto has = [&](const std::string& text) {
    for (const auto& w : plan.warnings)
      if (w.find(text) != std::string::npos) return true;
    return false;
  };
  CHECK(has("ha), outside 100 m^2 .. 10 km^2: is it the polygon you meant"));
  CHECK(has("waypoints, more than 1000: check the GSD (20.00 cm/px) against the site's 1200.0 ha"));
  CHECK(has("h in 1 sortie(s), more than 2.0 h"));
  CHECK(has("split it into sorties that fit a battery"));
  CHECK_THROWS_WITH_AS((void)mission_items(plan.sortie_path(0, wide)),
                       doctest::Contains("more than the PX4 limit of 500"), std::invalid_argument);
  // The mask too large for memory: one readable line, the sizes as integers, the GSD that fits.
  try {
    (void)load_survey_site(big, 1.0);
    FAIL("no error");
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    CHECK(what.find("the site's mask at 1 cm/px would be 400") != std::string::npos);
    CHECK(what.find(" pixels, more than the 400000000 allowed: a map GSD of at least 17.4 cm/px fits (--map-gsd-cm)") !=
          std::string::npos);
    CHECK(what.find("e+") == std::string::npos);
  }
}

namespace {

/// A 16 x 12 JPEG written by GDAL's JPEG driver with `tags` as its EXIF (EXIF_* metadata items).
fs::path exif_jpeg(const std::string& name, const std::vector<std::pair<const char*, const char*>>& tags) {
  GDALAllRegister();
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* jpeg = GetGDALDriverManager()->GetDriverByName("JPEG");
  REQUIRE(mem != nullptr);
  REQUIRE(jpeg != nullptr);
  std::unique_ptr<GDALDataset> src(mem->Create("", 16, 12, 3, GDT_Byte, nullptr));
  for (const auto& [k, v] : tags) src->SetMetadataItem(k, v);
  const fs::path file = scratch() / name;
  std::unique_ptr<GDALDataset>(jpeg->CreateCopy(file.c_str(), src.get(), FALSE, nullptr, nullptr, nullptr));
  return file;
}

}  // namespace

TEST_CASE("read_exif_position: a picture's EXIF GPS tags, hemispheres and altitude below sea level, none without") {
  const fs::path dubai = exif_jpeg("exif_dubai.jpg", {{"EXIF_GPSLatitude", "(25) (12) (3.6)"},
                                                      {"EXIF_GPSLatitudeRef", "N"},
                                                      {"EXIF_GPSLongitude", "(55) (18) (12.3456)"},
                                                      {"EXIF_GPSLongitudeRef", "E"},
                                                      {"EXIF_GPSAltitude", "(51.23)"},
                                                      {"EXIF_GPSAltitudeRef", "0x00"}});
  const auto p = read_exif_position(dubai);
  REQUIRE(p.has_value());
  CHECK(p->latitude_deg == doctest::Approx(25.0 + 12.0 / 60.0 + 3.6 / 3600.0).epsilon(1e-12));
  CHECK(p->longitude_deg == doctest::Approx(55.0 + 18.0 / 60.0 + 12.3456 / 3600.0).epsilon(1e-12));
  REQUIRE(p->altitude_msl_m.has_value());
  CHECK(*p->altitude_msl_m == doctest::Approx(51.23));

  const fs::path south = exif_jpeg("exif_dead_sea.jpg", {{"EXIF_GPSLatitude", "(31.5) (0) (0)"},
                                                         {"EXIF_GPSLatitudeRef", "S"},
                                                         {"EXIF_GPSLongitude", "(35.5) (0) (0)"},
                                                         {"EXIF_GPSLongitudeRef", "W"},
                                                         {"EXIF_GPSAltitude", "(430)"},
                                                         {"EXIF_GPSAltitudeRef", "0x01"}});
  const auto q = read_exif_position(south);
  REQUIRE(q.has_value());
  CHECK(q->latitude_deg == doctest::Approx(-31.5));
  CHECK(q->longitude_deg == doctest::Approx(-35.5));
  CHECK(*q->altitude_msl_m == doctest::Approx(-430.0));

  // No GPS tags, or no altitude.
  CHECK_FALSE(read_exif_position(exif_jpeg("exif_none.jpg", {{"EXIF_Make", "none"}})).has_value());
  const auto flat = read_exif_position(exif_jpeg("exif_no_alt.jpg", {{"EXIF_GPSLatitude", "(1) (2) (3)"},
                                                                     {"EXIF_GPSLatitudeRef", "N"},
                                                                     {"EXIF_GPSLongitude", "(4) (5) (6)"},
                                                                     {"EXIF_GPSLongitudeRef", "E"}}));
  REQUIRE(flat.has_value());
  CHECK_FALSE(flat->altitude_msl_m.has_value());

  // Malformed: refused, naming the file and the tag.
  const fs::path bad_ref = exif_jpeg("exif_bad_ref.jpg", {{"EXIF_GPSLatitude", "(25) (12) (3.6)"},
                                                          {"EXIF_GPSLatitudeRef", "E"},
                                                          {"EXIF_GPSLongitude", "(55) (18) (12)"},
                                                          {"EXIF_GPSLongitudeRef", "E"}});
  CHECK_THROWS_WITH_AS((void)read_exif_position(bad_ref),
                       (bad_ref.string() + ": EXIF EXIF_GPSLatitudeRef 'E' is neither N nor S").c_str(),
                       std::invalid_argument);
  const fs::path bad_minutes = exif_jpeg("exif_bad_minutes.jpg", {{"EXIF_GPSLatitude", "(25) (75) (0)"},
                                                                  {"EXIF_GPSLatitudeRef", "N"},
                                                                  {"EXIF_GPSLongitude", "(55) (18) (12)"},
                                                                  {"EXIF_GPSLongitudeRef", "E"}});
  CHECK_THROWS_WITH_AS((void)read_exif_position(bad_minutes), doctest::Contains("is not degrees, minutes and seconds"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)read_exif_position(scratch() / "exif_missing.jpg"), doctest::Contains("file not found"),
                       std::invalid_argument);
}
