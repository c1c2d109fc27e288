"""Object masks for every view from two views' masks or a world box, on an analytic scene (a red sphere
on a textured floor, fitted field with a faint haze around it): against the exact visible coverage."""
import json
import os

import numpy as np
import pytest
from test_background import FLOOR_Y, synthetic_object_scene

from mi_voldis.masks3d import box_masks, mask_names, surface_masks, surfaces, view_masks
from mi_voldis.metrics import dilate, iou
from mi_voldis.scene import build_integrator, integrator_properties
from mi_voldis.space import SceneSpace

VOXEL = 2.0 / 39


def scene():
    ds, _, full, *_ = synthetic_object_scene(views=10)
    props = integrator_properties(SceneSpace("world"), samples=256, step_size=0.5 * VOXEL)
    integ = build_integrator({"full": full.plugin(), "bg": full.plugin()}, props)
    return ds, surfaces(integ, ds.cameras)


def test_masks_from_two_views_and_from_a_box():
    ds, surf = scene()
    given = {1: ds.masks[1], 4: ds.masks[4]}  # 108 degrees apart on the orbit
    from_views = view_masks(ds.cameras, surf, given, images=ds.images)
    ious = np.array([iou(p, t) for p, t in zip(from_views, ds.masks)])
    assert ious.mean() >= 0.9 and ious.min() >= 0.85, ious
    # 3D alone takes the floor the sphere hides in both given views: colour settles it
    geometry_only = view_masks(ds.cameras, surf, given)
    assert np.mean([iou(p, t) for p, t in zip(geometry_only, ds.masks)]) < ious.mean() - 0.1
    centre, radius = np.array([0.0, FLOOR_Y + 0.3, 0.0]), 0.3
    lo, hi = centre - 1.1 * radius, centre + 1.1 * radius
    lo[1] = FLOOR_Y + 4 * VOXEL  # above the floor it stands on (a slab 1.5 voxels thick, soft by ~2 more)
    boxed = box_masks(ds.cameras, surf, lo, hi)
    ious = np.array([iou(p, t) for p, t in zip(boxed, ds.masks)])
    assert ious.mean() >= 0.9 and ious.min() >= 0.8, ious


def test_the_shadow_from_two_views_is_found_in_every_view():
    """Effect masks (the sphere's shadow on the floor) of two views lifted through the surface, a union of
    what either sees: on every other view that shows the shadow, the lifted pixels lie on it (within a
    pixel: its rim is soft at 40x30) and cover most of it."""
    ds, _, full, *_ = synthetic_object_scene(views=10, shadow=True)
    props = integrator_properties(SceneSpace("world"), samples=256, step_size=0.5 * VOXEL)
    surf = surfaces(build_integrator({"full": full.plugin(), "bg": full.plugin()}, props), ds.cameras)
    given = {1: ds.effects[1], 4: ds.effects[4]}
    lifted = surface_masks(ds.cameras, surf, given)
    shown = [v for v in range(len(ds.images)) if v not in given and ds.effects[v].sum() >= 40]
    assert len(shown) >= 5
    on = [(lifted[v] & dilate(ds.effects[v], 1)).sum() / lifted[v].sum() for v in shown]
    ious = [iou(lifted[v], ds.effects[v]) for v in shown]
    assert min(on) >= 0.8 and np.mean(ious) >= 0.55 and min(ious) >= 0.4, (on, ious)
    np.testing.assert_array_equal(lifted[1], ds.effects[1])


def test_make_masks_script_writes_masks_train_reads(tiny_dataset, tiny_run, tmp_path, capsys):
    """The script on a fitted run: masks for every view, the given views' own masks kept, and bad input
    (a box no view has in its frame among it) as one line naming the problem."""
    from test_bad_inputs import _boundary, script

    from mi_voldis.data import load_dataset
    from mi_voldis.data.images import read_mask
    ds = load_dataset(tiny_dataset)
    given = [f"{ds.names[v]}={os.path.join(tiny_dataset, 'masks', ds.names[v])}" for v in (1, 4)]
    out = str(tmp_path / "masks")
    main = script("make_masks").main
    assert _boundary.run(main, [tiny_dataset, "--out", out, "--run", tiny_run, "--quiet", "--from-views", *given]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["views"] == len(ds.names) and 0 <= summary["iou_vs_coverage"] <= 1
    written = [read_mask(os.path.join(out, n), "white") for n in ds.names]
    np.testing.assert_array_equal(written[1], ds.masks[1])
    assert sum(m.any() for m in written) >= len(ds.names) - 1
    far = str(tmp_path / "far")  # a box no view has in its frame: refused before anything is written
    assert _boundary.run(main, [tiny_dataset, "--out", far, "--run", tiny_run, "--quiet",
                                "--box", "50,50,50,51,51,51"]) == 1
    assert "--box 50,50,50,51,51,51: no view has any of the box in its frame" in capsys.readouterr().err
    assert not os.path.exists(far)
    assert _boundary.run(main, [tiny_dataset, "--out", far, "--run", tiny_run, "--box", "1,1,1,0,0,0"]) == 1
    assert "--box expects x0,y0,z0,x1,y1,z1" in capsys.readouterr().err
    assert _boundary.run(main, [tiny_dataset, "--out", far, "--run", tiny_run, "--from-views",
                                f"nope={given[0].split('=')[1]}"]) == 1
    assert "no view named 'nope'" in capsys.readouterr().err
    shade = str(tmp_path / "effects")  # --effects: the given masks as a patch of the surfaces
    assert _boundary.run(main, [tiny_dataset, "--out", shade, "--run", tiny_run, "--quiet", "--effects",
                                "--from-views", *given]) == 0
    assert "iou_vs_coverage" not in json.loads(capsys.readouterr().out)
    np.testing.assert_array_equal(read_mask(os.path.join(shade, ds.names[4]), "white"), ds.masks[4])
    with pytest.raises(SystemExit):
        main([tiny_dataset, "--out", shade, "--effects", "--box", "0,0,0,1,1,1"])
    assert "--effects goes with --from-views" in capsys.readouterr().err


def test_mask_files_are_named_by_image_stem_and_two_images_of_one_stem_are_refused():
    """The loaders match masks to images by stem: each view's mask is <stem>.png, from subfolders too, and
    a.png beside a.jpg (one mask file for two views) is refused up front, naming both."""
    assert mask_names(["r_000.png", "cam1/0001.jpg"], "data") == ["r_000.png", "0001.png"]
    with pytest.raises(ValueError, match="data: images a.png and b/a.jpg share the stem 'a', so their masks would "
                                         "be one file \\(a.png\\); rename one of them"):
        mask_names(["a.png", "b/a.jpg"], "data")
