#!/usr/bin/env python3
"""Self-test of the MobileNetV2 encoders (mobilenet_v2.encoder_layout, mobilenet_v2_140) and of
train_segnet's --encoder (run by CTest; exit code != 0 on failure). No npm, no network: the graph
import runs on a synthetic manifest.

1. The default encoder is the bundled networks' own: its layout is Table 2's first eleven rows at
   width 1.0, and the bundled mobilenetv2-dubai's model.pt loads into MobileNetV2Seg strictly.
2. Width 1.4 to block_16: TF's channel rounding (48, 24, 32, 48, 88, 136, 224, 448), output stride
   16, the blocks after block_13 (which would reach 32) dilated by 2, and the encoder's features at strides 4, 8, 16.
3. The graph import: every folded convolution becomes its kernel (HWIO / HWC1 transposed) and a
   batch norm that adds its offset and nothing else, so in eval mode a ConvBN computes the graph's
   convolution plus offset; a tensor missing or of another shape is refused by name.
4. train_segnet --encoder mnv2-140-b16: one step on the CPU, exported (OpenCV DNN checks the ONNX),
   model.yaml names the encoder, load_exported builds it back with the same weights; --encoder with
   ERFNet and weights of the other encoder are refused.

Needs torch (Debian python3-torch): CTest's tools:mobilenet_v2_140 is skipped (exit 77) without it.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from tool_output import check, require_torch

require_torch()

import numpy as np  # noqa: E402
import torch  # noqa: E402
import torch.nn.functional as F  # noqa: E402
import yaml  # noqa: E402

from adaptseg_tools import REPO, mobilenet_v2, mobilenet_v2_140  # noqa: E402
from adaptseg_tools.training.models import load_exported  # noqa: E402


def refused(fn, fragment: str):
    try:
        fn()
    except SystemExit as e:
        check(fragment in str(e.code), f"'{e.code}' lacks '{fragment}'")
        print(f"ok: refused: {str(e.code)[:120]}")
        return
    check(False, f"not refused (wanted '{fragment}')")


def synthetic_graph(rng, drop: str = "", reshape: str = "") -> tuple[dict, bytes, dict]:
    """A weights manifest with the graph's names for every convolution of the width-1.4 encoder,
    uint8-quantised random values; also the dequantised values by graph name."""
    enc = mobilenet_v2.MobileNetV2Encoder(*mobilenet_v2.ENCODERS[mobilenet_v2_140.ENCODER])
    sd = enc.state_dict()
    prefix = "StatefulPartitionedCall/predict/" + mobilenet_v2_140.GRAPH_SCOPE
    specs, chunks, values = [], [], {}
    for tprefix, conv, kind in mobilenet_v2_140.graph_to_torch_names(len(enc.blocks)):
        o, i, kh, kw = sd[f"{tprefix}.0.weight"].shape
        shape = [kh, kw, o, 1] if kind == "depthwise" else [kh, kw, i, o]
        for name, shp in ((f"{conv}_weights", shape), (f"{conv}_bn_offset", [o])):
            if name == drop:
                continue
            if name == reshape:
                shp = [s + 1 for s in shp]
            raw = rng.integers(0, 256, int(np.prod(shp)), dtype=np.uint8)
            q = {"min": -0.1, "scale": 0.2 / 255.0, "dtype": "uint8"}  # activations of a sane size
            specs.append({"name": prefix + name, "shape": shp, "dtype": "float32", "quantization": q})
            chunks.append(raw.tobytes())
            values[name] = (raw.astype(np.float32) * np.float32(q["scale"]) + np.float32(q["min"])).reshape(shp)
    return {"weightsManifest": [{"weights": specs}]}, b"".join(chunks), values


def main():
    # 1. The default encoder is the bundled one.
    stem, layout = mobilenet_v2.encoder_layout(1.0, 10)
    check(stem == 32 and [(t, c, s) for t, c, s, _ in layout] == mobilenet_v2.BLOCKS
          and all(d == 1 for *_, d in layout), f"default layout {stem} {layout}")
    net = REPO / "examples" / "models" / "mobilenetv2-dubai"
    meta = yaml.safe_load((net / "model.yaml").read_text())
    model = mobilenet_v2.MobileNetV2Seg(len(meta["classes"]), 0.0, image_pooling=bool(meta.get("image_pooling")))
    model.load_state_dict(torch.load(net / "model.pt", map_location="cpu"))  # strict
    print("ok: the default encoder loads the bundled mobilenetv2-dubai strictly")

    # 2. Width 1.4, every block.
    stem, layout = mobilenet_v2.encoder_layout(1.4, 16)
    check(stem == 48, f"stem {stem}")
    check([c for _, c, _, _ in layout] == [24, 32, 32, 48, 48, 48, 88, 88, 88, 88, 136, 136, 136, 224, 224, 224, 448],
          f"channels {[c for _, c, _, _ in layout]}")
    check(2 * int(np.prod([s for _, _, s, _ in layout])) == 16, "output stride 16")
    check([d for *_, d in layout] == [1] * 14 + [2] * 3, f"dilations {[d for *_, d in layout]}")
    enc = mobilenet_v2.MobileNetV2Encoder(1.4, 16).eval()
    with torch.no_grad():
        f4, f8, f16 = enc(torch.zeros(1, 3, 64, 96))
    check(f4.shape[1:] == (32, 16, 24) and f8.shape[1:] == (48, 8, 12) and f16.shape[1:] == (448, 4, 6),
          f"features {f4.shape} {f8.shape} {f16.shape}")
    try:
        mobilenet_v2.encoder_layout(1.0, 17)
        check(False, "last block 17 accepted")
    except ValueError:
        print("ok: width 1.4 to block_16 at output stride 16; a block past 16 refused")

    # 3. The graph import on a synthetic manifest.
    rng = np.random.default_rng(0)
    graph, data, values = synthetic_graph(rng)
    sd = mobilenet_v2_140.encoder_state_dict(graph, data)
    w = values["expanded_conv_3/expand/Conv2D_weights"]  # H W I O
    check(torch.equal(sd["blocks.3.expand.0.weight"], torch.from_numpy(np.ascontiguousarray(w.transpose(3, 2, 0, 1)))),
          "1x1 kernel transposed HWIO -> OIHW")
    w = values["expanded_conv_5/depthwise/depthwise_weights"]  # H W C 1
    check(torch.equal(sd["blocks.5.depthwise.0.weight"], torch.from_numpy(np.ascontiguousarray(w.transpose(2, 3, 0, 1)))),
          "depthwise kernel transposed HWC1 -> C1HW")
    enc.load_state_dict(sd)
    enc.eval()
    x = torch.from_numpy(rng.standard_normal((1, 3, 32, 32)).astype(np.float32))
    with torch.no_grad():
        got = enc.stem(x)
        w = torch.from_numpy(np.ascontiguousarray(values["Conv/Conv2D_weights"].transpose(3, 2, 0, 1)))
        off = torch.from_numpy(values["Conv/Conv2D_bn_offset"])
        want = F.relu6(F.conv2d(F.pad(x, (0, 1, 0, 1)), w, stride=2) + off[None, :, None, None])
    check(float((got - want).abs().max()) < 1e-5, f"stem: ConvBN differs from conv + offset by {(got - want).abs().max()}")
    print("ok: kernels transposed, each batch norm adds the offset and nothing else")
    refused(lambda: mobilenet_v2_140.encoder_state_dict(*synthetic_graph(rng, drop="expanded_conv_7/project/Conv2D_bn_offset")[:2]),
            "expanded_conv_7/project/Conv2D_bn_offset")
    refused(lambda: mobilenet_v2_140.encoder_state_dict(*synthetic_graph(rng, reshape="expanded_conv_9/expand/Conv2D_weights")[:2]),
            "blocks.9.expand.0.weight")

    # 4. train_segnet --encoder mnv2-140-b16, one step.
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        torch.save(sd, t / "enc140.pt")
        torch.save(mobilenet_v2.MobileNetV2Encoder().state_dict(), t / "enc100.pt")
        common = [sys.executable, "-m", "adaptseg_tools.train_segnet", "--frozen-blocks", "4", "--no-image-pooling",
                  "--batch", "2", "--crop", "150", "--warmup", "1", "--steps", "1", "--val-every", "0",
                  "--val-max-images", "1", "--threads", "2", "--device", "cpu", "--train-fields", "dubai-tile-1",
                  "--val-field", "dubai-tile-2", "--test-field", "none"]
        run = subprocess.run(common + ["--arch", "mobilenetv2", "--encoder", "mnv2-140-b16", "--encoder-weights",
                                       str(t / "enc140.pt"), "--work-dir", str(t / "w"), "--model-dir", str(t / "m")],
                             capture_output=True, text=True)
        check(run.returncode == 0, f"training failed: {run.stdout[-2000:]} {run.stderr[-2000:]}")
        check("OpenCV DNN vs PyTorch" in run.stdout, "the export was not checked with OpenCV DNN")
        meta = yaml.safe_load((t / "m" / "model.yaml").read_text())
        check(meta.get("encoder") == "mnv2-140-b16" and "width 1.4" in meta["architecture"], f"model.yaml: {meta}")
        model, spec, meta = load_exported(t / "m")
        saved = torch.load(t / "m" / "model.pt", map_location="cpu")
        check(all(torch.equal(v, saved[k]) for k, v in model.state_dict().items()), "load_exported changed weights")
        check(model.encoder.channels[16] == 448, "load_exported built another encoder")
        print("ok: one step with --encoder mnv2-140-b16, exported, model.yaml names it, load_exported builds it")
        for extra, fragment in ((["--arch", "erfnet", "--crop", "160", "--encoder", "mnv2-140-b16"], "a MobileNetV2 option"),
                                (["--arch", "mobilenetv2", "--encoder", "mnv2-140-b16", "--encoder-weights",
                                  str(t / "enc100.pt")], "not the weights of --encoder mnv2-140-b16")):
            run = subprocess.run(common + extra + ["--work-dir", str(t / "w2"), "--model-dir", str(t / "m2")],
                                 capture_output=True, text=True)
            check(run.returncode != 0 and fragment in run.stderr, f"{extra}: rc {run.returncode}, {run.stderr[-500:]}")
            print(f"ok: refused: {run.stderr.strip().splitlines()[-1][:120]}")
    print("mobilenet_v2_140: all checks passed")


if __name__ == "__main__":
    main()
