"""What a field is: a map from a point of scene space to a density and a colour, stored at the vertices
of a lattice over an axis-aligned box and read by trilinear interpolation.

A field is stored in one of two ways, with the same interpolant: as a dense vertex grid
(:mod:`.grid`, every vertex, channels interleaved for one packet gather a corner) or as a sparse brick
grid (:mod:`.bricks`, only the bricks that hold something, the rest one shared empty brick). Raw
values become densities and colours through :mod:`.activations`. While a field is fitted its values
are a :class:`.state.FieldState` (made, carved, resampled, given or stripped of view dependence);
:mod:`.spec` turns arrays into the ``radiance_field`` medium plugin's dictionaries
(:mod:`mi_voldis.plugins.radiance_field`, which reads both storages), and :mod:`.dense_export`
resamples a fitted field onto a world-space grid for Mitsuba's own ``heterogeneous`` medium.
"""
