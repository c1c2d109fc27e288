"""What the scripts of this folder share: a fitted run and the held-out views they render.

``fitted_run(argv)``: argv = RUN [--views N] [rest...] -> (run, dataset, views, grid side, rest): up to N
held-out views spread evenly over them (all without --views). Also selects the llvm_ad_rgb variant."""
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

from mi_voldis.data.types import spread  # noqa: E402
from mi_voldis.tasks.base import FittedRun  # noqa: E402


def fitted_run(argv):
    args = list(argv)
    nviews = None
    if "--views" in args:
        i = args.index("--views")
        nviews = int(args[i + 1])
        del args[i:i + 2]
    run = FittedRun(args[0])
    ds = run.dataset
    views = list(ds.test)
    if nviews and len(views) > nviews:
        views = [views[i] for i in spread(len(views), nviews)]
    return run, ds, views, max(run.fields["full"].shape), args[1:]
