"""How the background field starts from the full one: the part of the object's visual hull no training
view sees unmasked cleared (``clear``, ``lift``) or the hull inpainted from around it (``harmonic``,
``guided``), before the refit on rays near the masks; and its colour cleared where nothing reads it."""
import dataclasses

import drjit as dr
import mitsuba as mi
import numpy as np

from ..cameras import pixel_rays, world_up
from ..device import from_numpy
from ..field.bricks import EMPTY_COLOR, EMPTY_DENSITY
from ..field.state import (
    MEAN_CHANNELS,
    density_raw_for_alpha,
    dilate_vertices,
    neighbour_vertices,
    resample,
    vertex_positions,
    without_view_dependence,
)
from ..metrics import diagonal_pixels, dilate
from ..render import march
from .fields import step_voxels
from .hull import hull_behind_occluders, visual_hull
from .visibility import hidden_depth, hidden_surface_side, in_view, seen_elsewhere


def hull_region(inputs, field, neighbours, depth=None):
    """Per stored vertex of ``field``, 1 inside the object's visual hull (Float), and the hull vertices'
    scene-space positions; the hull is grown by two vertices. With ``depth`` (view -> full-field median
    depth map) and ``hull_occluders`` it also takes in the points of
    :func:`~mi_voldis.fit.hull.hull_behind_occluders`: the object's parts that occluders hide from many
    views."""
    cfg, ds = inputs.cfg, inputs.ds
    pts_scene, real = vertex_positions(field)
    inside = np.zeros(len(pts_scene), bool)
    pts_world = inputs.space.to_world_np(pts_scene[real])
    diag = np.hypot(*ds.size)
    cams, masks = [ds.cameras[v] for v in ds.masked_train], ds.masks[ds.masked_train]
    px = int(np.ceil(cfg.hull_dilation * diag))
    inside[real] = visual_hull(pts_world, cams, masks, px, cfg.hull_min_views)
    if depth is not None and cfg.hull_occluders:
        inside[real] |= hull_behind_occluders(pts_world, cams, masks, px, cfg.hull_min_views,
                                              [depth.get(v) for v in ds.masked_train])
    grown = dilate_vertices(mi.Bool(inside), neighbours, 2) & mi.Bool(real)
    return dr.select(grown, 1.0, 0.0), pts_scene[np.array(grown)]


def start_cleared(inputs, state):
    """Background = full field with the hull cells no training view sees unmasked emptied (no density,
    their colour kept: :func:`emptied`; :func:`never_seen`) and the vertices only the object can occupy
    (:func:`~mi_voldis.fit.lift.object_ray_keys`: the haze a fit leaves around it, beyond the hull):
    what any view sees stays. L_bg then refits the (grown) hull on rays near the masks. Returns the
    lattice keys of the vertices emptied on the masked rays."""
    from .lift import keys_mask, object_ray_keys, training_depths
    full = state.fields["full"]
    depth = training_depths(inputs, state)
    carved = object_ray_keys(inputs, full, [v for v in depth if v in set(inputs.ds.masked_train)], depth)
    hull, state.hull_points = hull_region(inputs, full, neighbour_vertices(full))
    region = never_seen(inputs, full, hull > 0, depth) | keys_mask(full, carved)
    state.fields["bg"] = without_view_dependence(emptied(inputs, state, full, region), region)
    return carved


SOLID_ALPHA = 0.5  # opacity per sample step of the hidden surface's vertices as the background starts


def emptied(inputs, state, field, region):
    """``field`` with the vertices of ``region`` (Bool per stored vertex) empty: the initial density of
    an unfitted field. Their colour stays: colour is interpolated before its activation, so a black
    vertex beside a surface would darken it; where a whole neighbourhood is empty the colour is cleared
    at the end of the fit (:func:`clear_empty_background_color`)."""
    return with_opacity(inputs, state, field, region, inputs.cfg.density_init_alpha)


def with_opacity(inputs, state, field, region, alpha):
    """``field`` with the density of the vertices of ``region`` (Bool per stored vertex) that of opacity
    ``alpha`` per sample step of the fit (``state``'s, :func:`~mi_voldis.fit.fields.step_voxels`), their
    colour as it was."""
    raw = density_raw_for_alpha(alpha, voxel_of(field) * step_voxels(inputs.cfg, state), field.density_scale)
    data = field.bricks_data()
    channel = dr.arange(mi.UInt32, dr.width(data)) % field.width
    values = dr.select(dr.repeat(region, field.width) & (channel == 0), raw, data)
    return field.with_bricks(values)


def never_seen(inputs, field, candidates, depth, edge=1, tol=0.05):
    """Bool per stored vertex of ``field``: among ``candidates`` (Bool per stored vertex), those no
    training view of ``depth`` (view -> full-field depth map) has in view unmasked
    (:func:`~mi_voldis.fit.visibility.in_view`: outside its mask and, with ``fringe_unseen``, the
    object's dark fringe beside it (``inputs.fringe``: those pixels show the object's soft edge), grown by
    ``edge`` pixels as a vertex is a point and a mask a set of pixel centres, and not behind something
    nearer): the strict visual hull, where an occluder in front of the object in some view does not make
    its cells count."""
    return _none_unmasked(inputs, field, candidates, depth, edge,
                          lambda points, cams, depths, masks: in_view(points, cams, depths, masks, tol=tol))


def _none_unmasked(inputs, field, candidates, depth, edge, test):
    """Bool per stored vertex of ``field``: the ``candidates`` for which ``test(world points, cameras, depth
    maps, masks)`` (Bool per point) is False over the training views of ``depth``, each view's mask its
    object's (and, with ``fringe_unseen``, the object's dark fringe) grown by ``edge`` pixels."""
    ds = inputs.ds
    pts_scene, real = vertex_positions(field)
    pick = np.flatnonzero(np.array(candidates) & real)
    views = list(depth)
    shown = ds.masks if inputs.fringe is None or not inputs.cfg.fringe_unseen else ds.masks | inputs.fringe
    hit = test(inputs.space.to_world_np(pts_scene[pick]), [ds.cameras[v] for v in views],
               [depth[v] for v in views], [dilate(shown[v], edge) for v in views])
    out = np.zeros(len(pts_scene), bool)
    out[pick[~hit]] = True
    return mi.Bool(out)


def seen_through(inputs, field, candidates, depth):
    """Bool per stored vertex of ``field``: among ``candidates`` (Bool per stored vertex; the hull vertices
    some view sees unmasked), those on no training view's surface: wherever a view of ``depth`` (view ->
    full-field median depth map) has one unmasked (outside its mask and, with ``fringe_unseen``, the
    object's dark fringe, grown by a pixel as in :func:`never_seen`), its depth there is farther or nearer
    than the vertex by more than ``seen_surface_tol`` of the distance. Every view sees through them: what
    density the full field holds there is haze, which the data never asked of the background."""
    tol = inputs.cfg.seen_surface_tol
    return _none_unmasked(inputs, field, candidates, depth, 1,
                          lambda points, cams, depths, masks: seen_elsewhere(points, cams, depths, masks, tol=tol))


def density_ceiling(values, width, region):
    """Per packed value of a field's ``values`` (``width`` channels a vertex), the most the hull's fill may give
    it: the density the field holds at the vertices of ``region`` (Bool per stored vertex; the ones views see
    through, :func:`seen_through`), unbounded elsewhere. So the fill clears the full field's haze there at
    most, as the refit does (:func:`no_denser`), and the unseen vertices behind such a veil are filled from it,
    not from denser surfaces farther out: on a one-sided rig whose hull runs out to the far shell those are
    the far surfaces at the hull's end, which a fill carried through the veil would paint into the hole."""
    i = dr.arange(mi.UInt32, dr.width(values))
    capped = dr.gather(mi.Bool, region, i // width) & (i % width == 0)
    return dr.select(capped, values, dr.inf)


def no_denser(field, reference, region):
    """``field`` with its density in ``region`` (Bool per stored vertex) at most ``reference``'s (a field on
    the same lattice), colour as it was: the background's refit of the vertices views see through
    (:func:`seen_through`) may clear the full field's haze there, never add to it. Denser than the full
    field, such a vertex would lower the transmittance to the surface behind it, the foreground (the
    sample-wise max(w_full - w_bg, 0)) would take that surface's weight there, and its coverage spill past
    the object."""
    mine, theirs = field.bricks_data(), reference.bricks_data()
    i = dr.arange(mi.UInt32, dr.width(mine))
    density = dr.gather(mi.Bool, region, i // field.width) & (i % field.width == 0)
    return field.with_bricks(dr.select(density, dr.minimum(mine, theirs), mine))


def fringe_vertices(inputs, state, hull, depths):
    """Bool per stored vertex of the full field: the hull vertices (``hull``: Float per vertex) that
    training views see unmasked only through the object's dark fringe (``inputs.fringe``), unseen once
    it counts as masked (:func:`never_seen`); ``depths``: the full field's median depth maps by view,
    read and filled (:func:`~mi_voldis.fit.lift.training_depths`)."""
    from .lift import training_depths
    full = state.fields["full"]
    depth = training_depths(inputs, state, median=True, memo=depths)
    loose = dataclasses.replace(inputs, cfg=inputs.cfg.replace(fringe_unseen=True))
    return (never_seen(loose, full, hull > 0, depth)
            & ~never_seen(dataclasses.replace(inputs, fringe=None), full, hull > 0, depth))


def denser(kept, filled, width, region):
    """Packed values ``filled`` with the density (channel 0) in ``region`` (Bool per vertex) the larger of
    ``kept``'s and ``filled``'s, and their colour ``filled``'s.

    For the vertices seen only through the object's fringe (:func:`fringe_vertices`). Where the fill is
    denser, the surface there was the object's thinned edge or its dark outline on the floor, and the
    fill mends it. Where the fill is thinner it would move the surface the full field holds there by a
    vertex, and the foreground, the sample-wise max(w_full - w_bg, 0), would then show the moved part as
    object beside it (on the removal family: coverage spilling a pixel past the object)."""
    index = dr.arange(mi.UInt32, dr.width(region)) * width
    old, new = dr.gather(mi.Float, kept, index), dr.gather(mi.Float, filled, index)
    out = dr.copy(filled)
    dr.scatter(out, dr.select(region, dr.maximum(old, new), new), index)
    return out


def allocate_hidden_surface(inputs, state, depth, stride=2):
    """The full field with bricks allocated (empty) where the hidden surface's shell lies
    (:func:`hole_shell`): along the rays of every ``stride``-th masked pixel of the masked views of
    ``depth`` (view -> full-field median depth map), from the filled depth d to (1 + ``hole_carve_behind``)
    d. The fit allocated bricks where training rays end; behind an object no ray ends, so without them
    the background could hold no surface there and the hole would stay transparent. Empty bricks leave
    the full field's renders as they were."""
    from .lift import lattice_cells
    ds, cfg, full = inputs.ds, inputs.cfg, state.fields["full"]
    grow = diagonal_pixels(0.01, ds.size)
    points = []
    for v in [v for v in depth if v in set(int(u) for u in ds.masked_train)]:
        hole = dilate(ds.masks[v], grow)
        filled = hidden_depth(ds.cameras[v], depth[v], ds.masks[v], hole)
        if filled is None:
            continue
        py, px = np.nonzero(hole)
        py, px = py[::stride], px[::stride]
        o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
        for f in np.linspace(1.0, 1.0 + cfg.hole_carve_behind, 4):
            points.append(o + f * filled[py, px, None] * d)
    if not points:
        return full
    ijk, ok = lattice_cells(full, inputs.space, np.concatenate(points), 1)
    ijk = ijk[ok].reshape(-1, 3)
    s = full.layout.shift
    need = np.zeros(full.layout.table.shape, bool)
    need[ijk[:, 2] >> s, ijk[:, 1] >> s, ijk[:, 0] >> s] = True
    if not (need & (full.layout.table == 0)).any():
        return full
    return resample(full, None, need | (full.layout.table > 0))


def hull_bricks(inputs, layout, to_world):
    """The bricks (bz, by, bx Bools) of ``layout`` (a brick lattice over the box ``to_world`` maps the unit
    cube to) a corner of which lies in the visual hull of the masked training views (masks dilated by
    ``hull_dilation``, as :func:`hull_region`'s)."""
    cfg, ds = inputs.cfg, inputs.ds
    b = layout.brick
    span = np.array(layout.shape) - 1  # (X, Y, Z) vertices - 1
    nz, ny, nx = layout.table.shape
    # the corners of the bricks: vertex c * b along each axis, the last one clipped to the lattice
    axes = [np.minimum(np.arange(n + 1) * b, span[a]) / span[a] for a, n in enumerate((nx, ny, nz))]
    k, j, i = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    local = np.stack([i.ravel(), j.ravel(), k.ravel()], -1)
    scene = local @ to_world[:3, :3].T + to_world[:3, 3]
    px = int(np.ceil(cfg.hull_dilation * np.hypot(*ds.size)))
    corner = visual_hull(inputs.space.to_world_np(scene), [ds.cameras[v] for v in ds.masked_train],
                         ds.masks[ds.masked_train], px, cfg.hull_min_views).reshape(nz + 1, ny + 1, nx + 1)
    need = np.zeros(layout.table.shape, bool)
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                need |= corner[dz:dz + nz, dy:dy + ny, dx:dx + nx]
    return need


def allocate_hull(inputs, field):
    """``field`` with empty bricks allocated wherever the object's visual hull reaches (:func:`hull_bricks`).
    The fit stores bricks where training rays end, with a brick's margin about them
    (:func:`~mi_voldis.field.state.carve`); inside the object no ray ends, so what it hides (the floor under
    it, a wall behind it) is stored only where that margin reaches, which smaller bricks make thinner. The
    background can change only stored vertices: elsewhere in the hole it would render what lies beyond, or
    nothing. Empty bricks leave the field's renders as they were (to the rounding of the resampled values)."""
    need = hull_bricks(inputs, field.layout, field.to_world)
    if not (need & (field.layout.table == 0)).any():
        return field
    return resample(field, None, need | (field.layout.table > 0))


def start_harmonic(inputs, state, depths=None):
    """Background = full field with the object's visual hull, stored in full (:func:`allocate_hull`), inpainted from
    around it: a harmonic extension of density
    and colour, along the horizontal by default (:func:`fill_weights`), so surfaces the object hides (the floor
    under it) continue through the hull, except in the object's own voxels (:func:`background_regions`), whose
    density is emptied so that w_fg = w_full - w_bg keeps the whole object; then L_bg refits what some view
    sees. With ``keep_seen`` only the hull voxels no training view sees unmasked, or within ``keep_seen_gap``
    vertices of the object's, are inpainted; the others keep the full field's values (the fill's boundary; with
    ``hull_color_fill`` the density's alone, the colour filled from outside the hull: :func:`hull_fill`).
    Returns the hull, the object's voxels, those inpainted hull voxels and among them the seen ones every
    view sees through (:func:`background_regions`), which the fill leaves no denser than the full field
    (:func:`density_ceiling`).
    ``depths``: the full field's median depth maps by view, read and filled
    (:func:`~mi_voldis.fit.lift.training_depths`)."""
    state.fields["full"] = allocate_hull(inputs, state.fields["full"])  # room for what the object hides
    if inputs.cfg.hole_carve:  # room for the hidden surface where no training ray ended
        from .lift import training_depths
        state.fields["full"] = allocate_hidden_surface(inputs, state, training_depths(inputs, state, median=True))
        if depths is not None:  # the depths of the field as it was
            depths.clear()
    full = state.fields["full"]
    neighbours = neighbour_vertices(full)
    depths = {} if depths is None else depths  # rendered once for the regions and the fringe's vertices
    hull, points, obj, refill, solid, through = background_regions(inputs, state, neighbours, with_solid=True,
                                                                   depths=depths, with_through=True)
    region = dr.select(refill, hull, 0.0) if inputs.cfg.keep_seen else hull
    weights = fill_weights(inputs, full, points)
    data = full.bricks_data()
    ceiling = density_ceiling(data, full.width, through) if dr.count(through)[0] > 0 else None
    values = (hull_fill(data, full.width, region, hull, neighbours, weights, ceiling) if inputs.cfg.hull_color_fill
              else harmonic_fill(data, full.width, region, neighbours, weights=weights, ceiling=ceiling))
    if inputs.fringe is not None and inputs.cfg.fringe_unseen:  # what views see only through the fringe
        values = denser(data, values, full.width, fringe_vertices(inputs, state, hull, depths) & ~obj)
    # the object itself: empty, its colour the fill's (:func:`emptied`)
    filled = full.with_bricks(values)
    # the inpainted hole's colour is the mean: the 2D prior that paints it disagrees between views, and view
    # dependence fitted to that would show each view its own inpainting (refit_elements keeps it 0); what
    # some view sees keeps the full field's gloss with its density and colour
    state.fields["bg"] = without_view_dependence(emptied(inputs, state, filled, obj), region)
    if solid is not None:  # the hidden surface: opaque from the filled depth on (hole_shell)
        state.fields["bg"] = with_opacity(inputs, state, state.fields["bg"], solid & ~obj, SOLID_ALPHA)
    state.hull_points = points
    return hull, obj, refill, through


def voxel_of(field):
    return float(np.max(np.diag(field.to_world)[:3] / (np.array(field.shape) - 1)))


def background_regions(inputs, state, neighbours=None, with_solid=False, depths=None, with_through=False):
    """The visual hull (Float per stored vertex), its vertices' positions, the object's own voxels
    (Bool) and the hull vertices no training view sees unmasked (Bool, :func:`never_seen`) with those
    within ``keep_seen_gap`` vertices of the object's voxels: the object's soft edge, which views see
    unmasked beside its silhouette, goes with it (``keep_seen`` refills only these). The
    object's voxels are unseen hull vertices that either hold
    the object's density where a masked ray can show it (full-field opacity per voxel above
    ``object_alpha``, transmittance on some masked ray at least 5%) or, with ``object_front``, lie just
    in front of it on a masked ray (:func:`masked_ray_cells`). The walls and floor around the object
    that some view sees are no part of it, however opaque, so a low ``object_alpha`` can take in the
    object's soft edge without carving the surfaces beside it; nor is the density hidden behind it,
    where the refit continues the background; with ``object_behind_fill`` nor are the lowest of them that
    the masked views vote at or behind the surface it hides (:func:`behind_hidden_surface`: the floor it
    stands on stays whole). With ``hole_carve`` the object's voxels also take in the
    unseen hull vertices in front of the surface the object hides or far behind it (:func:`hole_shell`),
    however faint; ``with_solid``: also (5th) the unseen vertices from that surface on, which the
    background starts opaque (None without ``hole_carve``). With ``keep_seen`` and ``seen_surface_tol``, the
    refilled vertices take in the seen ones that every view sees through (:func:`seen_through`);
    ``with_through``: also (last) those (Bool), which the refit leaves no denser than the full field
    (:func:`no_denser`). ``depths``: see :func:`start_harmonic`."""
    from .lift import training_depths
    cfg, full = inputs.cfg, state.fields["full"]
    neighbours = neighbours or neighbour_vertices(full)
    depth = training_depths(inputs, state, median=True, memo=depths)
    hull, points = hull_region(inputs, full, neighbours, depth)
    raw = dr.gather(mi.Float, full.data, dr.arange(mi.UInt32, full.vertices) * full.width)
    shown, front = masked_ray_cells(inputs, state, list(inputs.ds.masked_train))
    candidates = (raw > density_raw_for_alpha(cfg.object_alpha, voxel_of(full), full.density_scale)) & shown
    if cfg.object_front:
        candidates |= front
    unseen = never_seen(inputs, full, hull > 0, depth)
    obj, refill = unseen & candidates, unseen
    through = dr.zeros(mi.Bool, full.vertices)
    if cfg.keep_seen:  # the object's soft edge is refilled too, and the haze views see through
        refill = unseen | (dilate_vertices(obj, neighbours, cfg.keep_seen_gap) & (hull > 0))
        if cfg.seen_surface_tol > 0:
            through = seen_through(inputs, full, (hull > 0) & ~refill, depth)
            refill |= through
    if cfg.object_behind_fill:  # the surface the object stands on stays whole under its outline
        obj &= ~behind_hidden_surface(inputs, full, obj, depth, cfg.object_behind_layers)
    solid = None
    if cfg.hole_carve:  # unseen space before the hidden surface (the object's or empty) and far behind it
        carve, solid = hole_shell(inputs, full, unseen, depth)
        obj |= unseen & carve
    out = (hull, points, obj, refill) + ((solid,) if with_solid else ())
    return out + (through,) if with_through else out


def behind_hidden_surface(inputs, field, candidates, depth, layers=0.0):
    """Bool per stored vertex of ``field``: among ``candidates`` (Bool per stored vertex), those the masked
    training views of ``depth`` (view -> full-field median depth map) vote at or behind the surface the
    object hides (:func:`~mi_voldis.fit.visibility.hidden_surface_side`, masks grown by 1% of the diagonal
    as :func:`hole_shell`'s); with ``layers`` > 0 only those within that many voxels of the candidates'
    lowest height (their 1st percentile along the cameras' up, :func:`~mi_voldis.cameras.world_up`). Where the
    object stands on a floor its base and the floor share cells: the floor's vertices under its outline hold
    both, no view sees them unmasked, and emptied with the object they leave a gap in the floor along the
    outline (a ring in the hole, the floor's underside or nothing showing through). Left to the fill, the
    floor continues whole; the foreground, w_full - w_bg, loses the object's density in those cells. Higher
    up the vote can be wrong: over a hazy full field the depth filled into a mask comes too near, and the
    object's upper parts would go to the background with the floor."""
    ds = inputs.ds
    pts_scene, real = vertex_positions(field)
    pick = np.flatnonzero(np.array(candidates) & real)
    views = [v for v in depth if v in set(int(u) for u in ds.masked_train)]
    world = inputs.space.to_world_np(pts_scene[pick])
    _, _, beyond = hidden_surface_side(world, [ds.cameras[v] for v in views], [depth[v] for v in views],
                                       [ds.masks[v] for v in views], diagonal_pixels(0.01, ds.size),
                                       inputs.cfg.hole_carve_margin, 0.0)
    if layers > 0 and len(pick):
        height = world @ world_up([ds.cameras[i] for i in ds.train])
        # a voxel in world units: the space's scale at its centre (the unit ball, where a contraction is linear)
        scale = float(np.linalg.norm(np.diff(inputs.space.to_world_np(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])),
                                             axis=0)))
        beyond &= height < np.percentile(height, 1) + layers * voxel_of(field) * scale
    out = np.zeros(len(pts_scene), bool)
    out[pick[beyond]] = True
    return mi.Bool(out)


def hole_shell(inputs, field, candidates, depth):
    """Two Bools per stored vertex of ``field``, among ``candidates`` (Bool per stored vertex): those the
    masked training views of ``depth`` (view -> full-field median depth map) vote in front of the surface
    the object hides or far behind it (:func:`~mi_voldis.fit.visibility.hidden_surface_side`; masks
    grown by 1% of the diagonal as the colour prior's, margins ``hole_carve_margin`` and
    ``hole_carve_behind``), to be emptied; and those behind it but not far, the back of the shell left
    about that surface, to be made opaque. The harmonic fill spreads the density around the hull through
    all of it, a veil the colour prior then paints: on a forward-facing rig, whose hull reaches far
    behind the object, a column of haze where the object stood. Emptied before and behind and opaque
    from the filled depth on, the hole shows a surface there, which the prior paints."""
    ds, cfg = inputs.ds, inputs.cfg
    pts_scene, real = vertex_positions(field)
    pick = np.flatnonzero(np.array(candidates) & real)
    views = [v for v in depth if v in set(int(u) for u in ds.masked_train)]
    grow = diagonal_pixels(0.01, ds.size)
    front, far, beyond = hidden_surface_side(inputs.space.to_world_np(pts_scene[pick]), [ds.cameras[v] for v in views],
                                             [depth[v] for v in views], [ds.masks[v] for v in views], grow,
                                             cfg.hole_carve_margin, cfg.hole_carve_behind)
    carve, solid = np.zeros(len(pts_scene), bool), np.zeros(len(pts_scene), bool)
    carve[pick[front | far]] = True
    solid[pick[beyond & ~far]] = True
    return mi.Bool(carve), mi.Bool(solid)


def masked_ray_cells(inputs, state, views, reach=2.0, erode=1, visible=0.05, chunk=1 << 16):
    """Two Bools per stored vertex of the full field, from the masked rays of ``views`` (masks eroded
    by ``erode`` pixels: edge rays graze past the object): the corners of the cells they sample while
    their transmittance is at least ``visible``, and of those they sample within ``reach`` voxels
    before their median point (where the transmittance falls below a half), that sample included.

    The first is what of the object a view can show: behind an opaque object no fit constrains the
    density, and the haze it leaves there (all the way to the far bound on a forward-facing capture)
    is no part of the object but the free place where the background continues. The second is the
    space just before the object's surface: on a masked ray nothing but the object stands in front of
    the background, so a background drawn there would be its colour at its place and cover it in
    w_fg = w_full - w_bg; the band stays thin so that a mask wider than the object (its median point
    far behind) marks nothing but the space just before that far surface."""
    from ..render.surface import median_points
    from .fields import fit_integrator
    ds, full = inputs.ds, state.fields["full"]
    integrator = fit_integrator(inputs, state)
    plan = integrator.plan(("full",))
    chain = plan.sources.full
    shown, front = dr.zeros(mi.Float, full.vertices), dr.zeros(mi.Float, full.vertices)
    m = full.to_world
    origin = mi.Point3f(*(float(x) for x in m[:3, 3]))
    scale = mi.Vector3f(*(float(x) for x in (np.array(full.shape) - 1) / np.diag(m)[:3]))
    top = [int(n) - 2 for n in full.shape]  # a cell's lower corner: its upper one stays in the lattice
    band = reach * voxel_of(full)

    with dr.suspend_grad():
        for v in views:
            py, px = np.nonzero(ds.masks[v] & ~dilate(~ds.masks[v], erode))
            o, d = pixel_rays(ds.cameras[v], px + 0.5, py + 0.5)
            ends, hit = median_points(integrator, o, d, chunk)
            ends = np.where(hit[:, None], inputs.space.from_world_np(ends), np.inf)  # scene space; none: no band
            for s in range(0, len(o), chunk):
                n = min(chunk, len(o) - s)
                end = from_numpy(mi.Point3f, ends[s:s + n])

                def mark(p, w, active, depth):
                    before = dr.exp(-depth[chain])  # transmittance up to the sample
                    lit = active & (before >= visible)
                    near = active & (before >= 0.5) & (dr.norm(end - p) <= band)
                    lower = [mi.UInt32(dr.clip(mi.Int32(dr.floor(c)), 0, t)) for c, t in zip((p - origin) * scale, top)]
                    for a in range(8):
                        i, j, k = (c + ((a >> axis) & 1) for axis, c in enumerate(lower))
                        dr.scatter(shown, 1.0, full.layout.address(i, j, k, lit), lit)
                        dr.scatter(front, 1.0, full.layout.address(i, j, k, near), near)

                rays = march.prepare_rays(plan, from_numpy(mi.Point3f, o[s:s + n]), from_numpy(mi.Vector3f, d[s:s + n]))
                march.forward(plan, rays, dr.full(mi.Float, 0.5, n), probe=mark)
    return shown > 0, front > 0


def background_ray_pool(ds, bank, dilation, effects=None):
    """Flat indices (into ``bank``) of unmasked pixels within the masks dilated by ``dilation``; with
    ``effects`` (the dataset's effect masks), those pixels count as masked: the photos show the object's
    shadow there, not the background. Pixels the dataset marks to ignore are left out."""
    diag = np.hypot(*ds.size)
    masks = bank.masks_np if effects is None else bank.masks_np | effects[bank.views]
    near = dilate(masks, int(np.ceil(dilation * diag))) & ~masks
    if bank.ignore_np is not None:
        near &= ~bank.ignore_np
    return np.flatnonzero(near.reshape(-1)).astype(np.uint32)


def effect_cells(inputs, state):
    """Bool per stored vertex of the full field: the cells the rays of the effect masks (the object's
    shadow, :attr:`~mi_voldis.data.types.Dataset.effects`) sample until their surface (transmittance
    above 5%, :func:`masked_ray_cells`, the effect masks not eroded: the dark fringe beside a mask is a pixel
    or two wide): the surfaces whose colour the photos show changed by the object. Their geometry stays the
    full field's, which every view sees."""
    ds = inputs.ds
    views = [v for v in ds.masked_train if ds.effects[v].any()]
    if not views:
        return dr.zeros(mi.Bool, state.fields["full"].vertices)
    shadow = dataclasses.replace(inputs, ds=dataclasses.replace(ds, masks=ds.effects))
    return masked_ray_cells(shadow, state, views, erode=0)[0]


def clear_empty_background_color(inputs, state, region=None):
    """Set background colour to black (from every view: no view-dependent term) at vertices that no visible
    background sample reads: those whose voxel opacity is below ``empty_color_alpha`` and whose neighbours
    (which share trilinear cells with them) are all below it too; inside ``region`` (Bool per stored vertex: the cleared
    hull) their density is emptied as well, so that the faint black left there does not add up to a
    smudge along the rays that cross it. Returns the fraction of stored vertices cleared."""
    bg = state.fields["bg"]
    threshold = density_raw_for_alpha(inputs.cfg.empty_color_alpha, voxel_of(bg), bg.density_scale)
    raw = dr.gather(mi.Float, bg.data, dr.arange(mi.UInt32, bg.vertices) * bg.width)
    empty = ~dilate_vertices(raw >= threshold, neighbour_vertices(bg))
    data = bg.bricks_data()
    channel = dr.arange(mi.UInt32, dr.width(data)) % bg.width
    vertex_empty = dr.repeat(empty, bg.width)
    values = dr.select(vertex_empty & (channel > 0) & (channel < MEAN_CHANNELS), EMPTY_COLOR, data)
    values = dr.select(vertex_empty & (channel >= MEAN_CHANNELS), 0.0, values)
    if region is not None:
        values = dr.select(vertex_empty & dr.repeat(region, bg.width) & (channel == 0), EMPTY_DENSITY, values)
    state.fields["bg"] = bg.with_bricks(values)
    return float(dr.mean(mi.Float(empty))[0])


def fill_weights(inputs, field, points):
    """The six neighbour weights (-x, +x, -y, +y, -z, +z) of the hull's fill: the diagonal of the
    conductivity K = I - (1 - v) u u^T in ``field``'s vertex units, u the world's up there
    (:func:`~mi_voldis.cameras.world_up`, carried through the scene space at the hull's centre: the
    median of ``points`` in world space, over a step small against its distance from the origin, so
    that the carrying stays local where the hull runs out to a contracted space's far shell, as an
    object's unseen hull does behind it on a one-sided rig) and v = ``hull_fill_vertical``. At v = 1
    the fill is the isotropic Laplace equation; towards 0 it runs along the horizontal alone, so each
    slice of the hull is filled from its own rim: a floor crossing the hull continues under the object,
    and the air above it stays air instead of taking a share of the floor's density (a translucent body
    of the hull's shape)."""
    v = inputs.cfg.hull_fill_vertical
    if v == 1.0 or len(points) == 0:
        return None
    ds = inputs.ds
    up = world_up([ds.cameras[i] for i in ds.train])
    world = inputs.space.to_world_np(points)
    centre = np.median(world, axis=0)
    step = 1e-4 * (1.0 + float(np.abs(centre).max()))  # locally linear there, and far above float64's rounding
    ends = inputs.space.from_world_np(np.stack([centre, centre + step * up]))
    local = np.linalg.solve(field.to_world[:3, :3], ends[1] - ends[0]) * (np.array(field.shape) - 1)
    u = local / np.linalg.norm(local)
    return [float(1.0 - (1.0 - v) * u[axis] ** 2) for axis in range(3) for _ in range(2)]


def hull_fill(values, width, region, hull, neighbours, weights=None, ceiling=None):
    """Packed ``values`` with those of ``region`` (Float per stored vertex, 1 = fill) replaced by their
    harmonic fill (:func:`harmonic_fill`): the density's from every value around ``region``; the colour's
    (the other channels) from the colour around ``hull`` (Float per stored vertex, ``region`` inside it)
    alone, the vertices of the hull outside ``region`` keeping their own. Those are the cells views see
    unmasked: beside the object's silhouette they hold its colour (its soft edge, mask edges that mix it
    in), and a fill from them would paint the object's tint and outline into the hole, a ghost the
    refit's 2D prior does not undo. ``ceiling``: as :func:`harmonic_fill`'s."""
    density = harmonic_fill(values, width, region, neighbours, channels=(0, 1), weights=weights, ceiling=ceiling)
    colour = harmonic_fill(values, width, hull, neighbours, channels=(1, width), weights=weights)
    channel = dr.arange(mi.UInt32, dr.width(values)) % width
    return dr.select(dr.repeat(region > 0, width) & (channel > 0), colour, density)


def harmonic_fill(values, width, region, neighbours, iterations=300, channels=None, weights=None, ceiling=None):
    """Packed ``values`` inside ``region`` (Float per stored vertex, 1 = fill) replaced by the harmonic
    extension of the values around them (Jacobi iterations of the 6-neighbour Laplace equation, every
    channel), a smooth volumetric inpainting: surfaces crossing the region continue through it. Only
    the region's values are iterated (compactly); the rest stay as they are. ``channels``: (first,
    end) of the channels to fill (default all); ``weights``: one per neighbour direction (default
    equal), the diagonal of an anisotropic conductivity: div(K grad f) = 0, each Jacobi step the
    weighted mean sum_d k_d f_d / sum_d k_d. ``ceiling`` (packed, as ``values``): the fill at most it, the
    discrete obstacle problem (u harmonic where u < ceiling, u <= ceiling everywhere), solved by projected
    Jacobi: each step's mean clipped to the ceiling, a monotone iteration (the weights are positive), so it
    tends to that problem's solution as the plain one tends to the harmonic fill."""
    n = dr.width(values)
    i = dr.arange(mi.UInt32, n)
    inside = dr.gather(mi.Float, region, i // width) > 0
    if channels is not None:
        inside &= (i % width >= channels[0]) & (i % width < channels[1])
    fill = dr.compress(inside)  # packed indices to fill
    m = dr.width(fill)
    if m == 0:  # nothing to fill (a hull too thin for any vertex of the grid)
        return dr.copy(values)
    compact = dr.full(mi.UInt32, m, n)  # packed index -> its place in the fill set (m: not in it)
    dr.scatter(compact, dr.arange(mi.UInt32, m), fill)
    vertex, channel = fill // width, fill % width
    dirs = []
    for nb in neighbours:
        j = dr.gather(mi.UInt32, nb, vertex) * width + channel
        k = dr.gather(mi.UInt32, compact, j)
        dirs.append((k < m, k, dr.gather(mi.Float, values, j)))  # (free?, place, fixed value)
    top = None if ceiling is None else dr.gather(mi.Float, ceiling, fill)
    inner = dr.zeros(mi.Float, m) if top is None else dr.minimum(0.0, top)
    dr.eval(dirs, inner, top)
    weights = [1.0] * 6 if weights is None else weights
    total = sum(weights)
    for _ in range(iterations):
        inner = sum(w * dr.select(free, dr.gather(mi.Float, inner, k, free), fixed)
                    for w, (free, k, fixed) in zip(weights, dirs) if w > 0) / total
        if top is not None:
            inner = dr.minimum(inner, top)
        dr.eval(inner)
    out = dr.copy(values)  # the caller's values stay unchanged
    dr.scatter(out, inner, fill)
    return out
