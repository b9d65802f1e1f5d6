// Times the ONNX backend (OpenCV DNN) on one camera image: the network's forward pass alone
// (at its input size) and the whole OnnxSegmenter::segment (resampling to the input size if
// the camera's differs, normalisation, forward, logits resampled to the camera size, argmax).
// Driven by benchmarks/bench_erfnet.py, which runs PyTorch on the same weights side by side.
//
//   bench_erfnet MODEL_DIR [--threads N] [--iters K] [--warmup W] [--image PNG]
//                [--camera WxH] [--no-fusion]
//
// --camera: size of the random camera image (default: the network's input size).
// Prints one JSON object: {"threads": N, "iters": K, "input": [H, W], "camera": [H, W],
// "forward_ms": {"median", "min", "max"}, "segment_ms": {...}, "opencv": "4.6.0"}.

#include "bench_timing.hpp"

#include <adaptseg/erfnet/onnx_segmenter.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

namespace {

using adaptseg::bench::Stats;
using adaptseg::bench::stats;
using adaptseg::bench::time_ms;

void print_stats(const char* key, const Stats& s) {
  std::printf("\"%s\": {\"median\": %.3f, \"min\": %.3f, \"max\": %.3f}", key, s.median, s.min, s.max);
}

int usage() {
  std::cerr << "usage: bench_erfnet MODEL_DIR [--threads N] [--iters K] [--warmup W] [--image PNG] [--camera WxH] "
               "[--no-fusion]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string model_dir = argv[1];
  int threads = 1, iters = 30, warmup = 5;
  bool fusion = true;
  std::string image_file;
  cv::Size camera;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("missing value after " + a);
      return argv[++i];
    };
    try {
      if (a == "--threads")
        threads = std::stoi(next());
      else if (a == "--iters")
        iters = std::stoi(next());
      else if (a == "--warmup")
        warmup = std::stoi(next());
      else if (a == "--image")
        image_file = next();
      else if (a == "--camera") {
        const std::string v = next();
        const auto x = v.find('x');
        if (x == std::string::npos) throw std::invalid_argument("--camera expects WxH, got " + v);
        camera = {std::stoi(v.substr(0, x)), std::stoi(v.substr(x + 1))};
      } else if (a == "--no-fusion")
        fusion = false;
      else
        return usage();
    } catch (const std::exception& e) {
      std::cerr << "bench_erfnet: " << e.what() << '\n';
      return usage();
    }
  }
  if (threads < 1 || iters < 1 || warmup < 0) return usage();
  try {
    adaptseg::OnnxParams params;
    params.num_threads = threads;
    params.resize_to_network = true;
    adaptseg::OnnxSegmenter erfnet(model_dir, params);
    const cv::Size in = erfnet.input_size();
    if (camera.width <= 0 || camera.height <= 0) camera = in;

    adaptseg::Image image;
    if (!image_file.empty()) {
      image.bgr = cv::imread(image_file, cv::IMREAD_COLOR);
      if (image.bgr.empty()) throw std::invalid_argument("cannot read image " + image_file);
    } else {
      image.bgr.create(camera, CV_8UC3);
      cv::randu(image.bgr, 0, 256);
    }
    image.width_px = image.bgr.cols;
    image.height_px = image.bgr.rows;

    // The raw network, loaded the same way, for the forward pass alone.
    cv::dnn::Net net = cv::dnn::readNetFromONNX(model_dir + "/model.onnx");
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    net.enableFusion(fusion);
    const int shape[] = {1, 3, in.height, in.width};
    cv::Mat blob(4, shape, CV_32F);
    cv::randn(blob, 0.0, 1.0);

    const Stats fwd = stats(time_ms(
        [&] {
          net.setInput(blob);
          const cv::Mat out = net.forward();
          (void)out;
        },
        warmup, iters));
    const Stats seg = stats(time_ms([&] { (void)erfnet.segment(image); }, warmup, iters));

    std::printf(
        "{\"threads\": %d, \"cv_threads\": %d, \"iters\": %d, \"fusion\": %s, \"input\": [%d, %d], "
        "\"camera\": [%d, %d], ",
        threads, cv::getNumThreads(), iters, fusion ? "true" : "false", in.height, in.width, image.bgr.rows,
        image.bgr.cols);
    print_stats("forward_ms", fwd);
    std::printf(", ");
    print_stats("segment_ms", seg);
    std::printf(", \"opencv\": \"%s\"}\n", CV_VERSION);
  } catch (const std::exception& e) {
    std::cerr << "bench_erfnet: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
