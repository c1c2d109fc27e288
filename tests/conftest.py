import os

import pytest

import mi_voldis  # noqa: F401  (selects the Mitsuba variant and registers the plugins before any test)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TINY_FIT = ["steps_full=60", "steps_bg=12", "lr_warmup=2", "lr_density=0.3", "resolution_schedule=[[0,12],[20,20]]",
            "occupancy_at_step=20",
            "batch_rays=1024", "sh_degree=\"auto\"", "sh_trial_steps=4", "checkpoint_every=10", "eval_every=20",
            "preview_views=1"]


def pytest_report_header(config):
    """The variant the suite runs on (``$MI_VOLDIS_VARIANT``, else llvm_ad_rgb) heads pytest's report."""
    import mitsuba as mi
    return f"mi_voldis variant: {mi.variant()}"


@pytest.fixture(scope="session")
def tiny_dataset(tmp_path_factory):
    """The bundled tabletop scene rendered small (9 views, 32 x 24, 4 spp)."""
    from mi_voldis.synth.make import make_dataset
    out = str(tmp_path_factory.mktemp("data") / "tabletop")
    return make_dataset(os.path.join(ROOT, "scenes", "tabletop.xml"), out, views=9, resolution=(32, 24), spp=4,
                        progress=False)


@pytest.fixture(scope="session")
def tiny_run(tiny_dataset, tmp_path_factory):
    """A run fitted on it in a few dozen steps (every phase, tiny grids)."""
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.run import run_fit
    out = str(tmp_path_factory.mktemp("runs") / "tabletop")
    run_fit(tiny_dataset, out, FitConfig.from_sources(None, TINY_FIT), progress=False)
    return out
