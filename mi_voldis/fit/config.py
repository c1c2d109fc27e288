"""Every setting of fitting, named, commented and validated in one place (DVGO / Plenoxels style).

Override from the command line with ``--set name=value`` (repeatable) or a JSON file with
``--config FILE`` (a finished run's RUN/config.json is such a file); ``python scripts/train.py --help``
lists them all. The run writes the effective settings to RUN/config.json. Measurements behind the
defaults are in reports/notes.md.
"""
from dataclasses import dataclass

from ..inpaint2d import INPAINTERS, name_problem
from ..settings import Settings, setting


def _schedule_error(schedule):
    """Why ``schedule`` is not null or a list of [step, vertices] pairs starting at step 0, steps increasing."""
    what = "null or a non-empty list of [step, vertices] pairs, the first at step 0, steps increasing, vertices >= 2"
    if schedule is None:
        return None
    if not schedule or not all(isinstance(p, list) and len(p) == 2 and all(isinstance(v, int) and
                                                                              not isinstance(v, bool) for v in p)
                               for p in schedule):
        return what
    steps = [p[0] for p in schedule]
    if steps[0] != 0 or any(b <= a for a, b in zip(steps, steps[1:])) or min(p[1] for p in schedule) < 2:
        return what
    return None


def _inpainter_error(value):
    if isinstance(value, str) and name_problem(value) is None:
        return None
    return f"one of auto, {', '.join(INPAINTERS)}, or several of them joined by '+' (e.g. \"lateral+auto\")"


def _minutes_error(value):
    if value is None or value == "auto" or (isinstance(value, (int, float)) and not isinstance(value, bool)
                                            and 0.05 <= value <= 1e4):
        return None
    return "'auto', null or a number of minutes (0.05 to 10000)"


def _auto_or(whole, low=None, above=None):
    """A check of 'auto' or a number (``whole``: a whole one) >= ``low`` / > ``above``."""
    kind = "a whole number" if whole else "a number"
    bound = f" >= {low}" if low is not None else f" > {above}" if above is not None else ""

    def error(value):
        number = isinstance(value, int if whole else (int, float)) and not isinstance(value, bool)
        if value == "auto" or (number and (low is None or value >= low) and (above is None or value > above)):
            return None
        return f"'auto' or {kind}{bound}"
    return error


def _null_or(check):
    """``check`` that also takes null."""
    def error(value):
        return None if value is None else (None if check(value) is None else f"null or {check(value)}")
    return error


def _fractions_error(value):
    if isinstance(value, list) and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value) \
            and all(0 < v < 1 for v in value) and all(a < b for a, b in zip(value, value[1:])):
        return None
    return "a list of increasing fractions in (0, 1)"


@dataclass
class FitConfig(Settings):
    # settings added since runs were first recorded, at the values those runs were fitted with (not a field:
    # no annotation): plans before host_ms had no host term; background refits before bg_lr_* / bg_tv_*
    # stepped with the then default rates and TV weights, and filled the hull isotropically; degree-1 colour
    # before sh_color was RGB; backgrounds before fringe_contrast kept the dark fringe; scenes before
    # scene_occupancy_voxels / scene_stop_transmittance / scene_strides were written with fitting's cells,
    # stop and steps; fits before strides marched every occupied cell at the fit's step; default plans before
    # sample_ns did not count their last stage; fits before average_window kept the last iterate; fits before
    # free_space left the masks' free space to the data
    ADDED = {"sh_color": "rgb", "host_ms": 0.0, "bg_lr_density": 0.1, "bg_lr_color": 0.05, "bg_tv_density": 1e-4,
             "bg_tv_color": 1e-5,
             "lr_views": 0.0, "lr_views_final": True, "lr_views_quantile": 1.0,
             "lr_views_growth": False, "contract_radius": 1.0, "checkpoint_minutes": 2.0, "hull_fill_vertical": 1.0,
             "sh_gate": False, "sh_view_resolution": None, "sh_view_from": 0.0, "fringe_contrast": 0.0,
             "scene_occupancy_voxels": 4, "scene_stop_transmittance": 1e-4, "scene_strides": False,
             "strides": "none", "sample_ns": None, "float_ns": 0.0, "average_window": 0.0, "free_space": False,
             "object_behind_fill": False}

    # ---- scene space
    space: str = setting("auto", "where the fields live: 'contract' (all of space, Mip-NeRF 360's contraction), "
                                 "'world' (the dataset's box), 'ndc' (forward-facing captures) or 'auto' "
                                 "(world where the dataset states a box or its RGBA views' alpha carves one, "
                                 "else contract; config.json records the space chosen as space_used)",
                         choices=("auto", "contract", "world", "ndc"))
    contract_shell: float = setting(1.0, "contracted space: the outer shell's share b of the scene cube "
                                         "[-(1 + b), 1 + b]^3 (1: Mip-NeRF 360)", above=0)
    contract_radius: float = setting(1.0, "contracted space of a 360-degree capture: the linear cube's half-size "
                                          "as a multiple of 1.1 x the farthest camera's distance from the look-at "
                                          "point (below 1: finer voxels where the cameras look, the cameras "
                                          "in the shell)", above=0)

    # ---- schedule: coarse to fine, as data (mi_voldis/fit/schedule.py derives what is left null / 'auto')
    minutes: float | str | None = setting("auto", "time budget of the fit: the number of steps is chosen to fill "
                                                  "it ('auto': 2.5 min per million training pixels, 1.5 to 10, "
                                                  "the 10 growing as the cube root of the pixels past 12 M, at "
                                                  "most 15 (on cuda 0.5 min, 1 to 5), costed at reference_msps, "
                                                  "and min_steps at least; a number: "
                                                  "minutes of this machine's wall clock; null: steps_full)",
                                        check=_minutes_error)
    reference_msps: float | str = setting("auto", "with minutes 'auto', the coarse stage's kernel speed the plan "
                                                  "assumes, in M samples/s ('auto': the backend's, mi_voldis.fit."
                                                  "schedule.BACKENDS: 18 on llvm, the project's 2-core machine; "
                                                  "1000 on cuda): the plan depends on the capture and the backend, "
                                                  "not on how fast or busy this machine is",
                                          check=_auto_or(False, above=0))
    host_ms: float | str = setting("auto", "milliseconds a training step costs whatever its size (tracing, launches, "
                                           "reading the loss back), added to its kernels' time in the plan ('auto': "
                                           "the backend's, 0 on llvm, 5 on cuda)", check=_auto_or(False, low=0))
    sample_ns: float | str | None = setting("auto", "with minutes 'auto', the nanoseconds a step of the last stage "
                                                     "costs per evaluated training sample, its steps counted from "
                                                     "the 100th on ('auto': the backend's, mi_voldis.fit.schedule."
                                                     "BACKENDS: 268.4 on llvm, 1.05 on cuda; null: the stage is not "
                                                     "counted, its steps stay as modelled from the coarse one)",
                                            check=_null_or(_auto_or(False, above=0)))
    float_ns: float | str = setting("auto", "with minutes 'auto', the nanoseconds a step of the last stage costs per "
                                             "stored float of the fields it steps ('auto': the backend's, 2.014 on "
                                             "llvm, 0 on cuda)", check=_auto_or(False, low=0))
    steps_full: int | None = setting(None, "steps of the full-scene phase (null: from minutes)", low=1)
    min_steps: int = setting(3000, "with minutes 'auto', the full-scene phase runs at least this many steps, "
                                   "overrunning the budget where it allows fewer (the resolution is chosen "
                                   "from the budget alone)", low=0)
    resolution: int | str = setting("auto", "final vertices along the scene box's longest side ('auto': a voxel "
                                            "about pixels_per_voxel pixels of the training views wide)",
                                    check=_auto_or(True, low=4))
    pixels_per_voxel: float = setting(1.0, "'auto' resolution: voxel width in training-view pixels", above=0)
    max_resolution: int = setting(1024, "cap on the final resolution (and the density scale's unit)", low=8)
    min_observations: float = setting(64.0, "with a time budget, the final resolution lets its stage end this "
                                            "many training rays in every cell where rays end (surfaces): a grid "
                                            "seen too few times is worse than a coarser one seen often",
                                      above=0)
    max_memory_gib: float | str = setting("auto", "with resolution 'auto', the fit's peak memory stays within this "
                                                  "many GiB ('auto': the backend's, 4 of RAM on llvm, 32 of the "
                                                  "GPU's on cuda): the plan estimates it from the surface cells, "
                                                  "each stage counts its carved vertices before allocating them and "
                                                  "stops short of the bound (mi_voldis.fit.schedule."
                                                  "affordable_vertices; metrics.json: schedule.plan.memory_caps)",
                                          check=_auto_or(False, above=0))
    coarse_resolution: int = setting(64, "resolution of the first stage", low=4)
    stages: int = setting(4, "coarse-to-fine stages, each doubling the resolution", low=1, high=8)
    stage_starts: list = setting([0.1, 0.2, 0.35], "where stages 2, 3, ... start, as fractions of steps_full",
                                 check=_fractions_error)
    calibration_steps: int = setting(200, "steps of the first stage timed to plan the rest", low=10)
    resolution_schedule: list | None = setting(None, "explicit [[step, vertices along the box's longest side], "
                                                     "...] (null: derived from the settings above)",
                                               check=_schedule_error)
    steps_bg: int = setting(150, "steps of the background refit (every bg_strategy but 'scratch')", low=0)
    # the refit has its own rates and TV weights: it starts from a fitted field and reshapes the hole only
    bg_lr_density: float = setting(0.1, "Adam learning rate of raw density in the background refit", above=0)
    bg_lr_color: float = setting(0.05, "Adam learning rate of raw colour in the background refit", above=0)
    bg_tv_density: float = setting(1e-4, "total variation of raw density in the background refit", low=0)
    bg_tv_color: float = setting(1e-5, "total variation of raw colour coefficients in the background refit", low=0)
    batch_rays: int | str = setting("auto", "random rays per step, drawn across all training views ('auto': the "
                                            "backend's, 8192 on llvm, 32768 on cuda)", check=_auto_or(True, low=1))
    batch_tile: int = setting(1, "> 1: rays in tile x tile pixel tiles (coherent: faster marches, worse "
                                 "fits per second)", low=1)
    step_voxels: float | str = setting("auto", "sample spacing along a ray, in voxels of the current grid ('auto': "
                                               "half a voxel, and a whole one after the coarse stage where the "
                                               "default plan's grid is bound by memory or pixels, not by the "
                                               "observations the budget buys; metrics.json: schedule.plan."
                                               "step_voxels)", check=_auto_or(False, above=0))
    max_samples: int = setting(512, "cap on samples per ray", low=1)

    # ---- optimiser: Adam on raw grid values, exponential decay to lr * lr_final_ratio
    # the full phase's rates and TV weights go together: twice the rates reach the surfaces in the steps a
    # time budget buys, ten times the TV keeps what few views see from turning into floaters at those rates
    # (chosen on the removal family's tuning half, held on its check half and the captures: reports/notes.md)
    lr_density: float = setting(0.2, "Adam learning rate of raw density in the full phase (grids want far larger "
                                     "rates than NeRF MLPs)", above=0)
    lr_color: float = setting(0.1, "Adam learning rate of raw colour in the full phase", above=0)
    lr_views: float = setting(0.0, "the full phase's learning rates per brick times min(1, n / n_ref)^lr_views, n "
                                   "the training views whose image holds the brick (DVGO's per-voxel rates: what "
                                   "few views see fits slower, floaters have less room; mi_voldis.fit.observed); "
                                   "0: the same rates everywhere", low=0)
    lr_views_quantile: float = setting(1.0, "with lr_views, n_ref is this quantile of the bricks' view counts (1: the "
                                            "largest; 0.5: the median, so only the bricks fewer views see than "
                                            "most step slower)", above=0, high=1)
    lr_views_growth: bool = setting(False, "with lr_views, the factor slows only the density's growth (the colour and "
                                           "the density's decrease step at the full rate everywhere): a surface few "
                                           "views see still takes its colour, a floater before it grows slower")
    lr_views_final: bool = setting(True, "with lr_views, the last stage (the final resolution) steps at the per-brick "
                                         "rates too (false: at the phase's rates everywhere, as DVGO's fine stage; "
                                         "the carving at each stage's start has removed the bricks that the lower "
                                         "rates kept floaters from forming in)")
    lr_final_ratio: float = setting(0.1, "learning rates decay exponentially to this fraction", above=0, high=1)
    average_window: float = setting(0.125, "the full phase's fields are the exponential moving average of the last "
                                           "stage's iterates over a window of this fraction of its steps (the noise "
                                           "of the last steps' random rays averaged out: mi_voldis.optim.average); "
                                           "0: the last iterate", low=0, high=1)
    adam_beta1: float = setting(0.9, "Adam's first-moment decay", low=0, high=0.999999)
    adam_beta2: float = setting(0.99, "Adam's second-moment decay", low=0, high=0.999999)
    lr_warmup: int = setting(50, "steps of linear learning-rate ramp after every (re)start of Adam", low=0)

    # ---- initialisation
    density_init_alpha: float = setting(1e-3, "initial opacity of one sample step (softplus-shifted, like DVGO)",
                                        above=0, high=0.5)
    sh_degree: int | str = setting(1, "colour: 0 (RGB), 1 (spherical harmonics: view-dependent colour), or "
                                      "'auto': degree 1 only if it pays on validation views", choices=("auto", 0, 1))
    sh_color: str = setting("grey", "view-dependent colour at degree 1: 'rgb' (a triple a harmonic) or 'grey' (one "
                                   "coefficient a harmonic added to R, G and B alike: a gloss that brightens or "
                                   "darkens with the view, at half a degree-1 vertex's memory)",
                            choices=("rgb", "grey"))
    sh_gain_db: float = setting(2.0, "'auto': validation PSNR that degree 1 must gain over degree 0 in the trial "
                                     "fits (mi_voldis.fit.sh_degree); lower (0.25) gives degree 1 to captures whose "
                                     "colour changes with the view such as garden, but also to removal-family "
                                     "scenes whose removal then loses (reports/notes.md)", low=0)
    sh_gate: bool = setting(True, "degree 1: view dependence in proportion to a voxel's opacity (radiance_field's "
                                  "sh_gate), so that faint density shows its mean colour from every side")
    sh_view_resolution: int | None = setting(64, "grey degree 1: the gloss coefficients on a dense lattice of this "
                                                 "many vertices along the box's longest side (radiance_field's "
                                                 "view), the bricks keeping degree 0's 4 floats a vertex, so the "
                                                 "memory plan affords degree 0's grid; null: at every brick vertex",
                                             low=2)
    sh_view_from: float = setting(0.5, "degree 1: view-dependent colour fitted only from this fraction of the full "
                                       "phase's planned steps on, the geometry first fitted with the mean colour "
                                       "(progressive view dependence, as 3D Gaussian splatting raises its degree; "
                                       "before it a view lattice is not read, and the plan costs only the steps "
                                       "after it at a lattice's price); 0: from the start", low=0, high=1)
    sh_trial_steps: int = setting(200, "'auto': steps of each degree's trial fit (density and colour, at the end of "
                                       "the coarse stage)", low=1)

    # ---- regularisers (weights on per-vertex means; gradients added directly to the grids)
    tv_density: float = setting(1e-3, "total variation of raw density in the full phase", low=0)
    tv_color: float = setting(1e-4, "total variation of raw colour coefficients in the full phase", low=0)
    tv_every: int = setting(4, "apply the TV gradient (scaled by this) every k steps: it costs a pass over "
                               "the whole grid", low=1)
    sparsity: float = setting(1e-5, "L1 on activated density: empty space stays empty", low=0)
    exposure: bool = setting(False, "fit a per-image affine colour correction of the photographs (exposure, white "
                                   "balance; left out for novel views)")
    exposure_lr: float = setting(1e-3, "Adam learning rate of the colour corrections", above=0)
    exposure_weight: float = setting(1e-2, "pull of the colour corrections towards the identity", low=0)
    distortion: float = setting(0.01, "weight of Mip-NeRF 360's distortion loss, ray positions in units of the "
                                      "scene box (pulls each ray's weights into one compact peak: no floaters)",
                                low=0)
    distortion_object: float = setting(5.0, "factor on the distortion loss of rays inside the object's masks: "
                                            "one peak per object ray (haze left in front of the object would stay "
                                            "in the background and go missing from the foreground)", low=0)
    free_space: bool = setting(True, "the full phase keeps empty the space the object masks prove free: outside the "
                                     "visual hull, inside a training view's mask, nearer to that camera than the "
                                     "hull on the pixel (mi_voldis.fit.free_space); false: a fit may draw the "
                                     "object on a veil in front of it, which the background keeps as its ghost")
    free_space_margin: float = setting(0.02, "with free_space, a point is free only nearer than (1 - this) times the "
                                             "hull's distance on its pixel", low=0, high=0.5)
    near_grad: float = setting(0.0, "near-camera gradient scaling (Floaters No More) in the full field's fit: a "
                                    "sample's gradients are scaled by min(1, (d / r)^2), d its distance from "
                                    "the camera, r this fraction of the rig's extent (nerfstudio's unit: 1 is "
                                    "its scaling; 0: off)", low=0)

    depth_smooth: float = setting(0.0, "weight of an edge-aware depth smoothness on tiles of the full field's "
                                       "training rays (losses.depth_smoothness_loss, depths measured in scene "
                                       "space: SceneSpace.scene_depth): a patch of floor that few views see ends "
                                       "at the depth of the floor around it, not on a sheet of fog in front of "
                                       "the one camera that sees it (after RegNeRF's depth smoothness, on the "
                                       "photos' own pixels); 0: off, the default (what 10 gains and costs on the "
                                       "removal family and the captures: reports/notes.md)", low=0)
    depth_smooth_until: float = setting(1.0, "the smoothness acts on the full phase's first steps only, this "
                                             "fraction of its planned steps (1: all of them): a sheet of fog forms "
                                             "on the coarse grids, the fine ones may then fit what the prior would "
                                             "flatten", above=0, high=1)
    depth_smooth_rays: float = setting(0.25, "rays of that smoothness per step, fraction of batch_rays, in "
                                             "depth_smooth_tile x depth_smooth_tile tiles", above=0, high=1)
    depth_smooth_tile: int = setting(4, "edge of the smoothness's pixel tiles", low=2)
    depth_smooth_edge: float = setting(10.0, "gamma of the smoothness's edge weight exp(-gamma |c_a - c_b|_1 / 3): "
                                             "across a colour edge of the photo depth may jump", low=0)

    # ---- modelling only what the scene needs
    brick: int = setting(4, "vertices along a brick's edge (the sparse storage unit: a surface is kept with a "
                            "brick's margin on either side, so smaller bricks store fewer vertices around it, which "
                            "buys a finer grid within max_memory_gib and cheaper steps)", choices=(4, 8, 16))
    carve_weight: float = setting(1e-2, "at each resolution step bricks are kept where some training ray gives a "
                                        "sample this much weight (where rays end; grown by a brick): higher keeps "
                                        "fewer bricks, so a finer grid fits in max_memory_gib, until surfaces whose "
                                        "weight spreads over many samples (foliage, grass) lose bricks and show "
                                        "holes", above=0, high=1)
    carve_weight_memory: float = setting(3e-2, "a stage whose carved grid would pass max_memory_gib tightens "
                                               "carve_weight, in steps up to this weight, to the loosest one that "
                                               "lets it reach its planned grid (or else the finest grid it can): "
                                               "only captures that memory binds (large unbounded scenes) lose "
                                               "their faintest bricks (at or below "
                                               "carve_weight: never tighten; reports/notes.md)", above=0, high=1)
    carve: bool = setting(True, "carve bricks where no training ray ends (false: keep every brick, i.e. a dense "
                                "grid, for comparison)")
    carve_rays: int = setting(1 << 20, "training rays traced to find where rays end (all pixels when fewer)", low=1)
    occupancy_at_step: int = setting(250, "empty-space skipping starts at this step (0: never)", low=0)
    occupancy_voxels: int = setting(4, "occupancy cells are this many voxels of the current grid across", low=1)
    occupancy_alpha: float = setting(1e-3, "a cell is empty when no voxel in it reaches this opacity: half "
                                           "the initial one, so only space the data carved out is skipped",
                                     above=0, high=1)
    occupancy_every: int = setting(100, "steps between occupancy updates", low=1)
    strides: str = setting("last", "in contracted space, the fit's stages cross occupied cells of thin density "
                                   "in longer steps (the voldis integrator's strides): 'last' from the planned "
                                   "last stage on (each refinement carves the field as sampled in full), 'all' "
                                   "every stage, 'none'", choices=("last", "all", "none"))
    scene_occupancy_voxels: int = setting(1, "occupancy cells of the fitted scene (the scene.xml a run writes, "
                                             "scores and every task renders) are this many voxels across: "
                                             "cells of one voxel skip the empty air between a surface's voxels "
                                             "that fitting's coarser cells evaluate", low=1)
    scene_stop_transmittance: float = setting(1e-2, "rays of the fitted scene stop once every field's "
                                                    "transmittance falls below this (fitting: 1e-4), their "
                                                    "last sample taking the light left: what lies behind "
                                                    "changes a pixel by at most that much, times its "
                                                    "difference from that sample's colour",
                                              above=0, high=0.5)
    scene_strides: bool = setting(True, "the fitted scene, in contracted space, crosses occupied cells of thin "
                                        "density in longer steps (the voldis integrator's strides)")
    empty_color_alpha: float = setting(1e-3, "background colour is reset to black where its voxel opacity is "
                                             "lower", low=0, high=1)

    # ---- background
    bg_strategy: str = setting("guided", "'lift': from the full field, hull emptied and refitted, what no view "
                                       "sees lifted from a 2D inpainting; 'clear': the same without the lifted "
                                       "prior; 'harmonic': hull inpainted harmonically, then refitted; 'guided': "
                                       "'harmonic' refitted with each view's 2D inpainting as a weak prior on its "
                                       "masked rays; 'scratch': both fields jointly",
                                 choices=("lift", "clear", "harmonic", "guided", "scratch"))
    prior_weight: float = setting(0.1, "lambda of the 2D colour prior on masked rays, against 1 for L_bg "
                                       "(bg_strategy 'guided')", low=0)
    prior_rays: float = setting(0.25, "rays of that prior per step, fraction of batch_rays", above=0, high=1)
    prior_views: int = setting(4, "reference views inpainted and lifted in turn, each where the background "
                                  "still has a hole (bg_strategy 'lift')", low=1)
    prior_inpainter: str = setting("auto", "2D inpainter of the prior's views ('guided': every masked view, "
                                           "'lift': the reference views): 'telea' or 'ns' (OpenCV), 'fsr' (OpenCV "
                                           "contrib's frequency-selective reconstruction), 'membrane' (harmonic), "
                                           "'lateral' (each row across the hole from the colours beside it: the "
                                           "bands behind an object, not what stands under it), 'auto' ('fsr' where "
                                           "OpenCV has its contrib modules, else 'telea'; metrics.json: "
                                           "bg_prior.inpainter), or several joined by '+': the mean of their fills "
                                           "('lateral+auto' raised the removal family's worst tuning scene but "
                                           "lowered the worst of the scenes added to judge it: reports/notes.md)",
                                   check=_inpainter_error)
    hull_dilation: float = setting(0.03, "mask dilation for the visual hull, fraction of image diagonal",
                                   low=0, high=1)
    hull_min_views: float = setting(0.9, "a cell is in the hull if inside the dilated mask in this fraction of "
                                         "the views that see it", above=0, high=1)
    hull_occluders: bool = setting(True, "the hull also takes in the surface points some view sees inside its mask "
                                         "that it holds once the views with an occluder in front of them abstain "
                                         "from the vote: the object's parts occluders hide from many views "
                                         "(bg_strategy 'harmonic', 'guided')")
    bg_ray_dilation: float = setting(0.15, "refit rays come from masks dilated by this fraction of the "
                                           "diagonal", low=0, high=1)
    object_alpha: float = setting(0.2, "hull voxels this opaque in the full field that no training view sees "
                                       "unmasked and some masked ray shows (transmittance >= 5%) are the "
                                       "object: emptied in bg (bg_strategy 'harmonic', 'guided')", above=0, high=1)
    object_front: bool = setting(True, "hull voxels within two voxels before the full field's median point on a "
                                       "masked ray (nothing but the object stands there) that no training view "
                                       "sees unmasked are the object too, however faint: the prior cannot paint "
                                       "the background over the object, so the foreground layer covers it whole "
                                       "(bg_strategy 'harmonic', 'guided')")
    object_behind_fill: bool = setting(True, "the object's voxels that the masked training views vote at or behind "
                                             "the surface it hides (each view's full-field depth around its mask "
                                             "filled into it as disparity; the floor it stands on), within "
                                             "object_behind_layers of its lowest, take the hull's fill instead of "
                                             "being emptied (bg_strategy 'harmonic', 'guided'): emptied, they cut "
                                             "that surface along the object's outline, a ring where it stood; the "
                                             "foreground loses the object's voxels there (reports/notes.md)")
    object_behind_layers: float = setting(2.0, "with object_behind_fill, only the object's voxels within this many "
                                               "voxels of its lowest (1st percentile height along the cameras' up): "
                                               "the floor it stands on, not its upper parts that a hazy field's "
                                               "filled depth votes behind the surface (0: all; on the removal family "
                                               "all cost the foreground's coverage on six check scenes)", low=0)
    hole_carve: bool = setting(False, "unseen hull voxels that the masked training views vote in front of the surface "
                                     "the object hides (each view's full-field depth around its mask filled into it "
                                     "as disparity), or far behind it, are emptied in bg and kept so, as the "
                                     "object's voxels are (bg_strategy 'harmonic', 'guided'): the hole is a shell "
                                     "about the hidden surface, no veil of haze before it or behind it (off by "
                                     "default: on the removal family's tuning half it did not win, reports/notes.md)")
    hole_carve_margin: float = setting(0.05, "with hole_carve, a voxel is in front when nearer than (1 - this) times "
                                             "the filled depth", low=0, high=1)
    hole_carve_behind: float = setting(0.25, "with hole_carve, unseen hull voxels farther than (1 + this) times the "
                                             "filled depth are emptied and kept so too: hidden behind the filled "
                                             "surface, they would show through it as haze while it is not opaque",
                                       above=0)
    keep_seen: bool = setting(True, "hull voxels some training view sees unmasked keep the full field's density "
                                    "in bg (their colour is refitted; only the unseen voxels, those within "
                                    "keep_seen_gap of the object's and those on no view's surface, "
                                    "seen_surface_tol, are filled and reshaped; bg_strategy "
                                    "'harmonic', 'guided'): outside the object the two fields' densities agree, "
                                    "so the foreground layer w_fg = w_full - w_bg holds the object alone; the "
                                    "object's shadow stays in the background with that geometry")
    shadow_contrast: float = setting(0.5, "the object's shadow leaves with it (bg_strategy 'guided', a dataset "
                                          "without effect masks): a light is searched from the object's shape, "
                                          "its shading and the photos (mi_voldis.fit.shadow), and its shadow "
                                          "taken as effect masks when the photos step down across the shadow's "
                                          "edge by at least this much in log luminance (0.5: 39% darker) in "
                                          "every channel, pooled and in two thirds of the views that see it; "
                                          "0: off", low=0)
    fringe_contrast: float = setting(0.1, "the object's dark fringe leaves with it (bg_strategy 'guided'): pixels "
                                          "within fringe_width of a mask darker in every channel than the 2D fill "
                                          "from beyond that band by at least this in log, and darker than every "
                                          "pixel beyond it near them (its contact shadow, its dark soft edge; not a "
                                          "dark texture, mi_voldis.fit.fringe) join the effect masks; 0: off",
                                     low=0)
    fringe_width: float = setting(0.03, "the band beside the masks searched for the dark fringe, fraction of the "
                                        "image diagonal", above=0, high=1)
    fringe_unseen: bool = setting(True, "no view sees the background through the dark fringe: the hull vertices "
                                        "seen only there (the object's soft edge, its dark outline on the floor) "
                                        "are refilled with the hole instead of kept, not only left out of L_bg; "
                                        "their density only where the fill's is higher (thinned, the surface "
                                        "would move and the foreground spill past the object; reports/notes.md)")
    hull_color_fill: bool = setting(False, "with keep_seen, the hull vertices the fill inpaints take their colour "
                                           "from outside the hull alone, not from the vertices views see in it "
                                           "(those keep their own): beside the object's silhouette these hold the "
                                           "object's tint, and a fill from them paints a ghost of it into the hole "
                                           "(off by default, reports/notes.md; bg_strategy 'harmonic', 'guided')")
    hull_fill_vertical: float = setting(0.0, "weight of the world's up (from the cameras) in the hull's fill, "
                                             "against 1 for the horizontal: 0 fills each horizontal slice of the "
                                             "hull from its own rim, so the floor under the object continues "
                                             "whole and the floor's density is not carried up into the air above "
                                             "it; 1 fills isotropically (bg_strategy 'harmonic', 'guided')",
                                        low=0, high=1)
    keep_seen_gap: int = setting(1, "with keep_seen, hull vertices within this many vertices of the object's own "
                                    "voxels are filled even where a view sees them unmasked: the object's soft "
                                    "edge, which views see beside its silhouette, leaves with it (0: none)",
                                 low=0)
    seen_surface_tol: float = setting(0.0, "with keep_seen, a hull vertex some view sees unmasked keeps the full "
                                           "field's density only if it lies on such a view's surface (the full "
                                           "field's median depth there within this fraction of its distance); "
                                           "those every view sees through (the full field's haze about the "
                                           "object, which the hull's fill would carry into the hole as a glassy "
                                           "ghost) are filled and refitted with the hole, never denser than the "
                                           "full field (in the fill too, so the unseen hull behind them is filled "
                                           "from them, not from the far surfaces at the hull's end): denser, they "
                                           "would hide what views see behind them and the foreground would take "
                                           "it (0: every seen vertex kept, the default; 0.015 measured on the "
                                           "removal family and the captures in reports/notes.md; bg_strategy "
                                           "'harmonic', 'guided')",
                                     low=0, high=1)

    # ---- bookkeeping
    seed: int = setting(0, "random seed: ray batches and jitter", low=0)
    checkpoint_every: int | None = setting(None, "steps between checkpoints (null: every checkpoint_minutes)",
                                           low=1)
    # by time, not steps: a checkpoint writes the fields and their Adam moments (half a GB at 448^3), as costly
    # at a coarse grid's fast steps as at a fine one's, and on any machine; each phase also ends with one
    checkpoint_minutes: float = setting(2.0, "minutes of fitting between checkpoints (with checkpoint_every null)",
                                        above=0)
    eval_every: int = setting(250, "steps between held-out PSNR evaluations for the PSNR-vs-time log", low=1)
    eval_views: int = setting(3, "held-out views rendered for that log", low=0)
    preview_views: int = setting(3, "held-out views written as PNG previews", low=0)

    def for_backend(self, which):
        """These settings with what is 'auto' per backend (``which``: 'llvm' or 'cuda') made explicit."""
        from .schedule import BACKENDS
        b = BACKENDS[which]
        return self.replace(**{key: getattr(b, key) for key in ("reference_msps", "host_ms", "sample_ns", "float_ns",
                                                                 "batch_rays", "max_memory_gib")
                               if getattr(self, key) == "auto"})

    def check(self):
        if self.minutes is None and self.steps_full is None:
            raise ValueError("minutes and steps_full cannot both be null: the fit needs a budget or a step count")
        if self.resolution_schedule is not None and self.steps_full is None:
            raise ValueError("an explicit resolution_schedule needs steps_full")
