#pragma once
/// @file
/// Umbrella header of the network backends (CMake target adaptseg::erfnet; OpenCV DNN): a
/// segmentation network exported to ONNX (OnnxSegmenter) and an ensemble of them (EnsembleSegmenter),
/// and a network on disk by its identity (network_identity.hpp).

#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/erfnet/network_identity.hpp>
#include <adaptseg/erfnet/onnx_model_info.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
