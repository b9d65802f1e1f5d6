// The network backend component: its header and target from the installed package.
#include <adaptseg/erfnet/onnx_segmenter.hpp>

#include <cstdio>

int main() {
  static_assert(adaptseg::SegmentationBackend<adaptseg::OnnxSegmenter>);
  const adaptseg::OnnxParams params;
  std::printf("erfnet consumer: the backend's contract holds; resize_to_network %d\n",
              params.resize_to_network ? 1 : 0);
  return 0;
}
