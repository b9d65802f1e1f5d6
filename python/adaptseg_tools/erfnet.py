"""ERFNet (Romera, Alvarez, Bergasa, Arroyo: "ERFNet: Efficient Residual Factorized ConvNet for
Real-time Semantic Segmentation", T-ITS 2017), Table I, with a width multiplier on the channel
counts 16/64/128; and its inference graph with the transposed convolutions rewritten as
sub-pixel convolutions (an export option of train_segnet.py)."""

from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F


class DownsamplerBlock(nn.Module):
    """3x3 stride-2 conv (cout - cin channels) concatenated with 2x2 max-pooling, BN, ReLU."""

    def __init__(self, cin: int, cout: int):
        super().__init__()
        self.conv = nn.Conv2d(cin, cout - cin, 3, stride=2, padding=1, bias=True)
        self.pool = nn.MaxPool2d(2, stride=2)
        self.bn = nn.BatchNorm2d(cout, eps=1e-3)

    def forward(self, x):
        return F.relu(self.bn(torch.cat([self.conv(x), self.pool(x)], 1)))


class NonBottleneck1D(nn.Module):
    """Residual block of factorised convolutions: 3x1, ReLU, 1x3, BN, ReLU, 3x1 and 1x3 with
    dilation d, BN, dropout, then ReLU(x + block(x))."""

    def __init__(self, ch: int, dropout: float, dilation: int):
        super().__init__()
        d = dilation
        self.conv3x1_1 = nn.Conv2d(ch, ch, (3, 1), padding=(1, 0), bias=True)
        self.conv1x3_1 = nn.Conv2d(ch, ch, (1, 3), padding=(0, 1), bias=True)
        self.bn1 = nn.BatchNorm2d(ch, eps=1e-3)
        self.conv3x1_2 = nn.Conv2d(ch, ch, (3, 1), padding=(d, 0), dilation=(d, 1), bias=True)
        self.conv1x3_2 = nn.Conv2d(ch, ch, (1, 3), padding=(0, d), dilation=(1, d), bias=True)
        self.bn2 = nn.BatchNorm2d(ch, eps=1e-3)
        self.dropout = nn.Dropout2d(dropout) if dropout > 0 else nn.Identity()

    def forward(self, x):
        y = F.relu(self.conv3x1_1(x))
        y = F.relu(self.bn1(self.conv1x3_1(y)))
        y = F.relu(self.conv3x1_2(y))
        y = self.dropout(self.bn2(self.conv1x3_2(y)))
        return F.relu(y + x)


class UpsamplerBlock(nn.Module):
    """3x3 transposed conv, stride 2, BN, ReLU."""

    def __init__(self, cin: int, cout: int):
        super().__init__()
        self.conv = nn.ConvTranspose2d(cin, cout, 3, stride=2, padding=1, output_padding=1, bias=True)
        self.bn = nn.BatchNorm2d(cout, eps=1e-3)

    def forward(self, x):
        return F.relu(self.bn(self.conv(x)))


def erfnet_channels(width: float) -> tuple[int, int, int]:
    return tuple(max(4, int(round(c * width))) for c in (16, 64, 128))  # type: ignore[return-value]


class ERFNet(nn.Module):
    """Encoder: downsampler 3->c1, downsampler c1->c2, 5 x NB1D(c2), downsampler c2->c3,
    2 x [NB1D(c3) with dilations 2, 4, 8, 16]. Decoder: upsampler c3->c2, 2 x NB1D(c2),
    upsampler c2->c1, 2 x NB1D(c1), 2x2 stride-2 transposed conv c1->classes.
    (c1, c2, c3) = (16, 64, 128) x width. Input H and W must be multiples of 8."""

    def __init__(self, num_classes: int, width: float = 1.0, drop_enc1: float = 0.03,
                 drop_enc2: float = 0.3):
        super().__init__()
        c1, c2, c3 = erfnet_channels(width)
        enc = [DownsamplerBlock(3, c1), DownsamplerBlock(c1, c2)]
        enc += [NonBottleneck1D(c2, drop_enc1, 1) for _ in range(5)]
        enc += [DownsamplerBlock(c2, c3)]
        for _ in range(2):
            enc += [NonBottleneck1D(c3, drop_enc2, d) for d in (2, 4, 8, 16)]
        dec = [UpsamplerBlock(c3, c2), NonBottleneck1D(c2, 0, 1), NonBottleneck1D(c2, 0, 1),
               UpsamplerBlock(c2, c1), NonBottleneck1D(c1, 0, 1), NonBottleneck1D(c1, 0, 1)]
        self.encoder = nn.Sequential(*enc)
        self.decoder = nn.Sequential(*dec)
        self.output_conv = nn.ConvTranspose2d(c1, num_classes, 2, stride=2, bias=True)

    def forward(self, x):
        return self.output_conv(self.decoder(self.encoder(x)))




def _fold_bn(weight, bias, bn: nn.BatchNorm2d, reps: int):
    """Conv weight/bias followed by eval-mode `bn`, each BN channel covering `reps` conv
    output channels."""
    scale = bn.weight.detach() / torch.sqrt(bn.running_var + bn.eps)
    shift = bn.bias.detach() - bn.running_mean * scale
    s = scale.repeat_interleave(reps)
    return weight * s[:, None, None, None], bias * s + shift.repeat_interleave(reps)


def _pixel_shuffle_4d(y):
    """F.pixel_shuffle(y, 2) for batch 1 with 4-D reshapes/transposes only: OpenCV 4.6 runs
    ONNX DepthToSpace as a slow 6-D permute."""
    _, c4, h, w = y.shape
    c = c4 // 4
    y = y.reshape(c * 2, 2, h, w).permute(0, 2, 3, 1).reshape(c, 2, h, 2 * w)
    return y.permute(0, 2, 1, 3).reshape(1, c, 2 * h, 2 * w)


class SubPixelUpsampler(nn.Module):
    """A stride-2 ConvTranspose2d (kernel 3, padding 1, output_padding 1, or kernel 2,
    padding 0), optionally followed by BN and ReLU, rewritten exactly as an ordinary
    convolution producing the four output phases as channels, followed by a pixel shuffle.

    Kernel 3: output row 2m takes input row m with kernel row 1; output row 2m+1 takes input
    rows m (kernel row 2) and m+1 (kernel row 0); the same along columns. A 2x2 convolution
    with padding 1 whose output is cropped by one row/column at the top/left sees exactly the
    input window {m, m+1} (zero beyond the last row, as output_padding implies)."""

    def __init__(self, deconv: nn.ConvTranspose2d, bn: nn.BatchNorm2d | None, relu: bool):
        super().__init__()
        w = deconv.weight.detach()  # (cin, cout, kh, kw)
        cin, cout, kh, kw = w.shape
        if (kh, kw) == (3, 3) and deconv.stride == (2, 2) and deconv.padding == (1, 1) \
                and deconv.output_padding == (1, 1):
            k = torch.zeros(cout, 2, 2, cin, 2, 2)  # (o, phase y, phase x, c, window y, window x)
            taps = {(0, 0): 1, (1, 0): 2, (1, 1): 0}  # (phase, window offset) -> kernel index
            for (a, dy), ky in taps.items():
                for (b, dx), kx in taps.items():
                    k[:, a, b, :, dy, dx] = w[:, :, ky, kx].t()
            k = k.reshape(cout * 4, cin, 2, 2)
            self.crop = True
        elif (kh, kw) == (2, 2) and deconv.stride == (2, 2) and deconv.padding == (0, 0):
            k = w.permute(1, 2, 3, 0).reshape(cout * 4, cin, 1, 1)
            self.crop = False
        else:
            raise ValueError(f"unsupported ConvTranspose2d {deconv}")
        bias = deconv.bias.detach().repeat_interleave(4)
        if bn is not None:
            k, bias = _fold_bn(k, bias, bn, 4)
        self.conv = nn.Conv2d(cin, cout * 4, k.shape[-1], padding=1 if self.crop else 0)
        self.conv.weight.data.copy_(k)
        self.conv.bias.data.copy_(bias)
        self.relu = relu

    def forward(self, x):
        y = self.conv(x)
        if self.crop:
            y = y[:, :, 1:, 1:]
        if self.relu:
            y = F.relu(y)
        return _pixel_shuffle_4d(y)


class ERFNetInference(nn.Module):
    """`model` (in eval mode) with its transposed convolutions as SubPixelUpsampler: the same
    function up to float rounding (~1e-6). Tried as a way to avoid OpenCV DNN's Deconvolution
    layer; on the 2-core benchmark machine it was not measurably faster (docs/benchmarks.md),
    so the default export keeps ConvTranspose (--export-graph deconv). Batch 1 only."""

    def __init__(self, model: ERFNet):
        super().__init__()
        self.encoder = model.encoder
        self.decoder = nn.Sequential(*[SubPixelUpsampler(b.conv, b.bn, True) if isinstance(b, UpsamplerBlock)
                                       else b for b in model.decoder])
        self.output_conv = SubPixelUpsampler(model.output_conv, None, False)

    def forward(self, x):
        return self.output_conv(self.decoder(self.encoder(x)))


