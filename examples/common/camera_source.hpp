#pragma once
// Where adaptseg_live's images come from (docs/programs.md, "Flying a vehicle"): a recorded
// folder of posed images (replay), a folder a real camera writes into (watched after each
// trigger), or a camera simulated over a bundled field at the vehicle's measured pose. Each
// gives one Shot per waypoint: the image, the ground-truth labels where it has them (the
// oracle's), and the pose to fuse it at. Not part of the library.

#include "common/image_set.hpp"

#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// A camera's pose in the flight frame: x, y [m], z the altitude above ground [m], and the yaw
/// of its image x axis [deg, counter-clockwise from the frame's +x axis] (Image::yaw_deg).
struct CameraPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw_deg = 0.0;
};

/// One picture from a camera source.
struct Shot {
  std::string name;  ///< its file (or a label) for the console and result.json
  cv::Mat bgr;       ///< CV_8UC3 (B, G, R) of the camera model's size, or empty (no image: the oracle's labels only)
  cv::Mat labels;    ///< ground-truth labels under the footprint at map resolution (the oracle's), or empty
  CameraPose pose;   ///< where it was taken: what the planner fuses it at
  std::filesystem::path file;  ///< the picture's file, where it is a new file (FolderCamera), else empty
};

/// Waits `seconds` while keeping whatever must stay alive meanwhile (the vehicle link) alive.
using Idle = std::function<void(double seconds)>;

/// A camera the live loop takes one picture per waypoint with.
class CameraSource {
 public:
  virtual ~CameraSource() = default;
  /// For the console: what the images are.
  [[nodiscard]] virtual std::string description() const = 0;
  /// Just before the trigger: a watched folder notes the files it holds.
  virtual void before_trigger() {}
  /// The picture taken with the camera at `at` (the vehicle's measured pose at the trigger, or
  /// the waypoint itself when a recorded folder is replayed without a vehicle).
  /// @throws std::invalid_argument (one line) when there is none.
  virtual Shot take(const CameraPose& at, const Idle& idle) = 0;
};

/// `picture` as the planner takes it: 8-bit BGR (grey and BGRA converted) of the camera model's
/// size, resampled with area interpolation where it has another size of the same aspect ratio
/// (within 1 %; a camera that crops or pads is not resampled into shape).
/// @throws std::invalid_argument naming `what`, both sizes and what to do.
inline cv::Mat fit_to_camera(cv::Mat picture, const CameraParams& camera, const std::string& what) {
  if (picture.empty()) return picture;
  if (picture.depth() != CV_8U)
    throw std::invalid_argument(what + ": an 8-bit image is needed (got OpenCV depth " +
                                std::to_string(picture.depth()) + ")");
  if (picture.channels() == 1)
    cv::cvtColor(picture, picture, cv::COLOR_GRAY2BGR);
  else if (picture.channels() == 4)
    cv::cvtColor(picture, picture, cv::COLOR_BGRA2BGR);
  else if (picture.channels() != 3)
    throw std::invalid_argument(what + ": 1, 3 or 4 channels expected (got " + std::to_string(picture.channels()) +
                                ")");
  const int w = camera.image_width_px, h = camera.image_height_px;
  if (picture.cols == w && picture.rows == h) return picture;
  const double want = static_cast<double>(w) / h, got = static_cast<double>(picture.cols) / picture.rows;
  if (std::abs(got / want - 1.0) > 0.01)
    throw std::invalid_argument(what + ": the image is " + std::to_string(picture.cols) + "x" +
                                std::to_string(picture.rows) + " (aspect " + fmt(got, 3) +
                                "), the decision model's camera " + std::to_string(w) + "x" + std::to_string(h) +
                                " (aspect " + fmt(want, 3) +
                                "): crop the images to the camera's aspect ratio, or calibrate a model for this "
                                "camera (adaptseg_calibrate --image-width " +
                                std::to_string(picture.cols) + " --image-height " + std::to_string(picture.rows) +
                                " --sensor-width-mm ... --focal-mm ...)");
  cv::Mat out;
  cv::resize(picture, out, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  return out;
}

/// Sets `image.ground_truth` to `labels` (the oracle's). A pose known to the centimetre can
/// move each footprint edge that lies half-way between map pixels by one pixel, and a measured
/// altitude off by some centimetres scales the footprint: labels at most 2 pixels off each way,
/// or of the footprint's aspect ratio (within 2 %), are stretched to it (nearest neighbour), as a
/// camera image is to the footprint of the pose it is reported at; any other size is an error
/// naming `what`.
inline void attach_labels(Image& image, cv::Mat labels, const std::string& what) {
  const cv::Size want = image.footprint_px.size(), got = labels.size();
  const bool near = std::abs(got.width - want.width) <= 2 && std::abs(got.height - want.height) <= 2;
  const bool same_shape =
      !labels.empty() && want.area() > 0 &&
      std::abs(static_cast<double>(got.width) * want.height / (static_cast<double>(got.height) * want.width) - 1.0) <=
          0.02;
  if (labels.type() == CV_8UC1 && got != want && (near || same_shape))
    cv::resize(cv::Mat(labels), labels, want, 0, 0, cv::INTER_NEAREST);
  if (labels.type() != CV_8UC1 || labels.size() != want)
    throw std::invalid_argument(what + ": must be 8-bit single-channel labels of the footprint's " +
                                std::to_string(want.width) + "x" + std::to_string(want.height) + " map pixels (got " +
                                std::to_string(got.width) + "x" + std::to_string(got.height) + ")");
  image.ground_truth = std::move(labels);
}

/// A recorded folder (adaptseg_live --record-from, docs/data_format.md "The live image folder"):
/// the image whose recorded pose lies nearest `at`, within a tolerance; its recorded pose is the
/// one it was taken at.
class RecordedCamera final : public CameraSource {
 public:
  /// `rgb`: read rgb/FILE (a network segments it); `labels`: read labels/FILE (the oracle's).
  RecordedCamera(std::filesystem::path dir, std::vector<PosedImage> images, double tolerance_m, bool rgb, bool labels,
                 CameraParams camera)
      : dir_(std::move(dir)),
        images_(std::move(images)),
        tolerance_m_(tolerance_m),
        rgb_(rgb),
        labels_(labels),
        camera_(camera) {}

  [[nodiscard]] std::string description() const override {
    return "the recorded folder " + dir_.string() + " (poses within " + fmt(tolerance_m_, 2) + " m)";
  }

  Shot take(const CameraPose& at, const Idle&) override {
    const PosedImage& p = find_image(images_, at.position, tolerance_m_);
    Shot s{p.file, {}, {}, {p.pose, p.yaw_deg}, {}};
    if (rgb_)
      s.bgr = fit_to_camera(read(dir_ / "rgb" / p.file, cv::IMREAD_COLOR, "camera image"), camera_,
                            (dir_ / "rgb" / p.file).string());
    if (labels_) s.labels = read(dir_ / "labels" / p.file, cv::IMREAD_UNCHANGED, "labels");
    return s;
  }

  /// The labels' file of a shot, for messages.
  [[nodiscard]] std::filesystem::path labels_file(const Shot& s) const { return dir_ / "labels" / s.name; }

 private:
  static cv::Mat read(const std::filesystem::path& path, int flags, const char* what) {
    if (!std::filesystem::is_regular_file(path))
      throw std::invalid_argument(path.string() + ": no " + what + " for this waypoint's image (poses.csv names it)");
    cv::Mat m = cv::imread(path.string(), flags);
    if (m.empty()) throw std::invalid_argument(path.string() + ": cannot decode the " + what);
    return m;
  }

  std::filesystem::path dir_;
  std::vector<PosedImage> images_;
  double tolerance_m_;
  bool rgb_, labels_;
  CameraParams camera_;
};

/// A folder a real camera (or its download script) writes each picture into: after a trigger,
/// the first new image file (.jpg, .jpeg, .png, .tif, .tiff) that appears within the timeout and
/// decodes is the picture, taken at the pose measured at the trigger (or where its EXIF tags say:
/// adaptseg_live --image-pose exif reads Shot::file).
class FolderCamera final : public CameraSource {
 public:
  FolderCamera(std::filesystem::path dir, double timeout_s, CameraParams camera)
      : dir_(std::move(dir)), timeout_s_(timeout_s), camera_(camera) {
    if (!std::filesystem::is_directory(dir_))
      throw std::invalid_argument("--camera-folder " + dir_.string() + ": not a directory");
    before_trigger();
  }

  [[nodiscard]] std::string description() const override {
    return "new images in " + dir_.string() + " (waiting up to " + fmt(timeout_s_, 1) + " s after each trigger)";
  }

  void before_trigger() override { seen_ = listing(); }

  Shot take(const CameraPose& at, const Idle& idle) override {
    const auto t0 = std::chrono::steady_clock::now();
    const auto waited = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
    std::map<std::filesystem::path, std::uintmax_t> sizes;  // new files and their size at the last look
    for (;;) {
      for (const auto& [path, size] : listing()) {
        if (seen_.count(path) != 0) continue;
        // A file whose size held for one look has been written; one that does not decode yet is
        // looked at again.
        const auto it = sizes.find(path);
        if (it != sizes.end() && it->second == size && size > 0) {
          cv::Mat m = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
          if (!m.empty()) {
            before_trigger();
            return {path.filename().string(), fit_to_camera(std::move(m), camera_, path.string()), {}, at, path};
          }
        }
        sizes[path] = size;
      }
      if (waited() >= timeout_s_)
        throw std::invalid_argument("--camera-folder " + dir_.string() + ": no new image within " + fmt(timeout_s_, 1) +
                                    " s of the trigger (--camera-timeout-s)");
      idle(0.1);
    }
  }

 private:
  [[nodiscard]] std::map<std::filesystem::path, std::uintmax_t> listing() const {
    std::map<std::filesystem::path, std::uintmax_t> out;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir_, ec)) {
      if (!e.is_regular_file(ec)) continue;
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(),
                     [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (ext == ".jpg" || ext == ".jpeg" || ext == ".png" || ext == ".tif" || ext == ".tiff")
        out[e.path()] = e.file_size(ec);
    }
    return out;
  }

  std::filesystem::path dir_;
  double timeout_s_;
  CameraParams camera_;
  std::map<std::filesystem::path, std::uintmax_t> seen_;
};

/// A nadir camera simulated over a field (SimulatedSensor) at the pose it is given: its
/// orthomosaic (if any) resampled to the camera and its labels under the footprint. The flight
/// frame is the field's, or another georeferenced frame (`flight`: the --area site's), the pose
/// then carried over through WGS84.
class SimulatedCamera final : public CameraSource {
 public:
  /// `flight`: the flight frame where it is not the field's, with its map GSD `map_gsd_cm` (the
  /// labels are resampled to it).
  SimulatedCamera(Field field, CameraParams camera, std::optional<FieldGeo> flight = std::nullopt,
                  double map_gsd_cm = 0.0)
      : sensor_(std::move(field), CameraModel(camera)), map_gsd_cm_(map_gsd_cm) {
    if (flight && !(sensor_.field().geo() && *sensor_.field().geo() == *flight)) {
      if (!sensor_.field().geo())
        throw std::invalid_argument("--simulate-camera: field '" + sensor_.field().name() +
                                    "' needs a geo-reference (geo: in field.yaml or --geo-origin) to be flown in "
                                    "another frame (--area)");
      flight_.emplace(*flight);
      field_geo_.emplace(*sensor_.field().geo());
    }
  }

  [[nodiscard]] std::string description() const override {
    return "a camera simulated over field '" + sensor_.field().name() + "'";
  }

  Shot take(const CameraPose& at, const Idle&) override {
    CameraPose here = at;  // in the field's frame
    if (flight_) {
      here.position = field_geo_->to_field(flight_->to_wgs84(at.position));
      here.position.z() = at.position.z();
      // A yaw is the frame's heading less the bearing of the image's x axis.
      here.yaw_deg = at.yaw_deg + field_geo_->geo().heading_deg - flight_->geo().heading_deg;
    }
    const CameraModel& camera = sensor_.camera();
    detail::require(here.position.allFinite() && here.position.z() > 0.0,
                    "--simulate-camera: the camera must be above the ground; altitude [m]", here.position.z());
    // The footprint at the measured altitude; a GSD finer than the orthomosaic's (a vehicle a
    // little below the finest waypoint) is cut out at the orthomosaic's own resolution.
    const double gsd = camera.gsd_cm(here.position.z());
    const Extent fp = camera.footprint_at_gsd(gsd);
    Waypoint w;
    w.position = here.position;
    w.gsd_cm = std::max(gsd, sensor_.field().gsd_cm());
    w.footprint = {here.position.x() - 0.5 * fp.width_m, here.position.y() - 0.5 * fp.height_m,
                   here.position.x() + 0.5 * fp.width_m, here.position.y() + 0.5 * fp.height_m};
    Image img = sensor_.capture(w, here.yaw_deg);
    const double scale = map_gsd_cm_ > 0.0 ? sensor_.field().gsd_cm() / map_gsd_cm_ : 1.0;
    if (std::abs(scale - 1.0) > 1e-9) {
      const cv::Size size(std::max(1, static_cast<int>(std::lround(img.ground_truth.cols * scale))),
                          std::max(1, static_cast<int>(std::lround(img.ground_truth.rows * scale))));
      cv::resize(cv::Mat(img.ground_truth), img.ground_truth, size, 0, 0, cv::INTER_NEAREST);
    }
    char name[96];
    std::snprintf(name, sizeof name, "sim-%05zu", shots_++);
    return {name, std::move(img.bgr), std::move(img.ground_truth), at, {}};
  }

 private:
  SimulatedSensor sensor_;
  double map_gsd_cm_;
  std::optional<GeoReference> flight_, field_geo_;
  std::size_t shots_ = 0;
};

}  // namespace adaptseg::examples
