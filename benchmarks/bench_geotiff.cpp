// Loading a GeoTIFF field and writing its fused map as GeoTIFF: wall time and peak memory.
//   bench_geotiff FIELD_DIR OUT_DIR
// benchmarks/bench_geotiff.sh makes a 20000 x 20000 field from a bundled tile and runs this.
#include <adaptseg/gdal/gdal_io.hpp>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>

namespace {

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: bench_geotiff FIELD_DIR OUT_DIR\n");
    return 2;
  }
  try {
    const std::filesystem::path out = argv[2];
    std::filesystem::create_directories(out);
    const auto t0 = std::chrono::steady_clock::now();
    const adaptseg::Field field = adaptseg::gdal::load_field(argv[1]);
    const double load_s = seconds_since(t0);
    const double load_rss = peak_rss_mib();
    const double mib = 1024.0 * 1024.0;
    const double image_mib = static_cast<double>(field.image().total() * field.image().elemSize()) / mib;
    const double labels_mib = static_cast<double>(field.labels().total()) / mib;
    const auto t1 = std::chrono::steady_clock::now();
    adaptseg::gdal::write_map_geotiff(out / "map.tif", field, field.labels());
    const double write_s = seconds_since(t1);
    std::printf("field %d x %d px (%.1f x %.1f m at %.1f cm/px)\n", field.width_px(), field.height_px(),
                field.area().width_m(), field.area().height_m(), field.gsd_cm());
    std::printf(
        "load (gdal::load_field): %.2f s, peak RSS %.0f MiB; held: image %.0f MiB + labels %.0f MiB + "
        "valid mask %.0f MiB = %.0f MiB\n",
        load_s, load_rss, image_mib, labels_mib, labels_mib, image_mib + 2 * labels_mib);
    std::printf("write map.tif (DEFLATE): %.2f s, peak RSS %.0f MiB\n", write_s, peak_rss_mib());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_geotiff: %s\n", e.what());
    return 1;
  }
}
