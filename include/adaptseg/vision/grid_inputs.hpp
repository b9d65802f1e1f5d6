#pragma once
/// @file
/// One image's decision inputs summed over cells of the map grid straight from the camera frame
/// (beyond the paper): what the adaptive planner computes once per top-level image (every
/// candidate cell of every candidate GSD, and the region) and once per descent image (the scene
/// check). The same sums, to the bit, as cell_inputs() of planes_on_grid() (image_summary.hpp).

#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/detail/exact_sum.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/image_summary.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg {

/// One image's decision inputs as the map grid sees them over `rect`, summed cell by cell
/// without bringing any plane onto the grid: cell() gives, to the bit, cell_inputs() of
/// planes_on_grid() of pixel_inputs() for the inputs it was built with (the others NaN), at a
/// fraction of the cost. What the planner computes once per top-level image (every candidate
/// cell of every candidate GSD, and the region) and once per descent image (the scene check).
class GridInputs {
 public:
  /// How many cells will be asked for: `many` sums each camera row once up front (prefix sums),
  /// so that each further cell costs its rows, not its pixels; `one` does not.
  enum class Cells { one, many };

  /// No image yet (assign() one).
  GridInputs() = default;

  /// The inputs `inputs` (σ is always among them: a cell's field pixels are those σ knows) of
  /// `image` segmented as `segmentation` (labels and, where given, probabilities or member
  /// votes), over the map pixels `rect`.
  /// @throws std::invalid_argument as pixel_inputs() and planes_on_grid().
  GridInputs(const Image& image, const Segmentation& segmentation, std::span<const int> interest, int ignore_label,
             cv::Rect rect, std::span<const DecisionInput> inputs, Cells cells = Cells::many) {
    assign(image, segmentation, interest, ignore_label, rect, inputs, cells);
  }

  /// As the constructor, reusing this object's buffers (a planner that sums every image's
  /// inputs allocates them once).
  /// @throws std::invalid_argument as the constructor.
  void assign(const Image& image, const Segmentation& segmentation, std::span<const int> interest, int ignore_label,
              cv::Rect rect, std::span<const DecisionInput> inputs, Cells cells = Cells::many) {
    rect_ = rect;
    fp_ = image.footprint_px;
    camera_ = cv::Size(image.width_px, image.height_px);
    wanted_.fill(false);
    wanted_list_.clear();
    index_.clear();
    for (auto& p : prefix_sum_) p.clear();
    for (auto& p : prefix_count_) p.clear();
    const cv::Mat& labels = segmentation.labels;
    detail::require(labels.type() == CV_8UC1 && labels.cols == image.width_px && labels.rows == image.height_px,
                    "GridInputs: labels must be CV_8UC1 of the image's size", labels.cols);
    for (const auto* planes : {&segmentation.probabilities, &segmentation.member_votes})
      for (const cv::Mat& p : *planes)
        detail::require(p.type() == CV_32FC1 && p.size() == labels.size(),
                        "GridInputs: probabilities and member votes must be CV_32FC1 planes of the labels' size",
                        p.cols);
    wanted_[index_of(DecisionInput::sigma)] = true;
    for (DecisionInput i : inputs) wanted_[index_of(i)] = true;
    camera_units(segmentation, interest, ignore_label);
    const FootprintFrame frame(image);
    if (frame.turned()) {
      index_.assign(static_cast<std::size_t>(rect.area()), -1);
      const double su = image.width_px / static_cast<double>(fp_.width);
      const double sv = image.height_px / static_cast<double>(fp_.height);
      for (int y = 0; y < rect.height; ++y)
        for (int x = 0; x < rect.width; ++x) {
          const cv::Point2d f = frame.to_footprint(rect.x + x + 0.5, rect.y + y + 0.5);
          const double u = std::floor(f.x * su), v = std::floor(f.y * sv);
          if (u < 0.0 || v < 0.0 || u >= image.width_px || v >= image.height_px) continue;
          index_[static_cast<std::size_t>(y) * static_cast<std::size_t>(rect.width) + static_cast<std::size_t>(x)] =
              static_cast<int>(v) * image.width_px + static_cast<int>(u);
        }
      return;
    }
    // Which camera column / row each footprint column / row reads: the resampling of
    // planes_on_grid() (INTER_NEAREST_EXACT) applied to the indices themselves.
    cv::Mat cols(1, image.width_px, CV_32SC1), rows(image.height_px, 1, CV_32SC1);
    for (int x = 0; x < image.width_px; ++x) cols.at<int>(0, x) = x;
    for (int y = 0; y < image.height_px; ++y) rows.at<int>(y, 0) = y;
    cv::Mat up_cols, up_rows;
    cv::resize(cols, up_cols, cv::Size(fp_.width, 1), 0, 0, cv::INTER_NEAREST_EXACT);
    cv::resize(rows, up_rows, cv::Size(1, fp_.height), 0, 0, cv::INTER_NEAREST_EXACT);
    col_of_.assign(up_cols.ptr<int>(0), up_cols.ptr<int>(0) + fp_.width);
    row_of_.resize(static_cast<std::size_t>(fp_.height));
    for (int y = 0; y < fp_.height; ++y) row_of_[static_cast<std::size_t>(y)] = up_rows.at<int>(y, 0);
    if (rows_fit_ && cells == Cells::many) prefix_sums();
  }

  /// The map pixels the inputs are over.
  [[nodiscard]] cv::Rect rect() const noexcept { return rect_; }

  /// cell_inputs() over `cell` (map pixels in rect()'s frame) where `field` (CV_8UC1 of rect()'s
  /// size, non-zero = field) is set and the image saw something; the inputs it was not built
  /// with are NaN.
  /// @throws std::invalid_argument for a field mask of another size or type.
  [[nodiscard]] CellInputs cell(const cv::Mat& field, cv::Rect cell) const {
    detail::require(field.type() == CV_8UC1 && field.size() == rect_.size(),
                    "GridInputs::cell: the field mask must be CV_8UC1 of the rect's size", field.cols);
    const cv::Rect r = cell & cv::Rect(0, 0, rect_.width, rect_.height);
    if (rows_fit_ && index_.empty()) return cell_by_camera_pixels(field, r);
    std::array<detail::ExactSum, kDecisionInputCount> sum{};
    std::array<std::int64_t, kDecisionInputCount> count{};
    std::int64_t field_px = 0;
    // Per row: the camera pixel index of each map pixel (-1: outside the footprint), then the
    // row's sums in plain integers (a row's units fit 64 bits), added to the exact sums.
    std::vector<int> source(static_cast<std::size_t>(std::max(0, r.width)));
    for (int y = r.y; y < r.y + r.height; ++y) {
      if (!source_row(y, r.x, r.width, source)) continue;
      const auto* f = field.ptr<unsigned char>(y) + r.x;
      std::array<std::int64_t, kDecisionInputCount> row_sum{};
      for (int x = 0; x < r.width; ++x) {
        const int s = source[static_cast<std::size_t>(x)];
        if (s < 0 || f[x] == 0) continue;
        const auto at = static_cast<std::size_t>(s);
        if (units_[index_of(DecisionInput::sigma)][at] == kUnknown) continue;
        ++field_px;
        for (std::size_t k : wanted_list_) {
          const std::int64_t v = units_[k][at];
          if (v == kUnknown) continue;
          if (rows_fit_)
            row_sum[k] += v;
          else
            sum[k].add(v);
          ++count[k];
        }
      }
      if (rows_fit_)
        for (std::size_t k : wanted_list_) sum[k].add(row_sum[k]);
    }
    return detail::cell_means(sum, count, field_px, wanted_);
  }

 private:
  static constexpr std::int64_t kUnknown = std::numeric_limits<std::int64_t>::min();

  /// Runs of consecutive map rows (columns) of [first, first + n) in rect()'s frame that read one
  /// camera row (column): (camera row, map rows) pairs, in order; `of` is row_of_ (col_of_) and
  /// `offset` rect()'s position in the footprint's frame along that axis.
  static std::vector<std::pair<int, std::int64_t>> runs(const std::vector<int>& of, int offset, int first, int n) {
    std::vector<std::pair<int, std::int64_t>> out;
    const int size = static_cast<int>(of.size());
    for (int k = std::max(first + offset, 0); k < std::min(first + n + offset, size); ++k) {
      const int camera = of[static_cast<std::size_t>(k)];
      if (!out.empty() && out.back().first == camera)
        ++out.back().second;
      else
        out.emplace_back(camera, 1);
    }
    return out;
  }

  /// cell() of an unturned image: each camera pixel once, weighted by the field pixels of the
  /// cell that read it (integer sums, so the same to the bit as map pixel by map pixel). A strip
  /// of map rows that read one camera row and are field across the cell (the common case) is
  /// summed from the row's prefix sums; elsewhere each camera pixel's block of field is counted.
  [[nodiscard]] CellInputs cell_by_camera_pixels(const cv::Mat& field, cv::Rect r) const {
    const auto row_runs = runs(row_of_, rect_.y - fp_.y, r.y, r.height);
    std::vector<std::pair<int, std::int64_t>> col_runs;  // made when a strip is partly field
    std::vector<std::int64_t> column_field;              // ... and its field pixels per map column
    std::array<detail::ExactSum, kDecisionInputCount> sum{};
    std::array<std::int64_t, kDecisionInputCount> count{};
    // The cell's map rows / columns inside the footprint, in the footprint's frame: [a, b).
    const int y_first = std::max(r.y, fp_.y - rect_.y), x_first = std::max(r.x, fp_.x - rect_.x);
    const int a = x_first + rect_.x - fp_.x, b = std::min(r.x + r.width + rect_.x - fp_.x, fp_.width);
    if (b <= a) return detail::cell_means(sum, count, 0, wanted_);
    const bool all_field = cv::countNonZero(field(r)) == r.area();  // then so is every strip
    int y0 = y_first;
    for (const auto& [camera_row, rows] : row_runs) {
      const cv::Mat strip = field(cv::Rect(r.x, y0, r.width, static_cast<int>(rows)));
      const int in_strip = all_field ? strip.rows * strip.cols : cv::countNonZero(strip);
      StripSums st{static_cast<std::size_t>(camera_row) * static_cast<std::size_t>(camera_.width), {}, {}};
      if (in_strip == strip.rows * strip.cols && !prefix_sum_[index_of(DecisionInput::sigma)].empty()) {
        add_field_strip(st, camera_row, a, b, rows);
      } else if (in_strip > 0) {
        if (col_runs.empty()) col_runs = runs(col_of_, rect_.x - fp_.x, r.x, r.width);
        const bool full = in_strip == strip.rows * strip.cols;
        // The strip's field pixels per map column, then per camera column's block of them.
        if (!full) {
          column_field.assign(static_cast<std::size_t>(rect_.width), 0);
          for (int y = y0; y < y0 + static_cast<int>(rows); ++y) {
            const auto* f = field.ptr<unsigned char>(y);
            for (int x = x_first; x < r.x + r.width; ++x)
              column_field[static_cast<std::size_t>(x)] += f[x] != 0 ? 1 : 0;
          }
        }
        int x0 = x_first;
        for (const auto& [camera_col, cols] : col_runs) {
          std::int64_t w = cols * rows;
          if (!full) {
            w = 0;
            for (int x = x0; x < x0 + static_cast<int>(cols); ++x) w += column_field[static_cast<std::size_t>(x)];
          }
          add(st, camera_col, w);
          x0 += static_cast<int>(cols);
        }
      }
      y0 += static_cast<int>(rows);
      for (std::size_t k : wanted_list_) {
        sum[k].add(st.sum[k]);
        count[k] += st.count[k];
      }
    }
    return detail::cell_means(sum, count, count[index_of(DecisionInput::sigma)], wanted_);
  }

  /// One strip's sums in cell_by_camera_pixels(): the camera row's first pixel `base`, each
  /// wanted input's units and known pixels.
  struct StripSums {
    std::size_t base = 0;
    std::array<std::int64_t, kDecisionInputCount> sum{}, count{};
  };

  /// Camera pixel `cx` of the strip's row read by `w` map pixels of the strip.
  void add(StripSums& st, int cx, std::int64_t w) const {
    const std::size_t at = st.base + static_cast<std::size_t>(cx);
    if (w == 0 || units_[index_of(DecisionInput::sigma)][at] == kUnknown) return;
    for (std::size_t k : wanted_list_) {
      const std::int64_t v = units_[k][at];
      if (v == kUnknown) continue;
      st.sum[k] += v * w;  // within 64 bits: rows_fit_
      st.count[k] += w;
    }
  }

  /// A strip of `rows` map rows reading camera row `camera_row`, field across the cell's
  /// footprint columns [a, b): the first and last camera columns as far as the cell reaches
  /// into them, those between from the row's prefix sums; then times the strip's rows.
  void add_field_strip(StripSums& st, int camera_row, int a, int b, std::int64_t rows) const {
    const int first = col_of_[static_cast<std::size_t>(a)], last = col_of_[static_cast<std::size_t>(b - 1)];
    if (first == last) {
      add(st, first, b - a);
    } else {
      add(st, first, col_start_[static_cast<std::size_t>(first) + 1] - a);
      add(st, last, b - col_start_[static_cast<std::size_t>(last)]);
      const std::size_t row = static_cast<std::size_t>(camera_row) * (static_cast<std::size_t>(camera_.width) + 1);
      for (std::size_t k : wanted_list_) {
        st.sum[k] += prefix_sum_[k][row + static_cast<std::size_t>(last)] -
                     prefix_sum_[k][row + static_cast<std::size_t>(first) + 1];
        st.count[k] += prefix_count_[k][row + static_cast<std::size_t>(last)] -
                       prefix_count_[k][row + static_cast<std::size_t>(first) + 1];
      }
    }
    for (std::size_t k : wanted_list_) st.sum[k] *= rows, st.count[k] *= rows;
  }

  /// Unturned: where each camera column's footprint columns start (col_start_), and per camera
  /// row the prefix sums over its columns of each wanted input's units and of its known pixels,
  /// each camera pixel weighted by the footprint columns that read it.
  void prefix_sums() {
    col_start_.assign(static_cast<std::size_t>(camera_.width) + 1, fp_.width);
    for (int u = fp_.width; u-- > 0;) col_start_[static_cast<std::size_t>(col_of_[static_cast<std::size_t>(u)])] = u;
    for (int cx = camera_.width; cx-- > 0;)  // columns no footprint column reads: where the next starts
      col_start_[static_cast<std::size_t>(cx)] =
          std::min(col_start_[static_cast<std::size_t>(cx)], col_start_[static_cast<std::size_t>(cx) + 1]);
    const std::size_t stride = static_cast<std::size_t>(camera_.width) + 1;
    const std::vector<std::int64_t>& sigma = units_[index_of(DecisionInput::sigma)];
    for (std::size_t k : wanted_list_) {
      prefix_sum_[k].assign(stride * static_cast<std::size_t>(camera_.height), 0);
      prefix_count_[k].assign(stride * static_cast<std::size_t>(camera_.height), 0);
      for (int cy = 0; cy < camera_.height; ++cy) {
        const std::size_t row = static_cast<std::size_t>(cy) * stride;
        const std::size_t at0 = static_cast<std::size_t>(cy) * static_cast<std::size_t>(camera_.width);
        std::int64_t s = 0, c = 0;
        for (int cx = 0; cx < camera_.width; ++cx) {
          const std::size_t at = at0 + static_cast<std::size_t>(cx);
          const std::int64_t w =
              col_start_[static_cast<std::size_t>(cx) + 1] - col_start_[static_cast<std::size_t>(cx)];
          if (w > 0 && sigma[at] != kUnknown && units_[k][at] != kUnknown) {
            s += units_[k][at] * w;
            c += w;
          }
          prefix_sum_[k][row + static_cast<std::size_t>(cx) + 1] = s;
          prefix_count_[k][row + static_cast<std::size_t>(cx) + 1] = c;
        }
      }
    }
  }

  /// The wanted inputs at every camera pixel, in units of 2^-32 (kUnknown for NaN).
  void camera_units(const Segmentation& segmentation, std::span<const int> interest, int ignore_label) {
    for (std::size_t k = 0; k < kDecisionInputCount; ++k)
      if (wanted_[k] && k != index_of(DecisionInput::boundary)) wanted_list_.push_back(k);
    // boundary's pixel quantity is σ's (cell_value() turns its mean into σ(1 − σ)).
    const cv::Mat& labels = segmentation.labels;
    const std::size_t total = labels.total();
    for (std::size_t k : wanted_list_) units_[k].resize(total);
    std::array<bool, 256> in_l{};
    for (int c : interest)
      if (c >= 0 && c < 256) in_l[static_cast<std::size_t>(c)] = true;
    const auto& probs = segmentation.probabilities;
    const auto& votes = segmentation.member_votes;
    std::vector<const float*> p_row(probs.size()), v_row(votes.size());
    // A row's values of the wanted inputs (pixel_input_rows: the one formula each), then in units.
    std::array<std::vector<float>, kDecisionInputCount> values{};
    std::array<float*, kDecisionInputCount> row_values{};
    for (std::size_t k : wanted_list_) {
      values[k].resize(static_cast<std::size_t>(labels.cols));
      row_values[k] = values[k].data();
    }
    std::array<bool, kDecisionInputCount> computed{};
    for (std::size_t k : wanted_list_) computed[k] = true;
    for (int y = 0; y < labels.rows; ++y) {
      const auto* l_row = labels.ptr<unsigned char>(y);
      for (std::size_t c = 0; c < probs.size(); ++c) p_row[c] = probs[c].ptr<float>(y);
      for (std::size_t c = 0; c < votes.size(); ++c) v_row[c] = votes[c].ptr<float>(y);
      pixel_input_rows(static_cast<std::size_t>(labels.cols), l_row, p_row, v_row, in_l, computed, row_values);
      const std::size_t row_start = static_cast<std::size_t>(y) * static_cast<std::size_t>(labels.cols);
      for (std::size_t k : wanted_list_) {
        std::int64_t* out = units_[k].data() + row_start;
        const float* v = values[k].data();
        for (int x = 0; x < labels.cols; ++x)
          out[x] = l_row[x] == ignore_label || std::isnan(v[x]) ? kUnknown : detail::exact_units(v[x]);
      }
    }
    if (wanted_[index_of(DecisionInput::boundary)]) {
      wanted_list_.push_back(index_of(DecisionInput::boundary));
      units_[index_of(DecisionInput::boundary)] = units_[index_of(DecisionInput::sigma)];
    }
    // The largest value an input takes at a pixel: a count over the classes of L, or a share.
    std::size_t classes = 0;
    for (int c : interest) classes += c >= 0 && c < 256 ? 1 : 0;
    const auto largest = static_cast<std::int64_t>(std::max<std::size_t>(1, classes)) * (std::int64_t{1} << 32);
    // A strip's sum: at most a whole footprint's pixels (or the rect's) times the largest value.
    const std::int64_t most_px =
        std::max<std::int64_t>(1, std::max(static_cast<std::int64_t>(fp_.width) * fp_.height,
                                           static_cast<std::int64_t>(rect_.width) * rect_.height));
    rows_fit_ = largest <= (std::int64_t{1} << 62) / most_px;
  }

  /// The camera pixel index of map pixels x0 .. x0 + n - 1 of row y (rect()'s frame) into
  /// `out`; false if none lies in the footprint.
  bool source_row(int y, int x0, int n, std::vector<int>& out) const {
    if (!index_.empty()) {
      const auto* row = index_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(rect_.width) +
                        static_cast<std::size_t>(x0);
      std::copy(row, row + n, out.begin());
      return true;
    }
    const int v = rect_.y + y - fp_.y;
    if (v < 0 || v >= fp_.height) return false;
    const int base = row_of_[static_cast<std::size_t>(v)] * camera_.width;
    bool any = false;
    for (int x = 0; x < n; ++x) {
      const int u = rect_.x + x0 + x - fp_.x;
      const bool in = u >= 0 && u < fp_.width;
      out[static_cast<std::size_t>(x)] = in ? base + col_of_[static_cast<std::size_t>(u)] : -1;
      any = any || in;
    }
    return any;
  }

  cv::Rect rect_;
  cv::Rect fp_;
  cv::Size camera_;
  std::array<bool, kDecisionInputCount> wanted_{};
  std::vector<std::size_t> wanted_list_;  ///< the wanted inputs' indices (boundary last)
  std::array<std::vector<std::int64_t>, kDecisionInputCount> units_{};
  std::vector<int> col_of_, row_of_;  ///< unturned: camera column / row of each footprint column / row
  std::vector<int> col_start_;        ///< unturned: first footprint column reading each camera column (+ the end)
  /// Unturned: per camera row (camera width + 1 entries each), prefix sums of a wanted input's
  /// units and of its known pixels, weighted by the footprint columns reading each pixel.
  std::array<std::vector<std::int64_t>, kDecisionInputCount> prefix_sum_{}, prefix_count_{};
  std::vector<int> index_;  ///< turned: camera pixel of each map pixel of rect (-1: none)
  /// A row's sum of units fits 64 bits (always, but for inputs of hundreds of classes over
  /// rows of millions of pixels): rows are summed in plain integers, else pixel by pixel.
  bool rows_fit_ = true;
};

}  // namespace adaptseg
