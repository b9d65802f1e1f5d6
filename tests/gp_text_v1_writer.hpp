#pragma once
// Writes a Gaussian process in adaptseg 0.1's line format (`adaptseg.gaussian_process 1`), as
// that version's GaussianProcess::save did, byte for byte: the library no longer writes the
// format, only reads it (detail/gp_text_v1.hpp), so the tests of that reader make their files
// here.

#include <adaptseg/core/gaussian_process.hpp>

#include <Eigen/Core>

#include <limits>
#include <locale>
#include <sstream>
#include <string>
#include <string_view>

namespace adaptseg::test {

template <Kernel K>
std::string gp_text_v1(const GaussianProcess<K>& gp) {
  const auto st = gp.state();
  std::ostringstream s;
  s.imbue(std::locale::classic());
  s.precision(std::numeric_limits<double>::max_digits10);
  const auto vec = [&s](std::string_view key, const Eigen::VectorXd& v) {
    s << key << ' ' << v.size();
    for (Eigen::Index i = 0; i < v.size(); ++i) s << ' ' << v(i);
    s << '\n';
  };
  s << "adaptseg.gaussian_process 1\n";
  s << "kernel " << K::kName << '\n';
  vec("log_parameters", st.kernel.log_parameters());
  vec("log_lower_bounds", st.kernel.log_lower_bounds());
  vec("log_upper_bounds", st.kernel.log_upper_bounds());
  s << "normalize_y " << (st.options.normalize_y ? 1 : 0) << '\n';
  s << "y_mean " << st.y_mean << '\n';
  s << "y_std " << st.y_std << '\n';
  s << "initial_jitter " << st.options.initial_jitter << '\n';
  s << "max_jitter_attempts " << st.options.max_jitter_attempts << '\n';
  s << "dimension " << gp.dimension() << '\n';
  s << "samples " << st.inputs.rows() << '\n';
  for (Eigen::Index i = 0; i < st.inputs.rows(); ++i) {
    for (Eigen::Index d = 0; d < st.inputs.cols(); ++d) s << st.inputs(i, d) << ' ';
    s << st.targets(i) << '\n';
  }
  s << "end adaptseg.gaussian_process\n";
  return s.str();
}

}  // namespace adaptseg::test
