#pragma once
/// @file
/// Umbrella header of the network backends (CMake target adaptseg::erfnet; OpenCV DNN): a
/// segmentation network exported to ONNX (OnnxSegmenter) and an ensemble of them (EnsembleSegmenter).

#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
