"""The background of the ``refit`` strategy: the object's visual hull inpainted from around it,
refitted on rays near the masks, and its colour cleared where nothing reads it."""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..grid import dilate_cells
from ..metrics import dilate
from . import grids
from .hull import visual_hull


def hull_region(ctx, state):
    """Per-vertex hull indicator (Float, 1 inside) of ``state``'s grid and the hull vertices'
    scene-space positions; the hull is grown by one voxel."""
    cfg = ctx.cfg
    pts_scene = np.array(grids.vertex_positions(state)).T
    pts_world = ctx.space.to_world_np(pts_scene)
    diag = np.hypot(*ctx.ds.size)
    train = ctx.ds.train
    inside = visual_hull(pts_world, [ctx.ds.cameras[v] for v in train], ctx.ds.masks[train],
                         int(np.ceil(cfg.hull_dilation * diag)), cfg.hull_min_views)
    sx, sy, sz = state.shape
    grown = dilate_cells(inside.reshape(sz, sy, sx))
    return mi.Float(grown.ravel().astype(np.float32)), pts_scene[grown.ravel()]


def start_background(ctx):
    """Background = full field with the object's visual hull inpainted from around it: a harmonic
    extension of density and colour, so surfaces the object hides (the floor under it) continue
    through the hull, except in the object's own dense voxels (full-field opacity per voxel above
    ``object_alpha``), which are emptied so that w_fg = w_full - w_bg keeps the whole object; then
    L_bg refits what some view sees."""
    full = ctx.states["full"]
    hull, points, obj = background_regions(ctx)
    voxel = ctx.cell(max(full.shape))
    empty = grids.density_raw_for_alpha(ctx.cfg.density_init_alpha, voxel * ctx.cfg.step_voxels, full.density_scale)
    density = grids.harmonic_fill(full.density, hull)
    density = mi.TensorXf(dr.select(obj, empty, density.array), full.density.shape)
    color = grids.harmonic_fill(full.color, hull)  # black in the object itself: there c_fg = c_full
    color = mi.TensorXf(dr.select(dr.repeat(obj, full.color.shape[3]), grids.EMPTY_COLOR, color.array),
                        full.color.shape)
    ctx.states["bg"] = grids.FieldState(density, color, full.to_world.copy(), full.density_scale)
    ctx.hull_points = points


def background_regions(ctx):
    """The visual hull (Float per vertex), its vertices' positions, and the object's own voxels
    (Bool: hull vertices whose full-field opacity per voxel exceeds ``object_alpha``)."""
    full = ctx.states["full"]
    hull, points = hull_region(ctx, full)
    voxel = ctx.cell(max(full.shape))
    dense = full.density.array > grids.density_raw_for_alpha(ctx.cfg.object_alpha, voxel, full.density_scale)
    return hull, points, (hull > 0) & dense


def background_ray_pool(ds, bank, dilation):
    """Flat indices (into ``bank``) of unmasked pixels within the masks dilated by ``dilation``."""
    diag = np.hypot(*ds.size)
    near = dilate(bank.masks_np, int(np.ceil(dilation * diag))) & ~bank.masks_np
    return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


def clear_empty_background_color(ctx):
    """Set background colour to black at vertices that no visible background sample reads: those
    whose voxel opacity is below ``empty_color_alpha`` and whose neighbours (which share trilinear
    cells with them) are all below it too."""
    bg = ctx.states["bg"]
    step = ctx.cell(max(bg.shape))
    threshold = grids.density_raw_for_alpha(ctx.cfg.empty_color_alpha, step, bg.density_scale)
    occupied = np.array(bg.density)[..., 0] >= threshold
    empty = mi.Bool(~dilate_cells(occupied).ravel())
    c = bg.color.shape[3]
    color = dr.select(dr.repeat(empty, c), grids.EMPTY_COLOR, bg.color.array)
    ctx.states["bg"] = grids.FieldState(bg.density, mi.TensorXf(color, bg.color.shape), bg.to_world, bg.density_scale)
    return float(dr.mean(mi.Float(empty))[0])
