#pragma once
/// @file
/// The header's name before adaptseg 0.3, kept for one version (it goes in 0.4): include
/// <adaptseg/erfnet/onnx_segmenter.hpp> (OnnxSegmenter, formerly ErfnetSegmenter).

#include <adaptseg/erfnet/onnx_segmenter.hpp>
