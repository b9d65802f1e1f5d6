// adaptseg::gdal from the installed package: GDAL found through it. A field georeferenced by
// geo: writes its map as a GeoTIFF, whose grid GDAL reads back.
#include <adaptseg/gdal/gdal_io.hpp>

#include <cstdio>
#include <filesystem>

int main() {
  const cv::Mat labels(40, 60, CV_8UC1, cv::Scalar(1));
  const adaptseg::Field field =
      adaptseg::Field("consumer", 10.0, labels, {{"soil", {0, 0, 0}}, {"crop", {0, 255, 0}}}, {1})
          .with_geo(adaptseg::FieldGeo{47.4, 8.5, 500.0, 90.0});
  const auto file = std::filesystem::temp_directory_path() / "adaptseg_consumer_map.tif";
  adaptseg::gdal::write_map_geotiff(file, field, field.labels());
  const adaptseg::gdal::RasterGrid grid = adaptseg::gdal::read_grid(file);
  std::printf("gdal consumer: map.tif %dx%d px of %.3f m\n", grid.width_px, grid.height_px, grid.pixel_size_m());
  return grid.width_px == 60 && grid.height_px == 40 && grid.pixel_size_m() > 0.0999 && grid.pixel_size_m() < 0.1001
             ? 0
             : 1;
}
