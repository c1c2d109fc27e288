"""Transform: move the foreground (scale / rotate / translate about its centre or a pivot); the
foreground is then evaluated at T^-1 p and recombined with each composition rule.

With ``moved_path`` ground truth (bundled scenes, same transform as ``moved_transform``), the PSNR of
every rule against it goes in one table.
"""
import mitsuba as mi
import numpy as np

from ..metrics import psnr, ssim
from ..render.mixing import RULES
from ..render.views import render_camera
from ..transforms import compose


def parse_rotate(text):
    """'y:30' -> ('y', 30.0); 'x,y,z:deg' with a vector axis also works."""
    if text is None:
        return None
    try:
        axis, deg = text.split(":")
        axis = axis.strip().lower()
        if axis not in ("x", "y", "z"):
            axis = tuple(float(v) for v in axis.split(","))
        return axis, float(deg)
    except ValueError:
        raise ValueError(f"--rotate expects AXIS:DEG (e.g. y:30), got '{text}'") from None


def parse_vector(text, name):
    if text is None:
        return None
    try:
        values = tuple(float(v) for v in text.split(","))
        assert len(values) == 3
        return values
    except (ValueError, AssertionError):
        raise ValueError(f"--{name} expects X,Y,Z, got '{text}'") from None


def matrix_from_options(run, options):
    """World-space transform of the foreground from the task options (or the dataset's own
    ``moved_transform`` with ``use_dataset_transform``)."""
    if options.get("use_dataset_transform"):
        if run.dataset.moved_transform is None:
            raise ValueError("the dataset has no moved_transform")
        return np.asarray(run.dataset.moved_transform, np.float64)
    pivot = parse_vector(options.get("pivot"), "pivot")
    pivot = run.foreground_centre_world() if pivot is None else np.asarray(pivot)
    return compose(float(options.get("scale") or 1.0), parse_rotate(options.get("rotate")),
                   parse_vector(options.get("translate"), "translate") or (0.0, 0.0, 0.0), pivot)


def run(run, output, options):
    ds = run.dataset
    matrix = matrix_from_options(run, options)
    rule = options.get("composition") or "paper"
    if rule not in RULES:
        raise ValueError(f"--composition must be one of {', '.join(RULES)}")
    to_world = mi.ScalarTransform4f(matrix.astype(np.float32))
    edited = run.integrator(composition=rule, fg_to_world=to_world)
    output.write_views(edited)
    output.write_scene({"full": run.fields["full"], "bg": run.fields["bg"]}, {"composition": rule},
                       {"fg_to_world": matrix})
    table = {}
    has_gt = ds.moved_transform is not None and np.allclose(matrix, ds.moved_transform, atol=1e-4)
    views = [v for v in ds.test if np.isfinite(ds.moved[v]).all()] if has_gt and ds.moved is not None else []
    for name in RULES:
        integ = edited if name == rule else run.integrator(composition=name, fg_to_world=to_world)
        scores = []
        for v in views:
            image = np.clip(render_camera(integ, ds.cameras[v], ("composite",))["composite"][0], 0, 1)
            scores.append((psnr(image, ds.moved[v]), ssim(image, ds.moved[v])))
        table[name] = {"psnr": float(np.mean([s[0] for s in scores])) if scores else None,
                       "ssim": float(np.mean([s[1] for s in scores])) if scores else None}
    return output.finish({"task": "transform", "matrix": matrix.tolist(), "composition": rule,
                          "ground_truth": bool(views), "rules_vs_ground_truth": table})
