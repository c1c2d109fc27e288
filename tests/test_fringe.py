"""The object's dark fringe beside its masks (mi_voldis.fit.fringe): its contact shadow and dark soft edge,
not a dark texture and not an occluder."""
from types import SimpleNamespace

import numpy as np

from mi_voldis.fit.fringe import EPS, dark_fringe, find_fringe
from mi_voldis.inpaint2d import inpainter
from mi_voldis.metrics import dilate

H, W = 60, 80
MASK = np.zeros((H, W), bool)
MASK[20:40, 30:50] = True


def floor(value=0.5):
    image = np.full((H, W, 3), value, np.float32)
    image[MASK] = [0.9, 0.1, 0.8]  # a magenta object
    return image


def test_the_contact_shadow_below_the_object_is_found_and_its_coloured_edge_is_not():
    """A grey floor; two rows below the object 50% darker (its contact shadow); a row above it half the
    object's magenta (its soft edge: brighter in red and blue, darker in green). Exactly the shadow's
    pixels are found."""
    image = floor()
    image[40:42, 30:50] = 0.25
    image[19, 30:50] = 0.5 * (np.array([0.9, 0.1, 0.8]) + 0.5)
    found = dark_fringe(image, MASK, 5, 0.1)
    expected = np.zeros_like(MASK)
    expected[40:42, 30:50] = True
    np.testing.assert_array_equal(found, expected)
    # a step smaller than the contrast is no fringe; one pixel beyond the band is not searched
    assert not dark_fringe(np.where(expected[..., None], 0.48, image), MASK, 5, 0.1).any()
    assert not dark_fringe(image, MASK & ~(dilate(~MASK, 3)), 1, 0.1).any()


def test_a_dark_texture_beside_the_object_is_no_fringe():
    """Grey stripes (0.2 and 0.6, four pixels each) cross the floor around the object. The dark stripes
    beside it are darker than the smooth 2D fill in every channel, so the first condition alone would take
    them; but they are no darker than the dark stripes beyond the band: nothing is found. A contact shadow
    on the same floor (two rows at 0.3 of the floor: darker than its darkest stripe) is."""
    image = floor()
    stripes = np.where((np.arange(W) // 4) % 2 == 0, 0.2, 0.6).astype(np.float32)
    image[~MASK] = np.broadcast_to(stripes[None, :, None], (H, W, 3))[~MASK]
    band = dilate(MASK, 5) & ~MASK
    filled = inpainter("telea")(image, dilate(MASK, 5))
    darker = np.all(np.log(image + EPS) < np.log(filled + EPS) - 0.1, axis=-1) & band
    assert darker.sum() > 30  # the fill's test alone
    assert not dark_fringe(image, MASK, 5, 0.1).any()
    shadowed = image.copy()
    shadowed[40:42, 30:50] *= 0.3
    found = dark_fringe(shadowed, MASK, 5, 0.1)
    assert found[40:42, 30:50].all() and not found[:40].any() and not found[42:].any()


def test_a_dark_occluder_in_front_of_the_object_is_no_fringe():
    """A dark pole stands beside the object, nearer the camera (depth 2 against the object's 5 and the
    floor's 6): without depths it is taken for the fringe, with them it is left to the scene."""
    image = floor()
    image[15:45, 50:53] = 0.1
    depth = np.full((H, W), 6.0, np.float32)
    depth[MASK] = 5.0
    depth[15:45, 50:53] = 2.0
    assert dark_fringe(image, MASK, 5, 0.1)[15:45, 50:53].sum() > 20
    assert not dark_fringe(image, MASK, 5, 0.1, depth=depth).any()


def test_the_fringe_of_a_dataset_is_searched_on_its_masked_training_views_alone():
    """Every view holds the same contact shadow; views 1 and 3 are masked training views, view 2 is held
    out, view 0 has no mask: the fringe is found on views 1 and 3 only, its band from the diagonal (0.05 of
    100 pixels: 5). A dataset without a fringe gives None."""
    image = floor()
    image[40:42, 30:50] = 0.25
    masks = np.array([np.zeros_like(MASK), MASK, MASK, MASK])
    ds = SimpleNamespace(size=(W, H), images=np.array([image] * 4), masks=masks, masked_train=np.array([1, 3]))
    found = find_fringe(ds, 0.05, 0.1)
    assert found.shape == masks.shape
    assert found[1].sum() == found[3].sum() == 40 and not found[0].any() and not found[2].any()
    ds.images = np.array([floor()] * 4)
    assert find_fringe(ds, 0.05, 0.1) is None
