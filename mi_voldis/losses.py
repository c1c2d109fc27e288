"""The losses of the paper, one function each (Benaim et al. 2022), and the distortion regulariser the
fits add to them. Fitting and every task call these; batching, statistics and PSNR logging stay with
their callers.

All take Dr.Jit values of one batch of rays (or a rendered image) and return a one-element ``mi.Float``
that ``dr.backward`` differentiates. Colours are premultiplied and display-encoded, as rendered; a
``target`` or reference that should not receive gradients is detached here. The sums of the paper are
written as means over the batch and the three colour channels, so that a loss is the mean squared
error per channel (its PSNR is -10 log10 of it) and does not scale with the batch.
"""
import drjit as dr
import mitsuba as mi


def full_loss(pred, target):
    """L_full = sum_i ||x_i - x^_i||^2 over all pixels i (paper Sec. 3.1): the full-scene field ``pred``
    against the photographs ``target`` (Color3f per ray)."""
    return dr.mean(dr.squared_norm(pred - target)) / 3.0


def background_loss(pred, target, mask):
    """L_bg = sum_i ||(1 - m_i)(x_i - x^_i)||^2 (paper Sec. 3.1): the background field ``pred`` against
    ``target`` only where the object mask ``mask`` (Float per ray, 1 on the object) is 0; the mean is
    over the unmasked rays."""
    keep = 1.0 - mask
    return dr.sum(keep * dr.squared_norm(pred - target)) / (3.0 * dr.maximum(dr.sum(keep), 1.0))


def camouflage_loss(composite, background):
    """L_cam = sum_i ||x^c_i - x^bg_i||^2 (paper Sec. 3.2, camouflage): the composite with the edited
    foreground colour against the background field's render of the same rays (held fixed)."""
    return dr.mean(dr.squared_norm(composite - dr.detach(background))) / 3.0


def nonneg_loss(full, residual, background):
    """L_res = sum_i ||x^full_i + x^res_i - x^bg_i||^2 (paper Sec. 3.2, non-negative inpainting): light
    added by the residual field (x^res >= 0 by construction) should turn the full scene into the
    background (held fixed)."""
    return dr.mean(dr.squared_norm(full + residual - dr.detach(background))) / 3.0


def semantic_loss(guide, edited, background, full, mask, bg_weight=0.5, l2_weight=10.0):
    """The text-guided loss (paper Sec. 3.3, semantic manipulation) of an edited view, sum of three terms:

        L_text = 1 - cos(E_I(M * I + (1 - M) * I_bg), E_T(t))          (similarity to the text)
        L_bg   = 1 - cos(E_I(I), E_I(I_bg))                              (similarity to the background)
        L_out  = mean ||(1 - M) (I - I_full)||^2                         (unchanged outside the mask)

        L = L_text + bg_weight * L_bg + l2_weight * L_out

    ``guide``: a :class:`mi_voldis.tasks.clip.ClipGuide` (CLIP's encoders E_I, E_T and the prompt t);
    ``edited`` I, ``background`` I_bg, ``full`` I_full: ``mi.TensorXf`` (H, W, 3); ``mask`` M:
    ``mi.TensorXf`` (H, W, 1), 1 on the object. Gradients reach ``edited`` only."""
    background, full, mask = dr.detach(background), dr.detach(full), dr.detach(mask)
    cos_text, cos_bg = guide.cosines(mask * edited + (1.0 - mask) * background, edited, background)
    outside = dr.mean(dr.square((1.0 - mask) * (edited - full)).array)
    return (1.0 - cos_text) + bg_weight * (1.0 - cos_bg) + l2_weight * mi.Float(outside)


def distortion_loss(per_ray, mask, object_gain=1.0):
    """Mip-NeRF 360's distortion loss L_dist = sum_ij w_i w_j |s_i - s_j| + 1/3 sum_i w_i^2 delta_i per ray
    (``per_ray``, from the march), averaged over the batch with the rays in the object mask ``mask``
    weighted by ``object_gain``: mean_r (1 + (object_gain - 1) m_r) L_dist,r. The object is a surface, so
    its rays should hold one peak: haze the full field leaves in front of it would otherwise stay in the
    background field and go missing from the foreground (w_fg = w_full - w_bg)."""
    return dr.mean((1.0 + (object_gain - 1.0) * mask) * per_ray)


def depth_smoothness_loss(depth, alpha, color, pairs, edge=10.0):
    """Edge-aware depth smoothness on neighbouring rays: RegNeRF's depth smoothness (Niemeyer et al. 2022, on
    patches of unseen views there), here on tiles of the training photos' own pixels, weighted down
    across the photo's colour edges, as self-supervised monocular depth does:

        L = mean_(a,b) A_a A_b exp(-edge |c_a - c_b|_1 / 3) ((D_a - D_b) / (D_a + D_b))^2

    over the ray pairs ``pairs`` (UInt32 a, UInt32 b: adjacent pixels, :func:`mi_voldis.raybank.tile_pairs`),
    ``depth`` D the expected depth per ray (the fit passes it through
    :meth:`mi_voldis.space.SceneSpace.scene_depth`: world units, or scene units in a contracted space,
    where a far wall's weakly determined depth of 10 or 30 units becomes nearly one value instead of a
    noise that a sheet near the camera would smooth away), ``alpha`` A its opacity (clamped to [0, 1]: a
    ray that ends nowhere has no depth to smooth) and ``color`` c the photo's; only D carries gradients.
    The step is relative, so a floor receding from the camera costs little per pixel while a sheet of fog
    floating before the one camera that sees that floor pays at its border, unless the photo shows an
    edge there."""
    a, b = pairs
    da, db = dr.gather(mi.Float, depth, a), dr.gather(mi.Float, depth, b)
    color, opacity = dr.detach(color), dr.clip(dr.detach(alpha), 0.0, 1.0)
    step = dr.abs(dr.gather(mi.Color3f, color, a) - dr.gather(mi.Color3f, color, b))
    weight = (dr.gather(mi.Float, opacity, a) * dr.gather(mi.Float, opacity, b)
              * dr.exp(-edge * (step.x + step.y + step.z) / 3.0))
    return dr.mean(weight * dr.square((da - db) / dr.maximum(da + db, 1e-6)))
