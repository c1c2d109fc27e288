"""Transform: move the foreground (scale / rotate / translate about its centre or a pivot); the
foreground is then evaluated at T^-1 p and recombined with each composition rule.

With ``moved_path`` ground truth (bundled scenes, same transform as ``moved_transform``), the PSNR of
every rule against it goes in one table.
"""
import numpy as np

from ..metrics import psnr, ssim
from ..render.mixing import RULES
from ..render.views import render_camera
from ..transforms import compose, to_scalar_transform
from .settings import parse_rotation


def matrix_from_settings(run, s):
    """World-space transform of the foreground from the task settings (or the dataset's own
    ``moved_transform`` with ``use_dataset_transform``)."""
    if s.use_dataset_transform:
        if run.dataset.moved_transform is None:
            raise ValueError(f"{run.dataset.root}: the dataset has no moved_transform")
        return np.asarray(run.dataset.moved_transform, np.float64)
    if s.matrix is not None:
        return np.asarray(s.matrix, np.float64)
    pivot = run.foreground_centre_world() if s.pivot is None else np.asarray(s.pivot, np.float64)
    return compose(s.scale, parse_rotation(s.rotate) if s.rotate else None, s.translate, pivot)


def run(run, output, progress=True):
    ds, s = run.dataset, output.settings
    matrix = matrix_from_settings(run, s)
    to_world = to_scalar_transform(matrix)
    edited = run.integrator(composition=s.composition, fg_to_world=to_world)
    output.write_views(edited)
    output.write_scene({"full": run.fields["full"], "bg": run.fields["bg"]}, composition=s.composition,
                       fg_to_world=to_world)
    table = {}
    has_gt = ds.moved_transform is not None and np.allclose(matrix, ds.moved_transform, atol=1e-4)
    views = [v for v in ds.test if np.isfinite(ds.moved[v]).all()] if has_gt and ds.moved is not None else []
    for name in RULES:
        integ = edited if name == s.composition else run.integrator(composition=name, fg_to_world=to_world)
        scores = []
        for v in views:
            image = np.clip(render_camera(integ, ds.cameras[v], ("composite",))["composite"][0], 0, 1)
            scores.append((psnr(image, ds.moved[v]), ssim(image, ds.moved[v])))
        table[name] = {"psnr": float(np.mean([x[0] for x in scores])) if scores else None,
                       "ssim": float(np.mean([x[1] for x in scores])) if scores else None}
    output.finish({"task": "transform", "matrix": matrix.tolist(), "composition": s.composition,
                   "ground_truth": bool(views), "rules_vs_ground_truth": table})
