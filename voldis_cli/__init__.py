"""Command-line programs of mi-voldis (``scripts/*.py`` in a checkout, ``voldis-*`` commands when
installed). Each module parses its arguments before importing :mod:`mi_voldis`, so that ``--variant``
chooses the Mitsuba variant before the package selects one."""
