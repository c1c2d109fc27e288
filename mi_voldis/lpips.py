"""LPIPS (Zhang et al. 2018, "The Unreasonable Effectiveness of Deep Features as a Perceptual Metric"),
v0.1 with the AlexNet backbone, from local weight files (nothing is downloaded). Needs PyTorch
(``pip install .[clip]`` or ``.[bench]``).

    d(x, y) = sum_l mean_hw || w_l * (f_l(x) / |f_l(x)| - f_l(y) / |f_l(y)|) ||^2

with f_l the activations after AlexNet's five ReLU stages (64, 192, 384, 256, 256 channels) of the
input scaled to [-1, 1] and normalised by LPIPS's fixed shift (-0.030, -0.088, -0.188) and scale
(0.458, 0.448, 0.450), |.| the norm over channels at each pixel and w_l the learned non-negative
per-channel weights. The weights folder holds

* ``alexnet.pth``: torchvision's ImageNet AlexNet state dict (``features.*`` keys are read);
* ``alex.pth``: LPIPS v0.1's linear layers (``lin0.model.1.weight`` ... ``lin4.model.1.weight``,
  each 1 x C x 1 x 1), as the ``lpips`` package ships them.
"""
import os

import numpy as np

CHANNELS = (64, 192, 384, 256, 256)
SHIFT = (-0.030, -0.088, -0.188)
SCALE = (0.458, 0.448, 0.450)


def _alexnet_features(torch):
    nn = torch.nn
    return nn.Sequential(
        nn.Conv2d(3, 64, 11, 4, 2), nn.ReLU(), nn.MaxPool2d(3, 2),
        nn.Conv2d(64, 192, 5, padding=2), nn.ReLU(), nn.MaxPool2d(3, 2),
        nn.Conv2d(192, 384, 3, padding=1), nn.ReLU(),
        nn.Conv2d(384, 256, 3, padding=1), nn.ReLU(),
        nn.Conv2d(256, 256, 3, padding=1), nn.ReLU())


RELU_INDICES = (1, 4, 7, 9, 11)  # outputs taken after these layers of the feature stack


def _load(torch, path):
    if not os.path.isfile(path):
        raise ValueError(f"{path}: LPIPS weight file is missing (see mi_voldis/lpips.py for the files needed)")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # torch raises many types for foreign files
        raise ValueError(f"{path}: not a PyTorch state dict ({type(e).__name__}: {e})") from None


def load_lpips(folder):
    """A function ``lpips(a, b)`` of two (H, W, 3) images in [0, 1] (display-encoded), from ``folder``."""
    try:
        import torch
    except ImportError:
        raise ValueError("LPIPS needs PyTorch: pip install .[clip] (or .[bench])") from None
    features = _alexnet_features(torch)
    state = _load(torch, os.path.join(folder, "alexnet.pth"))
    try:
        features.load_state_dict({k[len("features."):]: v for k, v in state.items() if k.startswith("features.")})
    except RuntimeError as e:
        raise ValueError(f"{os.path.join(folder, 'alexnet.pth')}: not AlexNet's features ({e})") from None
    lin = _load(torch, os.path.join(folder, "alex.pth"))
    weights = []
    for k, c in enumerate(CHANNELS):
        w = lin.get(f"lin{k}.model.1.weight")
        if w is None or tuple(w.shape) != (1, c, 1, 1):
            raise ValueError(f"{os.path.join(folder, 'alex.pth')}: lin{k}.model.1.weight must be 1 x {c} x 1 x 1")
        weights.append(w.float())
    features.eval()
    shift = torch.tensor(SHIFT).view(1, 3, 1, 1)
    scale = torch.tensor(SCALE).view(1, 3, 1, 1)

    def activations(img):
        x = torch.from_numpy(np.ascontiguousarray(img, np.float32)).permute(2, 0, 1)[None] * 2 - 1
        x = (x - shift) / scale
        out = []
        for i, layer in enumerate(features):
            x = layer(x)
            if i in RELU_INDICES:
                out.append(x / (torch.sqrt((x * x).sum(dim=1, keepdim=True)) + 1e-10))
        return out

    def lpips(a, b):
        with torch.no_grad():
            fa, fb = activations(a), activations(b)
            return float(sum(((w * (x - y) ** 2).sum(dim=1)).mean() for w, x, y in zip(weights, fa, fb)))
    return lpips
