"""The background of the ``refit`` strategy: the object's visual hull inpainted from around it,
refitted on rays near the masks, and its colour cleared where nothing reads it."""
import drjit as dr
import mitsuba as mi
import numpy as np

from ..field_state import EMPTY_COLOR, FieldState, density_raw_for_alpha, vertex_positions
from ..grid import dilate_cells, neighbour_indices
from ..metrics import dilate
from .fields import cell_size
from .hull import visual_hull


def hull_region(inputs, field):
    """Per-vertex hull indicator (Float, 1 inside) of ``field``'s grid and the hull vertices'
    scene-space positions; the hull is grown by one voxel."""
    cfg, ds = inputs.cfg, inputs.ds
    pts_scene = np.array(vertex_positions(field)).T
    pts_world = inputs.space.to_world_np(pts_scene)
    diag = np.hypot(*ds.size)
    inside = visual_hull(pts_world, [ds.cameras[v] for v in ds.train], ds.masks[ds.train],
                         int(np.ceil(cfg.hull_dilation * diag)), cfg.hull_min_views)
    sx, sy, sz = field.shape
    grown = dilate_cells(inside.reshape(sz, sy, sx))
    return mi.Float(grown.ravel().astype(np.float32)), pts_scene[grown.ravel()]


def start_background(inputs, state):
    """Background = full field with the object's visual hull inpainted from around it: a harmonic
    extension of density and colour, so surfaces the object hides (the floor under it) continue
    through the hull, except in the object's own dense voxels (full-field opacity per voxel above
    ``object_alpha``), which are emptied so that w_fg = w_full - w_bg keeps the whole object; then
    L_bg refits what some view sees."""
    full = state.fields["full"]
    hull, points, obj = background_regions(inputs, state)
    voxel = cell_size(state.lo, state.hi, max(full.shape))
    empty = density_raw_for_alpha(inputs.cfg.density_init_alpha, voxel * inputs.cfg.step_voxels, full.density_scale)
    density = harmonic_fill(full.density, hull)
    density = mi.TensorXf(dr.select(obj, empty, density.array), full.density.shape)
    color = harmonic_fill(full.color, hull)  # black in the object itself: there c_fg = c_full
    color = mi.TensorXf(dr.select(dr.repeat(obj, full.color.shape[3]), EMPTY_COLOR, color.array), full.color.shape)
    state.fields["bg"] = FieldState(density, color, full.to_world.copy(), full.density_scale)
    state.hull_points = points


def background_regions(inputs, state):
    """The visual hull (Float per vertex), its vertices' positions, and the object's own voxels
    (Bool: hull vertices whose full-field opacity per voxel exceeds ``object_alpha``)."""
    full = state.fields["full"]
    hull, points = hull_region(inputs, full)
    voxel = cell_size(state.lo, state.hi, max(full.shape))
    dense = full.density.array > density_raw_for_alpha(inputs.cfg.object_alpha, voxel, full.density_scale)
    return hull, points, (hull > 0) & dense


def background_ray_pool(ds, bank, dilation):
    """Flat indices (into ``bank``) of unmasked pixels within the masks dilated by ``dilation``."""
    diag = np.hypot(*ds.size)
    near = dilate(bank.masks_np, int(np.ceil(dilation * diag))) & ~bank.masks_np
    return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


def clear_empty_background_color(inputs, state):
    """Set background colour to black at vertices that no visible background sample reads: those
    whose voxel opacity is below ``empty_color_alpha`` and whose neighbours (which share trilinear
    cells with them) are all below it too."""
    bg = state.fields["bg"]
    step = cell_size(state.lo, state.hi, max(bg.shape))
    threshold = density_raw_for_alpha(inputs.cfg.empty_color_alpha, step, bg.density_scale)
    occupied = np.array(bg.density)[..., 0] >= threshold
    empty = mi.Bool(~dilate_cells(occupied).ravel())
    c = bg.color.shape[3]
    color = dr.select(dr.repeat(empty, c), EMPTY_COLOR, bg.color.array)
    state.fields["bg"] = FieldState(bg.density, mi.TensorXf(color, bg.color.shape), bg.to_world, bg.density_scale)
    return float(dr.mean(mi.Float(empty))[0])


def harmonic_fill(tensor, region, iterations=300):
    """Values of ``tensor`` inside ``region`` (Float per vertex, 1 = fill) replaced by the harmonic
    extension of the values around it (Jacobi iterations of the 6-neighbour Laplace equation, every
    channel), a smooth volumetric inpainting: surfaces crossing the region continue through it."""
    c = tensor.shape[3]
    v = dr.arange(mi.UInt32, dr.width(tensor.array)) // c
    fill = dr.gather(mi.Float, region, v) > 0
    values = dr.select(fill, 0.0, tensor.array)
    neighbours = neighbour_indices(tensor.shape)
    dr.eval(neighbours, values)
    for _ in range(iterations):
        mean = sum(dr.gather(mi.Float, values, j) for j in neighbours) * (1.0 / 6.0)
        values = dr.select(fill, mean, values)
        dr.eval(values)
    return mi.TensorXf(values, tensor.shape)
