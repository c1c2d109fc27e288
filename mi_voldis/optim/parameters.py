"""The optimised parameters of fitting: fields' packed grids, stepped by Adam in place."""


class PackedParameters(dict):
    """The fields' packed grids as the optimised parameters, ``{"role.packed": Float}`` (other keys, e.g.
    the colour corrections, are held as they are).

    Adam steps on the very arrays the march reads: a step neither packs density and colour tensors
    nor unpacks their gradients (at 128^3 that is three passes over 32 MB per field and step).
    ``update()`` hands changed arrays back to the fields; ``per_slot`` lays out per-channel values
    (Adam's learning rates, regulariser weights) in the packed layout."""

    def __init__(self, fields):
        self.fields = dict(fields)
        super().__init__({f"{r}.packed": f.packed for r, f in self.fields.items()})

    def update(self):
        for key, value in self.items():
            field = self.fields.get(key[:-len(".packed")]) if key.endswith(".packed") else None
            if field is not None and value is not field.packed:
                field.set_packed(value)

    def per_slot(self, role, density, color):
        """Values for the slots of one packed vertex: ``density`` for channel 0, ``color`` for the
        colour channels, 0 for the padding."""
        f = self.fields[role]
        return [density] + [color] * (f.channels - 1) + [0.0] * (f.width - f.channels)
