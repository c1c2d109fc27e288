"""LPIPS from local weight files: the metric's properties with weights the test makes, and clear errors."""
import os

import numpy as np
import pytest

torch = pytest.importorskip("torch", reason="LPIPS needs PyTorch (the clip or bench extra)")

from mi_voldis.lpips import CHANNELS, _alexnet_features, load_lpips  # noqa: E402


def weights(folder, seed=0):
    torch.manual_seed(seed)
    net = _alexnet_features(torch)
    torch.save({f"features.{k}": v for k, v in net.state_dict().items()}, os.path.join(folder, "alexnet.pth"))
    torch.save({f"lin{k}.model.1.weight": torch.rand(1, c, 1, 1) for k, c in enumerate(CHANNELS)},
               os.path.join(folder, "alex.pth"))


def test_lpips_is_a_distance_on_images(tmp_path):
    weights(str(tmp_path))
    lpips = load_lpips(str(tmp_path))
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 1, (64, 64, 3)).astype(np.float32)
    noise = rng.normal(0, 1, x.shape).astype(np.float32)
    y = np.clip(x + 0.2 * noise, 0, 1)
    assert lpips(x, x) == 0.0
    assert lpips(x, y) == pytest.approx(lpips(y, x), rel=1e-5) and lpips(x, y) > 0
    assert lpips(x, np.clip(x + 0.05 * noise, 0, 1)) < lpips(x, y)


def test_lpips_weight_errors(tmp_path):
    with pytest.raises(ValueError, match="alexnet.pth: LPIPS weight file is missing"):
        load_lpips(str(tmp_path))
    weights(str(tmp_path))
    torch.save({"lin0.model.1.weight": torch.rand(1, 3, 1, 1)}, os.path.join(tmp_path, "alex.pth"))
    with pytest.raises(ValueError, match="lin0.model.1.weight must be 1 x 64 x 1 x 1"):
        load_lpips(str(tmp_path))
