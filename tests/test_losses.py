"""The paper's losses (mi_voldis.losses): values on hand-made batches, what they leave out, where their
gradients go."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.losses import background_loss, camouflage_loss, full_loss, nonneg_loss


def colours(values):
    values = np.asarray(values, np.float32)
    return mi.Color3f(values[:, 0], values[:, 1], values[:, 2])


def test_full_loss_is_the_mean_squared_error_per_channel():
    pred = colours([[0.5, 0.5, 0.5], [1.0, 0.0, 0.0]])
    target = colours([[0.5, 0.5, 0.2], [0.0, 0.0, 0.0]])
    assert float(full_loss(pred, target)[0]) == pytest.approx((0.3 ** 2 + 1.0) / 6)


def test_background_loss_ignores_masked_rays_and_their_gradients():
    pred = colours([[0.2, 0.2, 0.2], [0.9, 0.1, 0.4], [0.0, 1.0, 0.0]])
    target = colours([[0.2, 0.2, 0.5], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    mask = mi.Float(0.0, 1.0, 0.0)  # the middle ray sees the object
    dr.enable_grad(pred)
    loss = background_loss(pred, target, mask)
    assert float(loss[0]) == pytest.approx(0.3 ** 2 / 6)  # mean over the two unmasked rays, 3 channels
    dr.backward(loss)
    grad = np.array(dr.grad(pred))
    assert np.all(grad[:, 1] == 0) and grad[2, 0] == pytest.approx(2 * (0.2 - 0.5) / 6)  # (channel, ray)
    # every ray masked: no division by zero, no loss
    assert float(background_loss(pred, target, mi.Float(1.0, 1.0, 1.0))[0]) == 0.0


def test_edit_losses_hold_their_references_fixed():
    """camouflage and non-negative losses move the edit towards the background render, never the
    background render towards the edit."""
    comp, bg, full, res = (colours(np.full((2, 3), v)) for v in (0.8, 0.3, 0.6, 0.1))
    dr.enable_grad(comp, bg, res)
    loss = camouflage_loss(comp, bg)
    assert float(loss[0]) == pytest.approx(0.25)
    dr.backward(loss)
    assert np.all(np.array(dr.grad(bg)) == 0) and np.all(np.array(dr.grad(comp)) > 0)
    loss = nonneg_loss(full, res, bg)
    assert float(loss[0]) == pytest.approx(0.16)
    dr.backward(loss)
    assert np.all(np.array(dr.grad(res)) > 0) and np.all(np.array(dr.grad(bg)) == 0)
