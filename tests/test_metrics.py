"""Image metrics with analytic answers."""
import numpy as np

from mi_voldis.metrics import diagonal_pixels, object_residue, score_dilation


def test_object_residue_counts_pixels_still_closer_to_the_object():
    rng = np.random.default_rng(0)
    photo = np.zeros((8, 8, 3)) + [0.9, 0.1, 0.1]   # a red object
    background = rng.uniform(0.0, 0.3, (8, 8, 3))  # dark true background
    mask = np.zeros((8, 8), bool)
    mask[2:6, 2:6] = True
    assert object_residue(photo, photo, background, mask) == 1.0          # nothing removed
    assert object_residue(background, photo, background, mask) == 0.0     # perfectly removed
    half = background.copy()
    half[2:4] = photo[2:4]                                                # the object's top half is left
    assert object_residue(half, photo, background, mask) == 0.5
    tinted = 0.7 * photo + 0.3 * background                               # a ghost: mostly object colour
    assert object_residue(tinted, photo, background, mask) == 1.0
    same = photo.copy()                                                   # photo = background: says nothing
    assert np.isnan(object_residue(background, same, same, mask))


def test_a_fraction_of_the_diagonal_is_whole_pixels_rounded_up_whichever_way_the_size_is_given():
    assert diagonal_pixels(0.03, (160, 120)) == 6 == diagonal_pixels(0.03, (120, 160))  # 0.03 * 200
    assert diagonal_pixels(0.031, (160, 120)) == 7  # 6.2 rounds up: a mask is never grown by less
    assert diagonal_pixels(0.01, (4, 3)) == 1 and diagonal_pixels(0.0, (4, 3)) == 0
    assert score_dilation((504, 378)) == diagonal_pixels(0.03, (504, 378)) == 19  # 0.03 * 630 = 18.9
