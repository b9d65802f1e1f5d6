// GP files (gp_io.hpp): the YAML format written and read back with identical predictions,
// read by a plain YAML parser, locale-proof; adaptseg 0.1's line format refused by name.

#include "comma_locale.hpp"
#include "test_support.hpp"

#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/vision/gp_io.hpp>

#include <Eigen/Core>
#include <doctest/doctest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

using adaptseg::ArdSquaredExponentialKernel;
using adaptseg::GaussianProcess;
using adaptseg::SquaredExponentialKernel;
using doctest::Contains;
using Ard = GaussianProcess<ArdSquaredExponentialKernel>;

namespace {

/// 20 samples of a smooth 2-D function, fitted, then one online observation (so that the
/// frozen normalisation differs from the data's).
Ard fitted_model() {
  Eigen::MatrixXd x(20, 2);
  Eigen::VectorXd y(20);
  for (Eigen::Index i = 0; i < 20; ++i) {
    x(i, 0) = 0.25 * static_cast<double>(i);
    x(i, 1) = std::fmod(0.7 * static_cast<double>(i), 3.0);
    y(i) = 50.0 * (std::sin(x(i, 0)) + 0.5 * std::cos(2.0 * x(i, 1)));
  }
  Ard gp(ArdSquaredExponentialKernel(Eigen::Vector2d(1.0, 1.0), 1.0, 0.01), {.normalize_y = true});
  gp.fit(x, y, {.restarts = 1});
  gp.add_observation(Eigen::Vector2d(1.0, 2.0), 160.0);
  return gp;
}

Eigen::MatrixXd queries() {
  Eigen::MatrixXd q(6, 2);
  q << 0.1, 0.2, 1.3, 2.9, 2.2, 0.4, 4.0, 1.5, 4.9, 2.7, 0.0, 0.0;
  return q;
}

/// Bit-identical predictions (two models restored from the same state).
void check_identical(const Ard& a, const Ard& b) {
  const auto pa = a.predict(queries());
  const auto pb = b.predict(queries());
  CHECK(pa.mean == pb.mean);
  CHECK(pa.variance == pb.variance);
}

/// Same state, hence the same predictions.
void check_same(const Ard& a, const Ard& b) {
  CHECK(a.size() == b.size());
  CHECK(a.kernel().log_parameters() == b.kernel().log_parameters());
  CHECK(a.kernel().log_lower_bounds() == b.kernel().log_lower_bounds());
  CHECK(a.kernel().log_upper_bounds() == b.kernel().log_upper_bounds());
  CHECK(a.y_mean() == b.y_mean());
  CHECK(a.y_std() == b.y_std());
  CHECK(a.options().normalize_y == b.options().normalize_y);
  CHECK(a.training_inputs() == b.training_inputs());
  CHECK(a.training_targets() == b.training_targets());
  // Predictions bit-identical to those of `a` restored from its state in memory (the file
  // loses nothing); `a` itself may differ from both in the last bits, its samples added online
  // where a restored model factorises them all at once.
  check_identical(Ard::from_state(a.state()), b);
}

Ard load_text(const std::string& text) {
  std::istringstream is(text);
  return adaptseg::load_gaussian_process<ArdSquaredExponentialKernel>(is);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  REQUIRE(pos != std::string::npos);
  return text.replace(pos, from.size(), to);
}

}  // namespace

TEST_CASE("gp file: YAML round trip through a file and a stream, identical predictions") {
  const Ard gp = fitted_model();
  const adaptseg::test::TempDir dir;
  const auto path = dir.path() / "o.yaml";
  adaptseg::save_gaussian_process(gp, path);
  check_same(gp, adaptseg::load_gaussian_process<ArdSquaredExponentialKernel>(path));

  std::stringstream ss;
  adaptseg::save_gaussian_process(gp, ss);
  check_same(gp, adaptseg::load_gaussian_process<ArdSquaredExponentialKernel>(ss));

  // An empty model (no data, so no dimension yet) keeps its kernel.
  const Ard empty(ArdSquaredExponentialKernel(Eigen::Vector3d(1.0, 2.0, 3.0)));
  std::stringstream es;
  adaptseg::save_gaussian_process(empty, es);
  const Ard back = adaptseg::load_gaussian_process<ArdSquaredExponentialKernel>(es);
  CHECK(back.size() == 0);
  CHECK(back.kernel().log_parameters() == empty.kernel().log_parameters());

  std::filesystem::remove(path);
  CHECK_THROWS_WITH_AS((void)adaptseg::load_gaussian_process<ArdSquaredExponentialKernel>(path),
                       Contains("cannot open"), std::invalid_argument);
}

TEST_CASE("gp file: a plain YAML parser reads every quantity") {
  const Ard gp = fitted_model();
  std::stringstream ss;
  adaptseg::save_gaussian_process(gp, ss);
  const YAML::Node n = YAML::Load(ss.str());
  CHECK(n["format"].as<std::string>() == "adaptseg.gaussian_process/2");
  CHECK(n["kernel"].as<std::string>() == std::string(ArdSquaredExponentialKernel::kName));
  CHECK(n["log_parameters"].as<std::vector<double>>().size() == 4);
  CHECK(n["y_std"].as<double>() == gp.y_std());
  CHECK(n["normalize_y"].as<bool>());
  CHECK(n["dimension"].as<int>() == 2);
  REQUIRE(n["inputs"].size() == 21);
  CHECK(n["inputs"][20].as<std::vector<double>>() == std::vector<double>{1.0, 2.0});
  CHECK(n["targets"][20].as<double>() == 160.0);
}

TEST_CASE("gp file: written under a comma-decimal global locale, the same bytes and predictions") {
  const Ard gp = fitted_model();
  std::stringstream plain;
  adaptseg::save_gaussian_process(gp, plain);
  std::stringstream comma;
  {
    const adaptseg::test::CommaLocale guard;
    adaptseg::save_gaussian_process(gp, comma);
    CHECK(comma.str() == plain.str());
    check_same(gp, load_text(comma.str()));  // read under the comma locale too
  }
}

TEST_CASE("gp file: broken YAML files are rejected, naming the key") {
  const Ard gp = fitted_model();
  std::stringstream ss;
  adaptseg::save_gaussian_process(gp, ss);
  const std::string text = ss.str();
  CAPTURE(text);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "adaptseg.gaussian_process/2", "adaptseg.gaussian_process/3")),
                       Contains("format must be adaptseg.gaussian_process/2"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "squared_exponential_ard", "squared_exponential_isotropic")),
                       Contains("'kernel' must be squared_exponential_ard"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "y_std:", "y_sd:")), Contains("missing key 'y_std'"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "normalize_y: true", "normalize_y: 1")),
                       Contains("'normalize_y' must be true or false"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "[1, 2]", "[1, nan]")), Contains("'inputs[20]' must be a finite"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(text, "[1, 2]", "[1, 2, 3]")), Contains("rows must all have 2 values"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text(text.substr(0, text.find("targets:"))), Contains("missing key 'targets'"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text("[1, 2"), Contains("YAML error"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_text("- 1\n- 2\n"), Contains("must be a mapping"), std::invalid_argument);
  // The ARD kernel has one length scale per input: rows of another dimension are refused.
  const Ard one_d(ArdSquaredExponentialKernel(Eigen::VectorXd::Ones(1)));
  std::stringstream e1;
  adaptseg::save_gaussian_process(one_d, e1);
  CHECK_THROWS_WITH_AS((void)load_text(replaced(e1.str(), "dimension: 0", "dimension: 3")),
                       Contains("does not accept inputs of dimension 3"), std::invalid_argument);
}

TEST_CASE("gp file: adaptseg 0.1's line format is refused, saying to fit and save again") {
  // The first lines of a GP as adaptseg 0.1 wrote it (after comments and blank lines).
  const std::string old = "# decision-function model\n\nadaptseg.gaussian_process 1\nkernel squared_exponential_ard\n";
  CHECK_THROWS_WITH_AS((void)load_text(old),
                       Contains("a Gaussian process in adaptseg 0.1's line format is no longer read since adaptseg "
                                "0.2.0; fit it again and save it with save_gaussian_process"),
                       std::invalid_argument);
  // A YAML file whose format names another version is not mistaken for it.
  CHECK_THROWS_WITH_AS((void)load_text("format: adaptseg.gaussian_process 1\n"), Contains("format"),
                       std::invalid_argument);
}
